// Mesh readers: the three volume formats agree on a committed mesh, and bad input gets an
// InputError that names the file, the line and the field.

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "handshare/fem/error.hpp"
#include "handshare/fem/mesh_io.hpp"
#include "handshare/fem/surface_import.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

const std::filesystem::path kData = HANDSHARE_FEM_TEST_DATA;

// Runs fn, expects an InputError whose message contains every one of `parts`.
void ExpectInputError(const std::function<void()>& fn, const std::vector<std::string>& parts,
                      std::size_t line = 0) {
  try {
    fn();
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const auto& p : parts) {
      EXPECT_NE(msg.find(p), std::string::npos) << "missing '" << p << "' in: " << msg;
    }
    if (line > 0) {
      EXPECT_EQ(e.line(), line) << msg;
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

void ExpectSameMesh(const TetMesh& a, const TetMesh& b) {
  ASSERT_EQ(a.num_nodes(), b.num_nodes());
  ASSERT_EQ(a.num_tets(), b.num_tets());
  for (std::int32_t v = 0; v < a.num_nodes(); ++v) {
    const auto j = b.IndexOfId(a.node_ids()[v]);
    ASSERT_TRUE(j.has_value());
    EXPECT_EQ((a.positions_m()[v] - b.positions_m()[*j]).norm(), 0.0);
  }
  for (std::int32_t e = 0; e < a.num_tets(); ++e) {
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(a.node_ids()[a.tets()[e][k]], b.node_ids()[b.tets()[e][k]]);
    }
  }
}

TEST(MeshIo, ThreeFormatsReadTheSameMesh) {
  const TetMesh msh = ReadGmshMsh(kData / "box_2x1x1.msh");
  const TetMesh tg = ReadTetgen(kData / "box_2x1x1.node");
  const TetMesh inp = ReadAbaqusInp(kData / "box_2x1x1.inp");
  EXPECT_EQ(msh.num_nodes(), 12);
  EXPECT_EQ(msh.num_tets(), 12);
  ExpectSameMesh(msh, tg);
  ExpectSameMesh(msh, inp);
  // 0.02 x 0.01 x 0.01 m.
  EXPECT_NEAR(msh.Volume(), 2e-6, 1e-18);
  // The bottom face as a node set in each format's own way.
  for (const auto& [mesh, name] : {std::pair{&msh, "bottom"}, std::pair{&tg, "marker:1"},
                                   std::pair{&inp, "BOTTOM"}}) {
    const auto* set = mesh->FindNodeSet(name);
    ASSERT_NE(set, nullptr) << name;
    EXPECT_EQ(set->size(), 6u) << name;
    for (std::int32_t v : *set) EXPECT_EQ(mesh->positions_m()[v].z(), 0.0);
  }
  // Dispatch by extension.
  EXPECT_EQ(ReadVolumeMesh(kData / "box_2x1x1.inp").num_tets(), 12);
  EXPECT_EQ(ReadVolumeMesh(kData / "box_2x1x1.ele").num_tets(), 12);
}

constexpr const char* kGoodMsh =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
    "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n"
    "$Elements\n2\n1 4 2 0 1 1 2 3 4\n2 4 2 0 1 2 3 4 5\n$EndElements\n";

TEST(MeshIo, GmshMinimalFileReads) {
  test::TempDir dir;
  const TetMesh m = ReadGmshMsh(dir.Write("ok.msh", kGoodMsh));
  EXPECT_EQ(m.num_tets(), 2);
  // Unit corner tet (1/6) plus the tet (1,0,0), (0,1,0), (0,0,1), (1,1,1) (det 2, volume 1/3).
  EXPECT_NEAR(m.Volume(), 1.0 / 6.0 + 1.0 / 3.0, 1e-15);
}

TEST(MeshIo, GmshErrorsNameFileLineAndField) {
  test::TempDir dir;
  auto with = [&](const std::string& from, const std::string& to) {
    std::string s = kGoodMsh;
    s.replace(s.find(from), from.size(), to);
    return dir.Write("bad.msh", s).string();
  };
  // Unknown node id 9 in element 2 on line 15.
  auto f = with("2 4 2 0 1 2 3 4 5", "2 4 2 0 1 2 3 4 9");
  ExpectInputError([&] { ReadGmshMsh(f); }, {f + ":15", "element 2", "unknown node id 9"}, 15);
  // Inverted element: swapping two nodes flips the sign of the volume.
  f = with("1 4 2 0 1 1 2 3 4", "1 4 2 0 1 1 3 2 4");
  ExpectInputError([&] { ReadGmshMsh(f); }, {f + ":14", "element 1", "inverted"}, 14);
  // Malformed coordinate, NaN coordinate.
  f = with("2 1 0 0", "2 1 zero 0");
  ExpectInputError([&] { ReadGmshMsh(f); }, {f + ":7", "field 'y'", "expected a number"}, 7);
  f = with("2 1 0 0", "2 1 nan 0");
  ExpectInputError([&] { ReadGmshMsh(f); }, {f + ":7", "field 'y'", "not a finite number"}, 7);
  // Truncated: the file ends inside $Elements.
  std::string trunc = kGoodMsh;
  trunc.resize(trunc.find("2 4 2 0"));
  f = dir.Write("trunc.msh", trunc).string();
  ExpectInputError([&] { ReadGmshMsh(f); }, {f, "unexpected end of file"});
  // Unsupported versions, binary files and element types.
  f = with("2.2 0 8", "4.1 0 8");
  ExpectInputError([&] { ReadGmshMsh(f); }, {f + ":2", "version", "msh22"}, 2);
  f = with("2.2 0 8", "2.2 1 8");
  ExpectInputError([&] { ReadGmshMsh(f); }, {f + ":2", "binary"}, 2);
  f = with("1 4 2 0 1 1 2 3 4", "1 11 2 0 1 1 2 3 4 1 2 3 4 5 1");
  ExpectInputError([&] { ReadGmshMsh(f); }, {f + ":14", "element type", "type 11"}, 14);
  // Wrong node count for the element type.
  f = with("1 4 2 0 1 1 2 3 4", "1 4 2 0 1 1 2 3");
  ExpectInputError([&] { ReadGmshMsh(f); }, {f + ":14", "needs 4 node ids"}, 14);
  // Duplicate node id.
  f = with("5 1 1 1", "4 1 1 1");
  ExpectInputError([&] { ReadGmshMsh(f); }, {f + ":10", "duplicate node id 4"}, 10);
  // Not a file at all.
  ExpectInputError([&] { ReadGmshMsh(dir.path() / "missing.msh"); }, {"missing.msh", "cannot open"});
  // An unknown section that never ends is named (its name was read from a line the search for
  // its end had overwritten: a use after free, found by the gmsh_mesh fuzz target).
  f = dir.Write("unended.msh", std::string(kGoodMsh) + "$NodeDataWithALongNameBeyondSmallStrings\n1\n2\n").string();
  ExpectInputError([&] { ReadGmshMsh(f); },
                   {f, "$NodeDataWithALongNameBeyondSmallStrings", "missing $EndNodeDataWithALongNameBeyondSmallStrings"});
}

TEST(MeshIo, TetgenErrors) {
  test::TempDir dir;
  dir.Write("a.node", "# c\n5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n");
  const std::string ele = dir.Write("a.ele", "2 4 0\n1 1 2 3 4\n2 2 3 4 5\n").string();
  EXPECT_EQ(ReadTetgen(dir.path() / "a").num_tets(), 2);
  dir.Write("a.ele", "2 4 0\n1 1 2 3 4\n2 2 3 4 6\n");
  ExpectInputError([&] { ReadTetgen(dir.path() / "a"); }, {ele + ":3", "unknown node id 6"}, 3);
  dir.Write("a.ele", "2 10 0\n");
  ExpectInputError([&] { ReadTetgen(dir.path() / "a"); }, {ele + ":1", "nodes per tetrahedron"}, 1);
  dir.Write("a.ele", "3 4 0\n1 1 2 3 4\n2 2 3 4 5\n");
  ExpectInputError([&] { ReadTetgen(dir.path() / "a"); }, {ele, "fewer tetrahedra"});
  const std::string node = dir.Write("b.node", "2 2 0 0\n1 0 0\n2 1 0\n").string();
  dir.Write("b.ele", "0 4 0\n");
  ExpectInputError([&] { ReadTetgen(dir.path() / "b"); }, {node + ":1", "dimension"}, 1);
}

constexpr const char* kGoodInp =
    "** comment\n*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n5, 1., 1., 1.\n"
    "*ELEMENT, TYPE=C3D4, ELSET=E\n1, 1, 2, 3, 4\n2, 2, 3,\n 4, 5\n"
    "*NSET, NSET=A\n1, 2\n*nset, nset=B, generate\n3, 5, 2\n*NSET, NSET=C\nA, B\n"
    "*MATERIAL, NAME=M\n*ELASTIC\n1e4, 0.3\n";

TEST(MeshIo, AbaqusSubset) {
  test::TempDir dir;
  const TetMesh m = ReadAbaqusInp(dir.Write("ok.inp", kGoodInp));
  EXPECT_EQ(m.num_tets(), 2);
  ASSERT_NE(m.FindNodeSet("C"), nullptr);
  EXPECT_EQ(m.FindNodeSet("C")->size(), 4u);  // 1, 2 and 3, 5
  EXPECT_EQ(*m.FindNodeSet("B"), (std::vector<std::int32_t>{2, 4}));
}

TEST(MeshIo, AbaqusErrors) {
  test::TempDir dir;
  auto with = [&](const std::string& from, const std::string& to) {
    std::string s = kGoodInp;
    s.replace(s.find(from), from.size(), to);
    return dir.Write("bad.inp", s).string();
  };
  auto f = with("TYPE=C3D4", "TYPE=C3D10");
  ExpectInputError([&] { ReadAbaqusInp(f); }, {f + ":8", "C3D10", "only C3D4"}, 8);
  f = with("1, 1, 2, 3, 4", "1, 1, 2, 3, 7");
  ExpectInputError([&] { ReadAbaqusInp(f); }, {f + ":9", "element 1", "unknown node id 7"}, 9);
  f = with("3, 0, 1, 0", "3, 0, 1");
  ExpectInputError([&] { ReadAbaqusInp(f); }, {f + ":5", "expected 'id, x, y, z'"}, 5);
  f = with("*NSET, NSET=A\n1, 2", "*NSET, NSET=A\n1, 12");
  ExpectInputError([&] { ReadAbaqusInp(f); }, {f + ":13", "node set A", "unknown node id 12"}, 13);
  f = with("A, B", "A, Q");
  ExpectInputError([&] { ReadAbaqusInp(f); }, {f + ":17", "unknown node set 'Q'"}, 17);
  f = with(" 4, 5\n*NSET", "*NSET");
  ExpectInputError([&] { ReadAbaqusInp(f); }, {f + ":11", "no continuation line"}, 11);
  f = with("2, 2, 3,\n 4, 5", "2, 3, 2,\n 4, 5");
  ExpectInputError([&] { ReadAbaqusInp(f); }, {f + ":10", "element 2", "inverted"}, 10);
}

TEST(MeshIo, UnknownExtension) {
  ExpectInputError([] { ReadVolumeMesh("mesh.vtk"); }, {"mesh.vtk", "unknown mesh format"});
}

}  // namespace
}  // namespace handshare::fem
