// The stiffening table (fem/stiffening.hpp): its file's checks, the gains it interpolates onto a
// mesh's surface nodes, and a patch's gain.
#include "handshare/fem/stiffening.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include <gtest/gtest.h>

#include "handshare/fem/error.hpp"

namespace handshare::fem {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

fs::path TempFile(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("handshare_stiffening_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p) << text;
  return p;
}

const char* kHeader =
    "x_m,y_m,z_m,nx,ny,nz,ax,ay,az,g_normal_4mm,g_normal_10mm,g_t1_4mm,g_t1_10mm,g_t2_4mm,g_t2_10mm\n";

std::string ErrorOf(const fs::path& p) {
  try {
    ReadStiffeningSamples(p);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Stiffening, ABadTableNamesItsFileLineAndField) {
  const fs::path header = TempFile("header.csv", "x_m,y_m\n1,2\n");
  EXPECT_NE(ErrorOf(header).find(header.string() + ":1: field 'header'"), std::string::npos) << ErrorOf(header);
  const fs::path gain = TempFile("gain.csv", std::string("# a comment\n") + kHeader + "0,0,0,0,0,1,1,0,0,1.1,9,1,1,1,1\n");
  EXPECT_NE(ErrorOf(gain).find(gain.string() + ":3: field 'g_normal_10mm': a gain outside [0.2, 5]"), std::string::npos)
      << ErrorOf(gain);
  const fs::path word = TempFile("word.csv", std::string(kHeader) + "0,0,zero,0,0,1,1,0,0,1,1,1,1,1,1\n");
  EXPECT_NE(ErrorOf(word).find(":2: field 'z_m': not a finite number: 'zero'"), std::string::npos) << ErrorOf(word);
  const fs::path normal = TempFile("normal.csv", std::string(kHeader) + "0,0,0,0,0,2,1,0,0,1,1,1,1,1,1\n");
  EXPECT_NE(ErrorOf(normal).find("field 'nx': the normal is not a unit vector"), std::string::npos) << ErrorOf(normal);
  const fs::path empty = TempFile("empty.csv", kHeader);
  EXPECT_NE(ErrorOf(empty).find("no samples"), std::string::npos) << ErrorOf(empty);
  EXPECT_NE(ErrorOf("/nonexistent/table.csv").find("cannot open"), std::string::npos);
  for (const auto& p : {header, gain, word, normal, empty}) fs::remove(p);
}

// A 40 mm cube (5 mm cells), its top face (z = 40 mm) sampled at a corner and 10 mm from it: gains known per depth
// and way; a node at a sample takes its gains, one far from both none.
struct StiffeningCube : ::testing::Test {
  TetMesh mesh = MakeBoxMesh(Vector3d(0.04, 0.04, 0.04), {8, 8, 8});
  Surface surface = ExtractSurface(mesh);
  std::int32_t NodeAt(const Vector3d& p) const {
    for (std::int32_t i = 0; i < mesh.num_nodes(); ++i) {
      if ((mesh.positions_m()[static_cast<std::size_t>(i)] - p).norm() < 1e-9) return i;
    }
    return -1;
  }
  std::vector<StiffeningSample> Samples() const {
    StiffeningSample a;
    a.p_m = {0.0, 0.0, 0.04};
    a.n_out = Vector3d::UnitZ();
    a.axis = Vector3d::UnitX();
    a.g_normal = {1.2, 1.5};
    a.g_t1 = {0.9, 0.8};
    a.g_t2 = {1.1, 1.3};
    StiffeningSample b = a;
    b.p_m = {0.01, 0.0, 0.04};
    b.g_normal = {1.0, 1.0};
    return {a, b};
  }
};

TEST_F(StiffeningCube, ANodeAtASampleHasItsGainsAtEachDepthAndWay) {
  const auto samples = Samples();
  const fs::path file = TempFile("cube.csv", "");
  WriteStiffeningSamples(file, samples, "a test table\nsecond line");
  const auto read = ReadStiffeningSamples(file);  // the written file reads back
  fs::remove(file);
  ASSERT_EQ(read.size(), 2u);
  EXPECT_NEAR(read[0].g_normal[1], 1.5, 1e-9);
  const StiffeningTable table(mesh, surface, read);
  const std::int32_t at_a = NodeAt({0.0, 0.0, 0.04});
  ASSERT_GE(at_a, 0);
  const Vector3d n = Vector3d::UnitZ();
  EXPECT_DOUBLE_EQ(table.NodeGain(at_a, Vector3d::Zero(), n), 1.0);             // not pressed
  EXPECT_DOUBLE_EQ(table.NodeGain(at_a, Vector3d(0, 0, 0.001), n), 1.0);        // pulled out
  EXPECT_NEAR(table.NodeGain(at_a, Vector3d(0, 0, -0.002), n), 1.1, 1e-6);      // half way to 4 mm
  EXPECT_NEAR(table.NodeGain(at_a, Vector3d(0, 0, -0.004), n), 1.2, 1e-6);
  EXPECT_NEAR(table.NodeGain(at_a, Vector3d(0, 0, -0.007), n), 1.35, 1e-6);     // between 4 and 10 mm
  EXPECT_NEAR(table.NodeGain(at_a, Vector3d(0, 0, -0.02), n), 1.5, 1e-6);       // the deepest beyond
  const double t = std::tan(kStiffeningObliqueRad);
  EXPECT_NEAR(table.NodeGain(at_a, 0.004 * Vector3d(t, 0, -1), n), 0.9, 1e-6);   // oblique toward t1 = x
  EXPECT_NEAR(table.NodeGain(at_a, 0.004 * Vector3d(-t, 0, -1), n), 0.9, 1e-6);  // either way along it
  EXPECT_NEAR(table.NodeGain(at_a, 0.004 * Vector3d(0, t, -1), n), 1.1, 1e-6);   // toward t2 = y
  EXPECT_NEAR(table.NodeGain(at_a, 0.004 * Vector3d(t / 2, 0, -1), n), 0.5 * 1.2 + 0.5 * 0.9, 1e-6);  // half a lean
  // A node between the samples takes their inverse-square-distance mean; one far from both
  // (the opposite corner, farther than 1.5 spacings) and one facing another way keep 1.
  const std::int32_t between = NodeAt({0.005, 0.0, 0.04});
  ASSERT_GE(between, 0);
  EXPECT_NEAR(table.NodeGain(between, Vector3d(0, 0, -0.004), n), 1.1, 1e-6);
  EXPECT_DOUBLE_EQ(table.NodeGain(NodeAt({0.04, 0.04, 0.04}), Vector3d(0, 0, -0.004), n), 1.0);
  EXPECT_DOUBLE_EQ(table.NodeGain(NodeAt({0.0, 0.0, 0.0}), Vector3d(0, 0, 0.004), -n), 1.0);
  EXPECT_DOUBLE_EQ(table.NodeGain(-1, Vector3d(0, 0, -0.004), n), 1.0);
  EXPECT_EQ(table.num_samples(), 2u);
  EXPECT_GT(table.covered_nodes(), 2u);
  EXPECT_LT(table.covered_nodes(), surface.nodes.size() / 4);
}

// A patch's gain weighs its nodes by their push; a node that pulls or carries only force
// along the surface counts for nothing, so a pair of opposite tangential forces does not change
// it.
TEST_F(StiffeningCube, APatchGainWeighsItsNodesByTheirPush) {
  const StiffeningTable table(mesh, surface, Samples());
  const Vector3d n = Vector3d::UnitZ();
  std::vector<ContactInput> in(2);
  in[0].node = NodeAt({0.0, 0.0, 0.04});
  in[1].node = NodeAt({0.01, 0.0, 0.04});
  in[0].u_m = in[1].u_m = Vector3d(0, 0, -0.004);
  std::vector<Vector3d> f = {Vector3d(0, 0, -3.0), Vector3d(0, 0, -1.0)};
  EXPECT_NEAR(table.PatchGain(in, f, n, Vector3d::Zero()), (3.0 * 1.2 + 1.0 * 1.0) / 4.0, 1e-6);
  f[0] += Vector3d(5, 0, 0);
  f[1] -= Vector3d(5, 0, 0);
  EXPECT_NEAR(table.PatchGain(in, f, n, Vector3d::Zero()), (3.0 * 1.2 + 1.0 * 1.0) / 4.0, 1e-6);
  f[1] = Vector3d(0, 0, 0.5);  // pulls: no weight
  EXPECT_NEAR(table.PatchGain(in, f, n, Vector3d::Zero()), 1.2, 1e-6);
  EXPECT_DOUBLE_EQ(table.PatchGain(in, std::vector<Vector3d>{Vector3d::Zero(), Vector3d::Zero()}, n, Vector3d::Zero()), 1.0);
  // The stick leans the press: at full lean toward t1 the first node's gain is its g_t1.
  f = {Vector3d(0, 0, -1.0), Vector3d::Zero()};
  EXPECT_NEAR(table.PatchGain(in, f, n, Vector3d(0.004 * std::tan(kStiffeningObliqueRad), 0, 0)), 0.9, 1e-6);
}

}  // namespace
}  // namespace handshare::fem
