// The faster and smaller surface-field storages against the direct sparse solve (the exact
// static FEM answer): the block low-rank compressed compliance (forces and surface field through
// the unchanged ContactSolver), the planar column copy in float32 and float16, the paper's T^d
// in float16, every kernel instruction set against the portable one, and the bad inputs.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <string>

#include "../src/compressed_blocks.hpp"
#include "../src/planar_columns.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/elementary_displacement.hpp"
#include "handshare/fem/error.hpp"
#include "handshare/fem/surface_field.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

constexpr Material kMat{1e4, 0.3};

// A wide thin block (bottom fixed): 750 free surface nodes, far apart enough for clusters of
// 16 nodes to have well-separated (compressible) partners.
using Model = test::BlockModel;

const Model& WideModel() {
  static const Model m = test::MakeBlockModel(test::MakeFixedBottomBox({0.12, 0.12, 0.015}, {16, 16, 2}), kMat);
  return m;
}

struct Errors {
  double force = 0.0, field = 0.0;
};

// ContactSolver on `c` (forces) and `field` (surface) against the direct solve.
Errors Compare(const Model& m, std::shared_ptr<const Compliance> c, SurfaceField& field,
               const std::vector<ContactInput>& in) {
  ContactSolver solver(std::move(c), {.max_contacts = 16});
  EXPECT_EQ(solver.Solve(in), StepStatus::kOk);
  const test::DirectContact d = test::SolveDirect(m.block.mesh, kMat, m.block.fixed, in);
  std::vector<Eigen::Vector3d> f(solver.forces_N().begin(), solver.forces_N().end());
  std::vector<Eigen::Vector3d> u(static_cast<std::size_t>(m.c64->num_nodes())), u_ref;
  EXPECT_TRUE(field.Evaluate(solver.loads(), u));
  for (std::int32_t v : m.c64->nodes()) u_ref.push_back(d.solution.u_m[v]);
  return {test::RelError(f, d.forces_N), test::RelError(u, u_ref)};
}

// Compressed at tolerance tol: ||C - C~||_F <= tol ||C||_F tile by tile (checked on the explicit
// residual), and float32 entries (6e-8). Forces solve C_cc f = d* (cond(C_cc) of a few for
// distinct random nodes) and the field sums 5 columns, so both errors stay within a small
// multiple of tol + 1e-7: bound 100 tol + 1e-5. Measured about 1e-7 (tol 1e-6) and 1e-4 (tol 1e-3).
TEST(CompressedCompliance, MatchesDirectSparseSolve) {
  const Model& m = WideModel();
  double previous_bytes = 0.0;
  for (double tol : {1e-6, 1e-3}) {
    CompressionStats st;
    auto c = std::make_shared<const Compliance>(m.c64->Compressed(m.block.mesh, {.tolerance = tol, .leaf_nodes = 16}, &st));
    EXPECT_EQ(c->storage(), ComplianceStorage::kCompressed);
    EXPECT_EQ(c->precision(), Precision::kFloat32);
    EXPECT_EQ(c->data_f32(), nullptr);
    EXPECT_GT(st.low_rank_tiles, 0) << "nothing was compressed: the test would not test it";
    const double packed_f32 = 4.0 * 9.0 * m.c64->num_nodes() * (m.c64->num_nodes() + 1) / 2;
    EXPECT_LT(static_cast<double>(c->storage_bytes()), packed_f32);
    if (previous_bytes > 0.0) {
      EXPECT_LT(static_cast<double>(c->storage_bytes()), previous_bytes);
    }
    previous_bytes = static_cast<double>(c->storage_bytes());
    RecordProperty("bytes_per_N2_tol_" + test::Sci(tol),
                   test::Sci(static_cast<double>(c->storage_bytes()) / (m.c64->num_nodes() * double(m.c64->num_nodes()))));
    SurfaceField field(c);
    EXPECT_EQ(field.uses_simd(), detail::BestIsa() != detail::Isa::kPortable);
    std::mt19937 rng(5);
    double worst = 0.0;
    for (int trial = 0; trial < 6; ++trial) {
      const Errors e = Compare(m, c, field, test::RandomContacts(*c, 1 + trial, rng));
      worst = std::max({worst, e.force, e.field});
    }
    RecordProperty("worst_rel_error_tol_" + test::Sci(tol), test::Sci(worst));
    EXPECT_LT(worst, 100 * tol + 1e-5) << "tolerance " << tol;
  }
}

