// fem_compress_sweep: storage of the compressed compliance (Compliance::Compressed) on the cubes
// of fem_bench (same meshes, material and fixed bottom), loaded read-only from fem_bench's cache
// of float64 compliances; one row per cube x tolerance x leaf size x admissibility.
//
//   fem_compress_sweep [--cache-dir DIR] [--cubes 12,21] [--tols 1e-3,1e-5] [--leaves 32]
//                      [--weak 0,1] [--f16 0,1] [--check] [--contacts] [--time]
//
// Columns: bytes / N^2 in total and split into dense tiles, factors and tables; build seconds;
// with --check also ||C - C~||_F / ||C||_F over all blocks and the largest relative error of a
// diagonal block C_kk (both against the loaded exact compliance); with --contacts the worst
// relative force and surface-field errors of ContactSolver over 32 sets of 5 random contacts;
// with --time the median microseconds of a force-only step and of a step with the surface field.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <memory>
#include <random>

#include "handshare/fem/assembly.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_solver.hpp"

#include "rel_error.hpp"

namespace {

using namespace handshare::fem;

template <class T>
std::vector<T> List(const std::string& s) {
  std::vector<T> v;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) v.push_back(static_cast<T>(std::stod(item)));
  return v;
}

using bench::RelError;

// Median time (us) of ContactSolver::Solve (forces only) and of Solve + SurfaceDisplacements on
// the compressed store, cycling through 32 sets of 5 random contacts.
std::pair<double, double> StepTimes(const std::shared_ptr<const Compliance>& c) {
  std::mt19937 rng(12);
  std::uniform_int_distribution<std::int32_t> slot(0, c->num_nodes() - 1);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  std::vector<std::vector<ContactInput>> sets(32);
  for (auto& in : sets) {
    while (in.size() < 5) {
      const std::int32_t node = c->nodes()[slot(rng)];
      bool dup = false;
      for (const auto& x : in) dup = dup || x.node == node;
      if (!dup) in.push_back({node, {u(rng), u(rng), u(rng)}});
    }
  }
  ContactSolver s(c, {.max_contacts = 5});
  std::vector<Eigen::Vector3d> field(static_cast<std::size_t>(c->num_nodes()));
  auto median = [&](bool with_field) {
    std::vector<double> t;
    for (int i = 0; i < 2000; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      s.Solve(sets[static_cast<std::size_t>(i % 32)]);
      if (with_field) s.SurfaceDisplacements(field);
      t.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    }
    std::nth_element(t.begin(), t.begin() + t.size() / 2, t.end());
    return t[t.size() / 2];
  };
  return {median(false), median(true)};
}

// Worst relative error of forces and of the surface field over 32 sets of 5 random contacts
// (fem_bench's kind: distinct random surface nodes, displacements up to 1 mm), ContactSolver on
// the compressed store against ContactSolver on the exact float64 compliance (which matches the
// direct sparse solve to 1e-15).
std::pair<double, double> ContactErrors(const std::shared_ptr<const Compliance>& exact,
                                        const std::shared_ptr<const Compliance>& c) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::int32_t> slot(0, exact->num_nodes() - 1);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  ContactSolver a(exact, {.max_contacts = 5}), b(c, {.max_contacts = 5});
  std::vector<Eigen::Vector3d> fa(static_cast<std::size_t>(exact->num_nodes())), fb(fa.size());
  double force = 0.0, field = 0.0;
  for (int set = 0; set < 32; ++set) {
    std::vector<ContactInput> in;
    while (in.size() < 5) {
      const std::int32_t node = exact->nodes()[slot(rng)];
      bool dup = false;
      for (const auto& x : in) dup = dup || x.node == node;
      if (!dup) in.push_back({node, {u(rng), u(rng), u(rng)}});
    }
    a.Solve(in);
    b.Solve(in);
    force = std::max(force, RelError({b.forces_N().begin(), b.forces_N().end()}, {a.forces_N().begin(), a.forces_N().end()}));
    a.SurfaceDisplacements(fa);
    b.SurfaceDisplacements(fb);
    field = std::max(field, RelError(fb, fa));
  }
  return {force, field};
}

}  // namespace

