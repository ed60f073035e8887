// Surface extraction, surface import (assimp) and tetrahedralization (external tetgen).

#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>

#include <Eigen/Geometry>

#include "handshare/fem/error.hpp"
#include "handshare/fem/surface_import.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

const std::filesystem::path kData = HANDSHARE_FEM_TEST_DATA;

// Volume enclosed by outward triangles (divergence theorem): sum p0 . (p1 x p2) / 6.
double EnclosedVolume(const std::vector<Eigen::Vector3d>& p, const std::vector<Triangle>& tris) {
  double v = 0.0;
  for (const auto& t : tris) v += p[t[0]].dot(p[t[1]].cross(p[t[2]])) / 6.0;
  return v;
}

TEST(Surface, BoxCountsOrientationAndNormals) {
  const TetMesh m = MakeBoxMesh({0.03, 0.04, 0.05}, {3, 4, 5});
  const Surface s = ExtractSurface(m);
  EXPECT_EQ(s.nodes.size(), std::size_t{4 * 5 * 6 - 2 * 3 * 4});
  EXPECT_EQ(s.triangles.size(), std::size_t{2 * 2 * (3 * 4 + 4 * 5 + 3 * 5)});
  // Outward orientation: the triangles enclose the mesh volume with a positive sign.
  EXPECT_NEAR(EnclosedVolume(m.positions_m(), s.triangles), m.Volume(), 1e-12 * m.Volume());
  EXPECT_NEAR(m.Volume(), 0.03 * 0.04 * 0.05, 1e-15);
  // The surface is closed: every edge in exactly two triangles.
  SurfaceMeshData sm{m.positions_m(), {}};
  for (const auto& t : s.triangles) sm.triangles.push_back(t);
  EXPECT_NO_THROW(CheckClosed(sm, "box"));
  // Face-interior nodes have the face normal; a corner node the mean of three.
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    const Eigen::Vector3d& x = m.positions_m()[s.nodes[i]];
    if (std::abs(x.z() - 0.05) < 1e-12 && x.x() > 1e-9 && x.x() < 0.03 - 1e-9 && x.y() > 1e-9 &&
        x.y() < 0.04 - 1e-9) {
      EXPECT_LT((s.normals[i] - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
    }
    EXPECT_NEAR(s.normals[i].norm(), 1.0, 1e-12);
  }
}

TEST(Surface, NonManifoldAndOverlappingMeshesAreRejected) {
  std::vector<Eigen::Vector3d> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.1, 0.1, -1}, {0.2, 0.2, 1}};
  // Three elements on one face (0,1,2): non-manifold.
  TetMesh three(p, {{0, 1, 2, 3}, {0, 2, 1, 4}, {0, 1, 2, 5}}, {}, "three.msh");
  try {
    ExtractSurface(three);
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("shared by 3 elements"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("three.msh"), std::string::npos) << e.what();
  }
  // Two elements on the same side of one face: overlapping.
  TetMesh overlap(p, {{0, 1, 2, 3}, {0, 1, 2, 5}}, {}, "overlap.msh");
  EXPECT_THROW(ExtractSurface(overlap), InputError);
}

TEST(Surface, InvertedElementInConstructorIsRejected) {
  std::vector<Eigen::Vector3d> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  try {
    TetMesh m(p, {{0, 2, 1, 3}}, {}, "inv.node");
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("inverted"), std::string::npos) << e.what();
    EXPECT_EQ(e.field(), "element 1");
  }
}

TEST(SurfaceImport, ObjAndStlAreWelded) {
  const SurfaceMeshData obj = ReadSurfaceMesh(kData / "cube.obj");
  EXPECT_EQ(obj.p_m.size(), 8u);
  EXPECT_EQ(obj.triangles.size(), 12u);
  EXPECT_NO_THROW(CheckClosed(obj, "cube.obj"));
  // The same cube as ASCII STL (every vertex repeated per facet).
  std::ostringstream stl;
  stl << "solid cube\n";
  for (const auto& t : obj.triangles) {
    stl << " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const auto& x = obj.p_m[t[k]];
      stl << "   vertex " << x.x() << ' ' << x.y() << ' ' << x.z() << "\n";
    }
    stl << "  endloop\n endfacet\n";
  }
  stl << "endsolid cube\n";
  test::TempDir dir;
  const SurfaceMeshData s = ReadSurfaceMesh(dir.Write("cube.stl", stl.str()));
  EXPECT_EQ(s.p_m.size(), 8u);
  EXPECT_EQ(s.triangles.size(), 12u);
}

TEST(SurfaceImport, OpenSurfaceIsRejected) {
  const SurfaceMeshData s = ReadSurfaceMesh(kData / "open_box.obj");
  try {
    CheckClosed(s, "open_box.obj");
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a closed surface"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("open_box.obj"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadSurfaceMesh("/nonexistent/x.obj"), InputError);
}

bool HaveTetgen() { return std::system("command -v tetgen > /dev/null 2>&1") == 0; }

TEST(Tetgen, ClosedCubeBecomesAVolumeMesh) {
  if (!HaveTetgen()) GTEST_SKIP() << "tetgen not installed (Debian package tetgen)";
  TetgenOptions opt;
  opt.max_volume_m3 = 1e-9;  // cube of 1e-6 m^3 -> at least 1000 elements
  const TetMesh m = TetrahedralizeSurfaceFile(kData / "cube.obj", opt);
  EXPECT_GE(m.num_tets(), 1000);
  // assimp stores vertices as float: the cube edge is 0.01f. TetGen fills the cube exactly, so
  // the volumes agree with that cube to round-off.
  const double edge = static_cast<double>(0.01f);
  const double vol = edge * edge * edge;
  EXPECT_NEAR(m.Volume(), vol, vol * 1e-12);
  const Surface s = ExtractSurface(m);
  EXPECT_NEAR(EnclosedVolume(m.positions_m(), s.triangles), vol, vol * 1e-12);
  // Every surface node lies on a cube face (TetGen's Steiner points are computed in double).
  for (std::int32_t v : s.nodes) {
    const Eigen::Vector3d& x = m.positions_m()[v];
    const double d = std::min({x.x(), x.y(), x.z(), edge - x.x(), edge - x.y(), edge - x.z()});
    EXPECT_NEAR(d, 0.0, 1e-15);
  }
  // The dispatcher tetrahedralizes surface formats too.
  EXPECT_GT(ReadVolumeMesh(kData / "cube.obj").num_tets(), 0);
}

TEST(Tetgen, MissingProgramIsAClearError) {
  TetgenOptions opt;
  opt.program = "handshare-no-such-tetgen";
  try {
    TetrahedralizeSurfaceFile(kData / "cube.obj", opt);
    ADD_FAILURE() << "no exception";
  } catch (const FemError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot run 'handshare-no-such-tetgen'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace handshare::fem