// Every block against the exact one: nodes in one cluster (diagonal tiles, so C_kk of every
// node) are dense float32 copies; in total ||C - C~||_F <= tol ||C||_F (+ float32 rounding).
TEST(CompressedCompliance, BlocksAreExactNearAndWithinToleranceFar) {
  const Model& m = WideModel();
  const double tol = 1e-4;
  const Compliance c = m.c64->Compressed(m.block.mesh, {.tolerance = tol, .leaf_nodes = 16});
  const std::int32_t N = c.num_nodes();
  double err2 = 0.0, norm2 = 0.0;
  for (std::int32_t k = 0; k < N; ++k) {
    const Eigen::Matrix3d exact = m.c64->Block(k, k);
    EXPECT_LT((c.Block(k, k) - exact).norm(), 1e-7 * exact.norm()) << "diagonal block " << k;
    for (std::int32_t n = 0; n < N; ++n) {
      const Eigen::Matrix3d e = m.c64->Block(n, k);
      const Eigen::Matrix3d a = c.Block(n, k);
      EXPECT_EQ(a, c.Block(k, n).transpose());  // symmetric by construction
      err2 += (a - e).squaredNorm();
      norm2 += e.squaredNorm();
    }
  }
  EXPECT_LT(std::sqrt(err2 / norm2), tol * 1.01 + 1e-7);
  EXPECT_GT(std::sqrt(err2 / norm2), 0.0);
}

// The hierarchical partition at two admissibility parameters: the blocks cover every leaf pair
// of the upper triangle exactly once, some low-rank blocks span several leaf tiles (otherwise it
// would be the flat grid), and each block, compared entry by entry with the exact compliance,
// meets ||A - A~||_F <= tol ||A||_F (its checked residual, plus float32 rounding of the factors:
// bound 1.01 tol + 1e-6), dense ones to float32 (1e-6).
// With weak admissibility (touching pairs tried too) the same holds, and it never stores more.
// Diagonal tiles are stored as their upper triangle: the dense bytes are exactly 3 m (3 m + 1) / 2
// floats per diagonal tile plus 9 m n per dense off-diagonal tile.
TEST(CompressedCompliance, HierarchicalBlocksWithinToleranceOfExact) {
  const Model& m = WideModel();
  const double tol = 1e-4;
  const std::int32_t N = m.c64->num_nodes();
  std::size_t strong_bytes = 0;
  for (const auto& [eta, weak] : {std::pair{0.7, false}, std::pair{3.0, false}, std::pair{3.0, true}}) {
    CompressionStats st;
    CompressionOptions o{.tolerance = tol, .leaf_nodes = 16, .eta = eta};
    o.weak_admissibility = weak;
    const Compliance c = m.c64->Compressed(m.block.mesh, o, &st);
    const detail::CompressedBlocks& h = *c.compressed();
    const auto slot = h.slot_of_pos();
    std::int64_t covered = 0, multi_tile = 0, low_rank = 0, dense_floats = 0;
    for (const detail::CompressedBlockInfo& b : h.blocks()) {
      ASSERT_TRUE(b.row_end <= b.col_begin || (b.row_begin == b.col_begin && b.row_end == b.col_end));
      const bool diagonal = b.row_begin == b.col_begin;
      covered += diagonal ? std::int64_t{b.row_end - b.row_begin} * (b.row_end - b.row_begin + 1) / 2
                          : std::int64_t{b.row_end - b.row_begin} * (b.col_end - b.col_begin);
      const std::int64_t rows = 3 * std::int64_t{b.row_end - b.row_begin}, cols = 3 * std::int64_t{b.col_end - b.col_begin};
      if (b.rank < 0) dense_floats += diagonal ? rows * (rows + 1) / 2 : rows * cols;
      double err2 = 0.0, norm2 = 0.0;
      for (std::int32_t q = b.col_begin; q < b.col_end; ++q)
        for (std::int32_t p = b.row_begin; p < b.row_end; ++p) {
          const Eigen::Matrix3d e = m.c64->Block(slot[p], slot[q]);
          err2 += (c.Block(slot[p], slot[q]) - e).squaredNorm();
          norm2 += e.squaredNorm();
        }
      const double rel = std::sqrt(err2 / norm2);
      if (b.rank < 0) {
        EXPECT_LT(rel, 1e-6) << "dense block at " << b.row_begin << ", " << b.col_begin;
      } else {
        ++low_rank;
        if (b.row_end - b.row_begin > 16 || b.col_end - b.col_begin > 16) ++multi_tile;
        EXPECT_LT(rel, 1.01 * tol + 1e-6) << "eta " << eta << " block rows " << b.row_begin << ".." << b.row_end
                                          << " cols " << b.col_begin << ".." << b.col_end << " rank " << b.rank;
      }
    }
    EXPECT_EQ(covered, std::int64_t{N} * (N + 1) / 2) << "the blocks must tile the upper triangle once";
    EXPECT_EQ(low_rank, st.low_rank_blocks);
    EXPECT_EQ(st.dense_bytes, 4 * dense_floats) << "diagonal tiles must be stored as their upper triangle";
    EXPECT_GT(multi_tile, 0) << "eta " << eta << ": no block spans more than one leaf pair";
    EXPECT_GT(st.largest_block_entries, 48 * 48);
    if (weak) {
      EXPECT_LE(c.storage_bytes(), strong_bytes) << "weak admissibility only adds candidates";
    } else {
      strong_bytes = c.storage_bytes();
    }
    RecordProperty("bytes_per_N2_eta_" + test::Sci(eta) + (weak ? "_weak" : ""),
                   test::Sci(static_cast<double>(c.storage_bytes()) / (double(N) * N)));
  }
}

