// Precomputed compliance blocks against direct solves, and the cache file: round trip, reuse,
// and a clear rejection of stale, corrupt and truncated files.

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

#include <Eigen/Cholesky>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/error.hpp"
#include "handshare/fem/static_solver.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

class ComplianceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    block_ = new test::Block(test::MakeFixedBottomBox({0.04, 0.04, 0.02}, {8, 8, 4}));
    ComplianceOptions o;
    o.block_nodes = 7;  // several right-hand-side blocks, one of them partial
    c64_ = new Compliance(Compliance::Precompute(block_->mesh, kMat, block_->fixed, o));
    o.precision = Precision::kFloat32;
    c32_ = new Compliance(Compliance::Precompute(block_->mesh, kMat, block_->fixed, o));
  }
  static void TearDownTestSuite() {
    delete c32_;
    delete c64_;
    delete block_;
  }
  static constexpr Material kMat{1e4, 0.3};
  static test::Block* block_;
  static Compliance* c64_;
  static Compliance* c32_;
};
test::Block* ComplianceTest::block_ = nullptr;
Compliance* ComplianceTest::c64_ = nullptr;
Compliance* ComplianceTest::c32_ = nullptr;

TEST_F(ComplianceTest, NodesAreTheFreeSurfaceNodes) {
  // 9 x 9 x 5 nodes; surface = all - interior (7 x 7 x 3); minus the fixed bottom (9 x 9).
  EXPECT_EQ(c64_->num_nodes(), 405 - 147 - 81);
  for (std::int32_t v : c64_->nodes()) {
    EXPECT_FALSE(c64_->IsFixed(v));
    EXPECT_EQ(c64_->nodes()[c64_->SlotOf(v)], v);
  }
  for (std::int32_t v : block_->fixed) EXPECT_EQ(c64_->SlotOf(v), -1);
  // Symmetric storage: 9 N (N + 1) / 2 scalars, i.e. 4.5 N^2 + O(N) scalars.
  const std::size_t N = static_cast<std::size_t>(c32_->num_nodes());
  EXPECT_EQ(c32_->storage_bytes(), 4 * 9 * N * (N + 1) / 2);
  EXPECT_EQ(c64_->storage_bytes(), 8 * 9 * N * (N + 1) / 2);
}

// A column of C is the displacement under a unit force: compare with the direct solve.
// Tolerance 1e-10 relative: both are double-precision direct solves of a ~1200-DOF system.
TEST_F(ComplianceTest, BlocksMatchDirectUnitLoadSolves) {
  StaticSolver direct(block_->mesh, kMat, block_->fixed, {});
  for (std::int32_t k : {0, 17, c64_->num_nodes() - 1}) {
    for (int a = 0; a < 3; ++a) {
      const StaticSolution s = direct.Solve({}, std::vector<NodalValue>{{c64_->nodes()[k], Eigen::Vector3d::Unit(a)}});
      std::vector<Eigen::Vector3d> got, want;
      for (std::int32_t n = 0; n < c64_->num_nodes(); ++n) {
        got.push_back(c64_->Block(n, k).col(a));
        want.push_back(s.u_m[c64_->nodes()[n]]);
      }
      EXPECT_LT(test::RelError(got, want), 1e-10) << "slot " << k << " axis " << a;
    }
  }
}