int main(int argc, char** argv) {
  std::filesystem::path dir = "fem_bench_cache";
  std::vector<int> cubes{12, 21}, leaves{32}, weak{0}, halves{0};
  std::vector<double> tols{1e-3, 1e-5};
  bool check = false, contacts = false, timing = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--cache-dir" && has) dir = argv[++i];
    else if (a == "--cubes" && has) cubes = List<int>(argv[++i]);
    else if (a == "--tols" && has) tols = List<double>(argv[++i]);
    else if (a == "--leaves" && has) leaves = List<int>(argv[++i]);
    else if (a == "--weak" && has) weak = List<int>(argv[++i]);
    else if (a == "--f16" && has) halves = List<int>(argv[++i]);
    else if (a == "--check") check = true;
    else if (a == "--contacts") contacts = true;
    else if (a == "--time") timing = true;
    else {
      std::fprintf(stderr, "usage: %s [--cache-dir DIR] [--cubes 12,21] [--tols 1e-3,1e-5] [--leaves 32] "
                   "[--weak 0,1] [--f16 0,1] [--check] [--contacts] [--time]\n", argv[0]);
      return 2;
    }
  }
  const Material mat{1e4, 0.3};  // as fem_bench
  std::printf("cube,N,tol,leaf,weak,f16,bytes_per_N2,dense,factors,tables,low_rank_blocks,f16_blocks,mean_rank,seconds,rel_error,diag_error,force_error,field_error,force_us,full_us\n");
  for (int n : cubes) {
    // fem_bench's MakeCube(n).
    const TetMesh mesh = MakeBoxMesh({0.1, 0.1, 0.1}, {n - 1, n - 1, n - 1});
    const std::vector<std::int32_t> fixed = NodesOnPlane(mesh, 2, 0.0);
    const auto exact_ptr = std::make_shared<const Compliance>(Compliance::Load(dir / ("cube" + std::to_string(n) + ".f64.compliance"),
                                              Compliance::InputHash(mesh, mat, fixed, {})));
    const Compliance& exact = *exact_ptr;
    const std::int32_t N = exact.num_nodes();
    const double n2 = double(N) * N;
    for (double tol : tols)
      for (int leaf : leaves)
        for (int w : weak)
        for (int f16 : halves) {
          CompressionOptions o{.tolerance = tol, .leaf_nodes = leaf};
          o.weak_admissibility = w != 0;
          o.factor_precision = f16 != 0 ? Precision::kFloat16 : Precision::kFloat32;
          CompressionStats st;
          const auto c_ptr = std::make_shared<const Compliance>(exact.Compressed(mesh, o, &st));
          const Compliance& c = *c_ptr;
          const auto [force, field] = contacts ? ContactErrors(exact_ptr, c_ptr) : std::pair{-1.0, -1.0};
          const auto [force_us, full_us] = timing ? StepTimes(c_ptr) : std::pair{-1.0, -1.0};
          double rel = -1.0, diag = -1.0;
          if (check) {
            double e2 = 0.0, a2 = 0.0;
            diag = 0.0;
            for (std::int32_t k = 0; k < N; ++k) {
              for (std::int32_t i = 0; i <= k; ++i) {
                const Eigen::Matrix3d e = exact.Block(i, k);
                const double d2 = (c.Block(i, k) - e).squaredNorm(), w2 = i == k ? 1.0 : 2.0;
                e2 += w2 * d2;
                a2 += w2 * e.squaredNorm();
                if (i == k) diag = std::max(diag, std::sqrt(d2) / e.norm());
              }
            }
            rel = std::sqrt(e2 / a2);
          }
          std::printf("%d,%d,%g,%d,%d,%d,%.3f,%.3f,%.3f,%.3f,%lld,%lld,%.1f,%.2f,%.3g,%.3g,%.3g,%.3g,%.3g,%.3g\n", n, N, tol, leaf, w, f16,
                      double(c.storage_bytes()) / n2, double(st.dense_bytes) / n2, double(st.factor_bytes) / n2,
                      double(st.table_bytes) / n2, static_cast<long long>(st.low_rank_blocks), static_cast<long long>(st.half_blocks), st.mean_rank,
                      st.seconds, rel, diag, force, field, force_us, full_us);
          std::fflush(stdout);
        }
  }
  return 0;
}