// Apply (every instruction set this CPU has, and portable) against the sum of Block() in double:
// the kernels read the packed diagonal tiles, dense tiles (both orientations) and factor views
// on their own, so agreeing with each other is not enough. Loads on the first, a middle and the
// last node of each leaf (the three cases of a column of a packed symmetric tile). Bound 1e-6
// (float sums in another order).
TEST(CompressedCompliance, ApplyMatchesBlocks) {
  const Model& m = WideModel();
  // Leaves of 6 and 11-12 nodes: 18 and 33-36 rows, so every vector width and tail of the kernels runs.
  for (const auto& [leaf, factors] : {std::pair{16, Precision::kFloat32}, std::pair{16, Precision::kFloat16},
                                      std::pair{8, Precision::kFloat16}}) {
    CompressionOptions o{.tolerance = 1e-3, .leaf_nodes = leaf};
    o.factor_precision = factors;
    CompressionStats st;
    const Compliance c = m.c64->Compressed(m.block.mesh, o, &st);
    EXPECT_EQ(st.half_blocks > 0, factors == Precision::kFloat16);
    const detail::CompressedBlocks& h = *c.compressed();
    const std::int32_t N = c.num_nodes();
    const auto slot = h.slot_of_pos();
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> f(-1.0, 1.0);
    std::vector<NodeLoad> loads;
    for (const detail::CompressedBlockInfo& b : h.blocks()) {
      if (b.row_begin != b.col_begin) continue;  // one diagonal block per leaf
      for (std::int32_t p : {b.row_begin, (b.row_begin + b.row_end) / 2, b.row_end - 1}) {
        loads.push_back({slot[p], {f(rng), f(rng), f(rng)}});
      }
    }
    ASSERT_GT(loads.size(), 60u);
    std::vector<Eigen::Vector3d> ref(static_cast<std::size_t>(N), Eigen::Vector3d::Zero()), got(ref.size());
    for (std::int32_t n = 0; n < N; ++n)
      for (const NodeLoad& l : loads) ref[n] += c.Block(n, l.slot) * Eigen::Vector3d(l.f_N[0], l.f_N[1], l.f_N[2]);
    std::vector<float> scratch(h.scratch_floats());
    for (detail::Isa isa : {detail::Isa::kPortable, detail::Isa::kAvx2, detail::Isa::kAvx512}) {
      if (static_cast<int>(isa) > static_cast<int>(detail::BestIsa())) continue;
      h.Apply(loads, got.data(), scratch.data(), isa);
      EXPECT_LT(test::RelError(got, ref), 1e-6) << detail::IsaName(isa) << " leaf " << leaf << " factors " << static_cast<int>(factors);
    }
  }
}

