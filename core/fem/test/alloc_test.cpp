// Real-time rule: Solve() and the displacement queries never touch the heap. This binary
// replaces the global operator new/delete with counting versions; a test fails if any
// allocation happens while counting is on.

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_patch.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/elementary_displacement.hpp"
#include "handshare/fem/surface_field.hpp"
#include "test_util.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};

void* CountedAlloc(std::size_t n, std::size_t align) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (n == 0) n = 1;
  void* p = align > alignof(std::max_align_t) ? std::aligned_alloc(align, (n + align - 1) / align * align)
                                              : std::malloc(n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
}  // namespace

void* operator new(std::size_t n) { return CountedAlloc(n, 0); }
void* operator new[](std::size_t n) { return CountedAlloc(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) { return CountedAlloc(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return CountedAlloc(n, static_cast<std::size_t>(a)); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return CountedAlloc(n, 0);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return CountedAlloc(n, 0);
  } catch (...) {
    return nullptr;
  }
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace handshare::fem {
namespace {

// Counts heap allocations in a scope.
class AllocationCounter {
 public:
  AllocationCounter() {
    g_allocations = 0;
    g_counting = true;
  }
  ~AllocationCounter() { g_counting = false; }
  long count() const { return g_allocations.load(); }
};

TEST(NoAllocation, CounterSeesAllocations) {
  // The detector itself must work, or the other tests prove nothing.
  long n = 0;
  {
    AllocationCounter counter;
    std::vector<double> v(100);
    v[3] = 1.0;
    n = counter.count();
  }
  EXPECT_GT(n, 0);
}

TEST(NoAllocation, SolversAndPatchQueries) {
  const test::Block b = test::MakeFixedBottomBox({0.03, 0.03, 0.015}, {6, 6, 3});
  const Material mat{1e4, 0.3};
  auto c64 = std::make_shared<Compliance>(Compliance::Precompute(b.mesh, mat, b.fixed, {}));
  ComplianceOptions o32;
  o32.precision = Precision::kFloat32;
  auto c32 = std::make_shared<Compliance>(Compliance::Precompute(b.mesh, mat, b.fixed, o32));
  auto T = std::make_shared<ElementaryDisplacementTensors>(
      ElementaryDisplacementTensors::FromCompliance(*c64, Precision::kFloat32));
  const Surface surface = ExtractSurface(b.mesh);
  const ContactPatchFinder finder(b.mesh, surface, *c64);

  // Everything the steps need, allocated before counting starts (the Init of the rules).
  ContactSolver plain(c64, {.max_contacts = 16});
  ContactSolver push(c32, {.max_contacts = 16, .coupling_stiffness_N_per_m = 200.0, .push_only = true});
  ElementaryDisplacementSolver paper(T, 16);
  auto T16 = std::make_shared<ElementaryDisplacementTensors>(
      ElementaryDisplacementTensors::FromCompliance(*c64, Precision::kFloat16));
  ElementaryDisplacementSolver paper16(T16, 16);
  auto cc = std::make_shared<const Compliance>(c64->Compressed(b.mesh, {.tolerance = 1e-3, .leaf_nodes = 8}));
  ContactSolver compressed(cc, {.max_contacts = 16, .push_only = true});
  CompressionOptions half_options{.tolerance = 1e-3, .leaf_nodes = 8};
  half_options.factor_precision = Precision::kFloat16;
  CompressionStats half_stats;
  auto cc16 = std::make_shared<const Compliance>(c64->Compressed(b.mesh, half_options, &half_stats));
  ContactSolver compressed16(cc16, {.max_contacts = 16, .push_only = true});
  SurfaceField columns16(c64, {.layout = SurfaceFieldLayout::kColumns, .precision = Precision::kFloat16});
  SurfaceField columns32(c64, {.layout = SurfaceFieldLayout::kColumns, .precision = Precision::kFloat32});
  SurfaceField columns_i16(c64, {.layout = SurfaceFieldLayout::kColumns, .precision = Precision::kInt16});
  std::vector<Eigen::Vector3d> field(c64->num_nodes());
  std::vector<std::int32_t> visible(c64->nodes().begin(), c64->nodes().begin() + 20);
  std::vector<Eigen::Vector3d> visible_u(visible.size());
  std::vector<ContactInput> patch(16);
  const auto top = NodesOnPlane(b.mesh, 2, 0.015);
  std::vector<ContactInput> in = {{top[10], {0, 0, -1e-3}, Eigen::Vector3d::UnitZ()},
                                  {top[11], {1e-4, 0, 1e-3}, Eigen::Vector3d::UnitZ()},
                                  {top[10], {0, 0, -2e-3}, Eigen::Vector3d::UnitZ()},
                                  {b.fixed[0], {0, 0, -1e-3}, Eigen::Vector3d::UnitZ()},
                                  {top[20], {0, 1e-4, -5e-4}, Eigen::Vector3d::UnitZ(), ContactMode::kNormalOnly}};
  std::vector<ContactInput> nan_in = in;
  nan_in[1].u_m.y() = std::nan("");
  const FrictionPatch friction{Eigen::Vector3d::UnitZ(), Eigen::Vector3d(3e-3, 0, 0), 0.5, 0.4, false};
  bool slipped = false;

  long n = 0;
  {
    AllocationCounter counter;
    for (int rep = 0; rep < 3; ++rep) {
      plain.Solve(in);
      plain.SurfaceDisplacements(field);
      plain.Displacements(visible, visible_u);
      push.Solve(in);
      push.SurfaceDisplacements(field);
      paper.Solve(in);
      paper.SurfaceDisplacements(field);
      paper16.Solve(in);
      paper16.SurfaceDisplacements(field);
      compressed.Solve(in);
      compressed.SurfaceDisplacements(field);
      compressed16.Solve(in);
      compressed16.SurfaceDisplacements(field);
      columns16.Evaluate(plain.loads(), field);
      columns32.Evaluate(plain.loads(), field);
      columns_i16.Evaluate(plain.loads(), field);
      plain.Solve(nan_in);
      const PatchResult r = finder.Sphere(b.mesh.positions_m()[top[17]], Eigen::Vector3d::UnitZ(), 0.01, 1e-3,
                                          ContactMode::kNormalOnly, patch);
      push.Solve(std::span(patch.data(), static_cast<std::size_t>(r.count)));
      // The same patch with friction, dragged far enough to slip.
      for (int q = 0; q < r.count; ++q) patch[static_cast<std::size_t>(q)].patch = 0;
      push.Solve(std::span(patch.data(), static_cast<std::size_t>(r.count)), std::span(&friction, 1));
      slipped = slipped || push.patch_states()[0].slipping;
      for (int q = 0; q < r.count; ++q) patch[static_cast<std::size_t>(q)].patch = -1;
      finder.FlatPunch(b.mesh.positions_m()[top[17]], Eigen::Vector3d::UnitZ(), 0.006, 1e-3,
                       ContactMode::kFull3d, std::span(patch.data(), 3));  // truncates
    }
    n = counter.count();
  }
  EXPECT_EQ(n, 0) << "heap allocations in the real-time path";
  // The calls did real work (the test is not vacuous).
  EXPECT_GT(plain.num_unique(), 0);
  EXPECT_TRUE(slipped);
  EXPECT_GT(compressed.num_unique(), 0);
  EXPECT_GT(compressed16.num_unique(), 0);
  EXPECT_GT(half_stats.half_blocks, 0) << "the float16 store has no float16 factors";
  EXPECT_GT(field[0].norm() + field[5].norm(), 0.0);
}

}  // namespace
}  // namespace handshare::fem