// The two precomputation methods (blocked solves; dense inverse of the Schur complement) give
// the same blocks to round-off. Bound 1e-11 of the largest diagonal block.
TEST_F(ComplianceTest, BothPrecomputeMethodsAgree) {
  ComplianceOptions o;
  o.method = PrecomputeMethod::kBlockedSolves;
  PrecomputeStats s1, s2;
  const Compliance a = Compliance::Precompute(block_->mesh, kMat, block_->fixed, o, {}, &s1);
  o.method = PrecomputeMethod::kSchurComplement;
  const Compliance b = Compliance::Precompute(block_->mesh, kMat, block_->fixed, o, {}, &s2);
  EXPECT_EQ(s1.method, PrecomputeMethod::kBlockedSolves);
  EXPECT_EQ(s2.method, PrecomputeMethod::kSchurComplement);
  ASSERT_EQ(a.num_nodes(), b.num_nodes());
  double scale = 0.0, diff = 0.0;
  for (std::int32_t k = 0; k < a.num_nodes(); ++k) {
    scale = std::max(scale, a.Block(k, k).norm());
    for (std::int32_t n = 0; n <= k; ++n) diff = std::max(diff, (a.Block(n, k) - b.Block(n, k)).norm());
  }
  EXPECT_LT(diff, 1e-11 * scale);
  // Progress reports reach the total.
  std::int64_t last = -1, total = 0;
  Compliance::Precompute(block_->mesh, kMat, block_->fixed, o,
                         [&](std::int64_t d, std::int64_t t) { last = d; total = t; });
  EXPECT_EQ(last, total);
  EXPECT_EQ(total, a.num_nodes());
}

TEST_F(ComplianceTest, SymmetricPositiveDefiniteAndFloat32Close) {
  for (std::int32_t n = 0; n < c64_->num_nodes(); n += 13) {
    for (std::int32_t k = 0; k < c64_->num_nodes(); k += 11) {
      EXPECT_EQ((c64_->Block(n, k) - c64_->Block(k, n).transpose()).norm(), 0.0);
      // float32 rounding: relative 6e-8 per entry, compare against the block's size.
      EXPECT_LT((c32_->Block(n, k) - c64_->Block(n, k)).norm(), 1e-6 * c64_->Block(k, k).norm());
    }
    Eigen::LLT<Eigen::Matrix3d> llt(c64_->Block(n, n));
    EXPECT_EQ(llt.info(), Eigen::Success);
  }
}

TEST_F(ComplianceTest, CacheRoundTripAndReuse) {
  test::TempDir dir;
  const auto file = dir.path() / "block.compliance";
  c32_->Save(file);
  ComplianceOptions o32;
  o32.precision = Precision::kFloat32;
  const std::uint64_t h = Compliance::InputHash(block_->mesh, kMat, block_->fixed, o32);
  EXPECT_EQ(h, c32_->input_hash());
  const Compliance back = Compliance::Load(file, h);
  ASSERT_EQ(back.num_nodes(), c32_->num_nodes());
  EXPECT_EQ(back.precision(), Precision::kFloat32);
  EXPECT_EQ(0, std::memcmp(back.data_f32(), c32_->data_f32(), c32_->storage_bytes()));
  EXPECT_EQ(back.SlotOf(c32_->nodes()[5]), 5);
  EXPECT_TRUE(back.IsFixed(block_->fixed[0]));
  std::string note;
  const Compliance again = Compliance::LoadOrPrecompute(file, block_->mesh, kMat, block_->fixed, o32, {}, &note);
  EXPECT_NE(note.find("loaded"), std::string::npos) << note;
}

std::string LoadError(const std::filesystem::path& f, std::uint64_t hash) {
  try {
    Compliance::Load(f, hash);
  } catch (const CacheError& e) {
    return e.what();
  }
  return "no exception";
}

void Patch(const std::filesystem::path& f, std::streamoff at, char value) {
  std::fstream io(f, std::ios::in | std::ios::out | std::ios::binary);
  io.seekp(at);
  io.put(value);
}