// float16 factors (opt-in): the rounding is part of the checked residual, so every low-rank block
// read back through Block() meets ||A - A~||_F <= tol ||A||_F as computed (bound tol (1 + 1e-9):
// the same products in double), at tolerance 1e-3 most blocks are float16 and the store is
// smaller than with float32 factors; at 1e-6 float16 cannot meet the tolerance, every block
// falls back to float32, and the store is no larger. Forces and field against the direct solve
// as for float32 (100 tol + 1e-5).
TEST(CompressedCompliance, Float16FactorsWithinToleranceOfExact) {
  const Model& m = WideModel();
  for (double tol : {1e-3, 1e-6}) {
    CompressionOptions o{.tolerance = tol, .leaf_nodes = 16};
    CompressionStats st32, st16;
    const Compliance c32 = m.c64->Compressed(m.block.mesh, o, &st32);
    o.factor_precision = Precision::kFloat16;
    auto c16 = std::make_shared<const Compliance>(m.c64->Compressed(m.block.mesh, o, &st16));
    EXPECT_NE(c16->input_hash(), c32.input_hash());
    const detail::CompressedBlocks& h = *c16->compressed();
    const auto slot = h.slot_of_pos();
    std::int64_t low_rank = 0;
    for (const detail::CompressedBlockInfo& b : h.blocks()) {
      if (b.rank < 0) continue;
      ++low_rank;
      double err2 = 0.0, norm2 = 0.0;
      for (std::int32_t q = b.col_begin; q < b.col_end; ++q)
        for (std::int32_t p = b.row_begin; p < b.row_end; ++p) {
          const Eigen::Matrix3d e = m.c64->Block(slot[p], slot[q]);
          err2 += (c16->Block(slot[p], slot[q]) - e).squaredNorm();
          norm2 += e.squaredNorm();
        }
      EXPECT_LE(std::sqrt(err2 / norm2), tol * (1.0 + 1e-9)) << "block rows " << b.row_begin << ".." << b.row_end
                                                             << " cols " << b.col_begin << ".." << b.col_end;
    }
    EXPECT_EQ(low_rank, st16.low_rank_blocks);
    RecordProperty("float16_over_float32_bytes_tol_" + test::Sci(tol),
                   test::Sci(static_cast<double>(c16->storage_bytes()) / static_cast<double>(c32.storage_bytes())));
    if (tol > 1e-4) {
      EXPECT_GT(st16.half_blocks, st16.low_rank_blocks / 2);
      EXPECT_LT(c16->storage_bytes(), c32.storage_bytes() * 3 / 4);
      SurfaceField field(c16);
      std::mt19937 rng(6);
      double worst = 0.0;
      for (int trial = 0; trial < 4; ++trial) {
        const Errors e = Compare(m, c16, field, test::RandomContacts(*c16, 1 + trial, rng));
        worst = std::max({worst, e.force, e.field});
      }
      EXPECT_LT(worst, 100 * tol + 1e-5);
      EXPECT_GT(worst, 0.0);
    } else {
      EXPECT_EQ(st16.half_blocks, 0);
      EXPECT_LE(c16->storage_bytes(), c32.storage_bytes());
    }
  }
}

// Every pair of nodes in one leaf (the packed diagonal tiles, both orders) against the exact
// compliance, to float32 (1e-7 relative to the diagonal blocks).
TEST(CompressedCompliance, DiagonalTilesMatchExact) {
  const Model& m = WideModel();
  const Compliance c = m.c64->Compressed(m.block.mesh, {.tolerance = 1e-3, .leaf_nodes = 16});
  const detail::CompressedBlocks& h = *c.compressed();
  const auto slot = h.slot_of_pos();
  int checked = 0;
  for (const detail::CompressedBlockInfo& b : h.blocks()) {
    if (b.row_begin != b.col_begin) continue;
    for (std::int32_t p = b.row_begin; p < b.row_end; ++p)
      for (std::int32_t q = b.row_begin; q < b.row_end; ++q) {
        const Eigen::Matrix3d e = m.c64->Block(slot[p], slot[q]);
        const double scale = m.c64->Block(slot[p], slot[p]).norm();
        ASSERT_LT((c.Block(slot[p], slot[q]) - e).norm(), 1e-7 * scale) << "positions " << p << ", " << q;
        ++checked;
      }
  }
  EXPECT_GT(checked, c.num_nodes());
}

// On the same mid-size model (750 nodes) the hierarchical partition stores strictly less than
// the flat grid of leaf tiles at the same tolerance (it tries every leaf pair the flat one tries,
// and merges far ones into blocks whose factors are shared).
TEST(CompressedCompliance, HierarchicalIsSmallerThanFlat) {
  const Model& m = WideModel();
  for (double tol : {1e-3, 1e-5}) {
    CompressionStats flat_st, h_st;
    const Compliance flat =
        m.c64->Compressed(m.block.mesh, {.tolerance = tol, .leaf_nodes = 16, .hierarchical = false}, &flat_st);
    const Compliance h = m.c64->Compressed(m.block.mesh, {.tolerance = tol, .leaf_nodes = 16}, &h_st);
    EXPECT_LT(h.storage_bytes(), flat.storage_bytes()) << "tolerance " << tol;
    EXPECT_LE(flat_st.largest_block_entries, 48 * 48) << "flat blocks are single leaf tiles";
    EXPECT_LT(h_st.factor_bytes, flat_st.factor_bytes);
    RecordProperty("hierarchical_over_flat_tol_" + test::Sci(tol),
                   test::Sci(static_cast<double>(h.storage_bytes()) / static_cast<double>(flat.storage_bytes())));
  }
}

// The column copy: float32 (rounding only, 6e-8 per entry; bound 1e-5 as for float32 storage),
// float16 (11-bit mantissa relative to the largest entry of each 16-node chunk: 2.4e-4 per
// entry, measured ~2e-4 on the field; bound 2e-3) and int16 (entries to 1/65534 of the largest
// in their chunk, each load to 1/43690 of its largest component; measured 7.5e-5, bound 2e-3
// like float16). Forces come from
// ContactSolver on the exact compliance, so they stay exact whatever the field storage.
TEST(SurfaceFieldColumns, Float32Float16AndInt16MatchDirectSparseSolve) {
  const Model& m = WideModel();
  SurfaceField f32(m.c64, {.layout = SurfaceFieldLayout::kColumns, .precision = Precision::kFloat32});
  SurfaceField f16(m.c64, {.layout = SurfaceFieldLayout::kColumns, .precision = Precision::kFloat16});
  SurfaceField i16(m.c64, {.layout = SurfaceFieldLayout::kColumns, .precision = Precision::kInt16});
  EXPECT_LT(f16.storage_bytes(), f32.storage_bytes() * 0.6);
  EXPECT_LT(i16.storage_bytes(), f32.storage_bytes() * 0.6);
  std::mt19937 rng(9);
  double worst32 = 0.0, worst16 = 0.0, worst_i16 = 0.0, force = 0.0;
  for (int trial = 0; trial < 6; ++trial) {
    const auto in = test::RandomContacts(*m.c64, 1 + trial, rng);
    const Errors a = Compare(m, m.c64, f32, in), b = Compare(m, m.c64, f16, in), c = Compare(m, m.c64, i16, in);
    worst32 = std::max({worst32, a.field});
    worst16 = std::max({worst16, b.field});
    worst_i16 = std::max({worst_i16, c.field});
    force = std::max({force, a.force, b.force, c.force});
  }
  RecordProperty("float16_field_rel_error", test::Sci(worst16));
  RecordProperty("int16_field_rel_error", test::Sci(worst_i16));
  EXPECT_LT(force, 1e-9);
  EXPECT_LT(worst32, 1e-5);
  EXPECT_LT(worst16, 2e-3);
  EXPECT_LT(worst_i16, 2e-3);
  EXPECT_GT(worst16, worst32);  // float16 really is the coarser one
  EXPECT_GT(worst_i16, worst32);
}