TEST_F(ComplianceTest, StaleCorruptAndTruncatedCachesAreRejected) {
  test::TempDir dir;
  const auto file = dir.path() / "c.compliance";
  c64_->Save(file);
  const std::uint64_t h = c64_->input_hash();
  // Stale: another material (and another fixed set) hash differently.
  const std::uint64_t h_soft = Compliance::InputHash(block_->mesh, {5e3, 0.3}, block_->fixed, {});
  EXPECT_NE(h_soft, h);
  std::vector<std::int32_t> fewer(block_->fixed.begin() + 1, block_->fixed.end());
  EXPECT_NE(Compliance::InputHash(block_->mesh, kMat, fewer, {}), h);
  std::string msg = LoadError(file, h_soft);
  EXPECT_NE(msg.find("stale"), std::string::npos) << msg;
  EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
  // LoadOrPrecompute recomputes a stale cache and says why.
  {
    const auto copy = dir.path() / "copy.compliance";
    std::filesystem::copy_file(file, copy);
    std::string note;
    const Compliance soft = Compliance::LoadOrPrecompute(copy, block_->mesh, {5e3, 0.3}, block_->fixed, {}, {}, &note);
    EXPECT_NE(note.find("stale"), std::string::npos) << note;
    EXPECT_NEAR(soft.Block(3, 3).norm(), 2.0 * c64_->Block(3, 3).norm(), 1e-9 * soft.Block(3, 3).norm());
    EXPECT_NO_THROW(Compliance::Load(copy, soft.input_hash()));
  }
  const auto size = std::filesystem::file_size(file);
  // Corrupt payload: one byte in the blocks.
  auto corrupt = dir.path() / "corrupt.compliance";
  std::filesystem::copy_file(file, corrupt);
  Patch(corrupt, static_cast<std::streamoff>(size - 100), 0x55);
  msg = LoadError(corrupt, h);
  EXPECT_NE(msg.find("checksum"), std::string::npos) << msg;
  // Corrupt header: the node count.
  auto corrupt_h = dir.path() / "corrupt_h.compliance";
  std::filesystem::copy_file(file, corrupt_h);
  Patch(corrupt_h, 32, 0x7f);
  msg = LoadError(corrupt_h, h);
  EXPECT_NE(msg.find("corrupt header"), std::string::npos) << msg;
  // Truncated.
  auto trunc = dir.path() / "trunc.compliance";
  std::filesystem::copy_file(file, trunc);
  std::filesystem::resize_file(trunc, size - 1000);
  msg = LoadError(trunc, h);
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
  std::filesystem::resize_file(trunc, 40);
  msg = LoadError(trunc, h);
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
  // Not a cache, another version, missing.
  const auto text = dir.path() / "text.compliance";
  std::ofstream(text) << std::string(200, 'x');
  msg = LoadError(text, h);
  EXPECT_NE(msg.find("not a handshare compliance cache"), std::string::npos) << msg;
  auto version = dir.path() / "version.compliance";
  std::filesystem::copy_file(file, version);
  Patch(version, 8, 9);
  msg = LoadError(version, h);
  EXPECT_NE(msg.find("format version 9"), std::string::npos) << msg;
  msg = LoadError(dir.path() / "missing.compliance", h);
  EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;
}

TEST(ComplianceOptionsTest, ExplicitNodesAreChecked) {
  const test::Block b = test::MakeFixedBottomBox({0.01, 0.01, 0.01}, {2, 2, 2});
  ComplianceOptions o;
  o.nodes = {b.fixed[0]};
  EXPECT_THROW(Compliance::Precompute(b.mesh, {1e4, 0.3}, b.fixed, o), InputError);
  o.nodes = {20, 20};
  EXPECT_THROW(Compliance::Precompute(b.mesh, {1e4, 0.3}, b.fixed, o), InputError);
  o.nodes = {13};  // the centre node: interior nodes may be compliance nodes too
  const Compliance c = Compliance::Precompute(b.mesh, {1e4, 0.3}, b.fixed, o);
  EXPECT_EQ(c.num_nodes(), 1);
  // Nothing fixed: singular.
  EXPECT_THROW(Compliance::Precompute(b.mesh, {1e4, 0.3}, {}, {}), FemError);
}

}  // namespace
}  // namespace handshare::fem