// int16 columns hold each entry to half a step of its chunk's scale (the largest entry of its
// 16 rows of that column / 32767), and one column's integer sums do not overflow with every
// entry and load at its extreme: each lane is then 3 * 32767 * 21845, 99.995% of 2^31 - 1.
TEST(SurfaceFieldColumns, Int16RoundingAndNoOverflow) {
  const Model& m = WideModel();
  const auto N = static_cast<std::int32_t>(m.c64->num_nodes());
  detail::PlanarColumns cols;
  cols.Build(N, N, detail::PlanarType::kInt16, [&](std::int32_t n, std::int32_t k) { return m.c64->Block(n, k); });
  EXPECT_EQ(cols.column_scalars() % 32, 0) << "int16 columns must be 64-byte multiples";
  for (std::int32_t k : {0, N / 3, N - 1}) {
    for (std::int32_t n0 = 0; n0 < N; n0 += detail::kChunkNodes) {
      double amax = 0.0;
      for (std::int32_t n = n0; n < std::min(N, n0 + detail::kChunkNodes); ++n) {
        amax = std::max(amax, m.c64->Block(n, k).cwiseAbs().maxCoeff());
      }
      for (std::int32_t n = n0; n < std::min(N, n0 + detail::kChunkNodes); ++n) {
        const double err = (cols.Get(n, k) - m.c64->Block(n, k)).cwiseAbs().maxCoeff();
        ASSERT_LE(err, 0.5 * amax / 32767.0 * (1.0 + 1e-6)) << "block (" << n << ", " << k << ")";
      }
    }
  }
  // Extreme entries: every block +-1 (all scales 1/32767, all q = +-32767); loads that make every
  // product positive in lane 0 and, after the sign flips, the most negative sum in the others.
  detail::PlanarColumns extreme;
  extreme.Build(20, 8, detail::PlanarType::kInt16, [](std::int32_t n, std::int32_t k) {
    return Eigen::Matrix3d::Constant((n + k) % 2 == 0 ? 1.0 : -1.0);
  });
  std::vector<std::int32_t> k(8);
  std::vector<Eigen::Vector3d> x(8);
  for (int j = 0; j < 8; ++j) {
    k[static_cast<std::size_t>(j)] = j;
    x[static_cast<std::size_t>(j)] = Eigen::Vector3d::Constant(j % 2 == 0 ? 1.0 : -1.0);
  }
  for (detail::Isa isa : {detail::Isa::kPortable, detail::Isa::kAvx2, detail::Isa::kAvx512}) {
    if (static_cast<int>(isa) > static_cast<int>(detail::BestIsa())) continue;
    std::vector<Eigen::Vector3d> out(20);
    extreme.SumColumns(k, x, out.data(), isa);
    for (std::int32_t n = 0; n < 20; ++n) {
      // Exactly +-24 up to the float scaling (a wrapped int32 sum would flip the sign).
      EXPECT_NEAR(out[static_cast<std::size_t>(n)].x(), n % 2 == 0 ? 24.0 : -24.0, 24.0 * 1e-6)
          << detail::IsaName(isa) << " node " << n;
    }
  }
}

// Each instruction set's kernel against the portable one, for the column copy (float32,
// float16), the compressed storage and the paper's T^d: same sums, float accumulation in a
// different order (bound 1e-6). More loads than one kernel group (32) and an invalid slot.
TEST(SurfaceFieldKernels, EveryInstructionSetAgreesWithPortable) {
  const Model& m = WideModel();
  auto cc = std::make_shared<const Compliance>(m.c64->Compressed(m.block.mesh, {.tolerance = 1e-5, .leaf_nodes = 16}));
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::int32_t> slot(0, m.c64->num_nodes() - 1);
  std::uniform_real_distribution<double> f(-1.0, 1.0);
  std::vector<NodeLoad> loads;
  for (int i = 0; i < 40; ++i) loads.push_back({slot(rng), {f(rng), f(rng), f(rng)}});
  loads.push_back({m.c64->num_nodes() + 3, {1, 1, 1}});
  loads.push_back({-1, {1, 1, 1}});
  const auto N = static_cast<std::size_t>(m.c64->num_nodes());
  for (int kind = 0; kind < 4; ++kind) {
    SurfaceFieldOptions o{.layout = kind == 2 ? SurfaceFieldLayout::kCompliance : SurfaceFieldLayout::kColumns,
                          .precision = kind == 1   ? Precision::kFloat16
                                       : kind == 3 ? Precision::kInt16
                                                   : Precision::kFloat32};
    auto c = kind == 2 ? cc : m.c64;
    SurfaceField simd(c, o);
    o.allow_simd = false;
    SurfaceField portable(c, o);
    EXPECT_STREQ(portable.kernel_name(), "portable");
    std::vector<Eigen::Vector3d> a(N), b(N);
    ASSERT_TRUE(simd.Evaluate(loads, a));
    ASSERT_TRUE(portable.Evaluate(loads, b));
    EXPECT_LT(test::RelError(a, b), 1e-6) << "kind " << kind << " kernel " << simd.kernel_name();
    EXPECT_GT(b[0].norm() + b[N - 1].norm(), 0.0);
    std::vector<Eigen::Vector3d> wrong(N - 1);
    EXPECT_FALSE(simd.Evaluate(loads, wrong));
  }
  // The intrinsics paths that this CPU has, called directly (int16: the integer sums are exact,
  // so only the float scaling and the double accumulation over groups may differ).
  for (detail::PlanarType type : {detail::PlanarType::kFloat16, detail::PlanarType::kInt16}) {
    detail::PlanarColumns cols;
    cols.Build(static_cast<std::int32_t>(N), static_cast<std::int32_t>(N), type,
               [&](std::int32_t n, std::int32_t k) { return m.c64->Block(n, k); });
    std::vector<Eigen::Vector3d> ref(N), got(N);
    cols.SumColumns(loads, ref.data(), detail::Isa::kPortable);
    for (detail::Isa isa : {detail::Isa::kAvx2, detail::Isa::kAvx512}) {
      if (static_cast<int>(isa) > static_cast<int>(detail::BestIsa())) continue;
      cols.SumColumns(loads, got.data(), isa);
      EXPECT_LT(test::RelError(got, ref), type == detail::PlanarType::kInt16 ? 1e-12 : 1e-6) << detail::IsaName(isa);
    }
  }
}

// The paper's form with float16 T^d: the correction matrix A is read from T^d too, so forces
// and field both carry the half-precision error (bound 5e-3, measured ~5e-4); float32 T^d
// stays at float32 accuracy (1e-5).
TEST(ElementaryDisplacement, Float16TablesAgainstFloat64) {
  const Model& m = WideModel();
  auto t64 = std::make_shared<ElementaryDisplacementTensors>(
      ElementaryDisplacementTensors::FromCompliance(*m.c64, Precision::kFloat64));
  auto t16 = std::make_shared<ElementaryDisplacementTensors>(
      ElementaryDisplacementTensors::FromCompliance(*m.c64, Precision::kFloat16));
  EXPECT_LT(t16->storage_bytes(), t64->storage_bytes() / 3);
  ElementaryDisplacementSolver s64(t64, 8), s16(t16, 8);
  std::mt19937 rng(4);
  std::vector<Eigen::Vector3d> u64(static_cast<std::size_t>(m.c64->num_nodes())), u16(u64.size());
  for (int trial = 0; trial < 5; ++trial) {
    const auto in = test::RandomContacts(*m.c64, 1 + trial, rng);
    ASSERT_EQ(s64.Solve(in), StepStatus::kOk);
    ASSERT_EQ(s16.Solve(in), StepStatus::kOk);
    std::vector<Eigen::Vector3d> f64(s64.forces_N().begin(), s64.forces_N().end()),
        f16(s16.forces_N().begin(), s16.forces_N().end());
    ASSERT_TRUE(s64.SurfaceDisplacements(u64));
    ASSERT_TRUE(s16.SurfaceDisplacements(u16));
    EXPECT_LT(test::RelError(f16, f64), 5e-3);
    EXPECT_LT(test::RelError(u16, u64), 5e-3);
    EXPECT_GT(test::RelError(u16, u64), 0.0);
  }
}

TEST(Float16, ConversionRoundsToNearestAndRoundTrips) {
  EXPECT_EQ(detail::FloatToHalf(1.0f), 0x3C00);
  EXPECT_EQ(detail::FloatToHalf(-2.0f), 0xC000);
  EXPECT_EQ(detail::FloatToHalf(65504.0f), 0x7BFF);
  EXPECT_EQ(detail::FloatToHalf(65520.0f), 0x7C00);  // rounds to infinity
  EXPECT_EQ(detail::FloatToHalf(std::ldexp(1.0f, -24)), 0x0001);
  EXPECT_EQ(detail::FloatToHalf(0.1f), 0x2E66);
  EXPECT_EQ(detail::FloatToHalf(1.0f + std::ldexp(1.0f, -11)), 0x3C00);  // tie: to even
  EXPECT_EQ(detail::FloatToHalf(1.0f + 3 * std::ldexp(1.0f, -11)), 0x3C02);
  int checked = 0;
  for (std::uint32_t h = 0; h < 0x10000; ++h) {
    if ((h & 0x7C00) == 0x7C00 && (h & 0x3FF) != 0) continue;  // NaN
    ASSERT_EQ(detail::FloatToHalf(detail::HalfToFloat(static_cast<std::uint16_t>(h))), h) << std::hex << h;
    ++checked;
  }
  EXPECT_EQ(checked, 0x10000 - 2 * 1023);
}

TEST(CompressedCompliance, BadInputsAreRejected) {
  const Model& m = WideModel();
  EXPECT_THROW((void)m.c64->Compressed(m.block.mesh, {.tolerance = 0.0}), InputError);
  EXPECT_THROW((void)m.c64->Compressed(m.block.mesh, {.tolerance = 1.5}), InputError);
  EXPECT_THROW((void)m.c64->Compressed(m.block.mesh, {.tolerance = 1e-4, .leaf_nodes = 2}), InputError);
  for (double eta : {0.0, -1.0, 101.0, std::nan("")}) {
    try {
      (void)m.c64->Compressed(m.block.mesh, {.tolerance = 1e-4, .eta = eta});
      ADD_FAILURE() << "eta " << eta << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("eta"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW((void)m.c64->Compressed(m.block.mesh, {.tolerance = 1e-4, .max_block_entries = 0}), InputError);
  for (Precision p : {Precision::kFloat64, static_cast<Precision>(3)}) {
    CompressionOptions o{.tolerance = 1e-4};
    o.factor_precision = p;
    EXPECT_THROW((void)m.c64->Compressed(m.block.mesh, o), InputError);
  }
  const TetMesh other = MakeBoxMesh({0.1, 0.1, 0.1}, {2, 2, 2});
  EXPECT_THROW((void)m.c64->Compressed(other, {}), InputError);
  const Compliance c = m.c64->Compressed(m.block.mesh, {.tolerance = 1e-3, .leaf_nodes = 16});
  EXPECT_THROW((void)c.Compressed(m.block.mesh, {}), InputError);
  EXPECT_THROW((void)c.ConvertedTo(Precision::kFloat64), InputError);
  EXPECT_THROW((void)m.c64->ConvertedTo(Precision::kFloat16), InputError);
  EXPECT_NE(c.input_hash(), m.c64->input_hash());
  test::TempDir dir;
  EXPECT_THROW(c.Save(dir.path() / "x.compliance"), CacheError);
  EXPECT_THROW(SurfaceField(m.c64, {.layout = SurfaceFieldLayout::kColumns, .precision = static_cast<Precision>(3)}),
               InputError);
  EXPECT_THROW((void)ElementaryDisplacementTensors::FromCompliance(*m.c64, static_cast<Precision>(3)), InputError);
}

}  // namespace
}  // namespace handshare::fem
