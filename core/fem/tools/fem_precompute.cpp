// fem_precompute MESH LOADCASE.json [--out CACHE] [--float32] [--block NODES]
// Assembles K, factors it once (CHOLMOD), computes the compliance blocks of every free surface
// node with a progress bar and an estimate of the time left, and writes the cache file. An
// existing cache for the same mesh, material and fixed nodes is reused; a stale or corrupt one is
// reported and rebuilt. Only E_Pa, nu, fixed_nodes / fixed_nset of the load case are used.

#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <iostream>
#include <string>

#include "cli_common.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/error.hpp"
#include "handshare/fem/surface_import.hpp"

namespace {

constexpr const char* kUsage =
    "usage: fem_precompute MESH LOADCASE.json [--out CACHE] [--float32] [--block NODES]\n"
    "  writes CACHE (default MESH.compliance): compliance blocks of the free surface nodes\n";

using Clock = std::chrono::steady_clock;

// One-line progress bar on stderr with the time left extrapolated from the solve rate.
class ProgressBar {
 public:
  void operator()(std::int64_t done, std::int64_t total) {
    const auto now = Clock::now();
    if (done == 0) {
      start_ = now;
      started_ = true;
    }
    if (!started_ || (done < total && now - last_ < std::chrono::milliseconds(200))) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double frac = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
    constexpr int kWidth = 40;
    const int filled = static_cast<int>(frac * kWidth);
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar.resize(kWidth, '.');
    char eta[64] = "estimating";
    if (done > 0) std::snprintf(eta, sizeof eta, "~%.0f s left", elapsed / frac - elapsed);
    std::fprintf(stderr, "\r[%s] %5.1f%% %lld/%lld nodes, %.1f s, %s   ", bar.c_str(), 100.0 * frac,
                 static_cast<long long>(done), static_cast<long long>(total), elapsed, eta);
    if (done == total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  Clock::time_point start_{}, last_{};
  bool started_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace handshare::fem;
  if (argc < 3) {
    std::cerr << kUsage;
    return 2;
  }
  return cli::RunMain("fem_precompute", [&] {
    std::string out = std::string(argv[1]) + ".compliance";
    ComplianceOptions options;
    for (int i = 3; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--out" && i + 1 < argc) {
        out = argv[++i];
      } else if (a == "--float32") {
        options.precision = Precision::kFloat32;
      } else if (a == "--float64") {
        options.precision = Precision::kFloat64;
      } else if (a == "--block" && i + 1 < argc) {
        const std::string v = argv[++i];
        char* end = nullptr;
        const long n = std::strtol(v.c_str(), &end, 10);
        if (end == v.c_str() || *end != '\0' || n < 1 || n > 100000) {
          throw InputError("", 0, "--block", "expected a node count in 1..100000, got '" + v + "'");
        }
        options.block_nodes = static_cast<int>(n);
      } else {
        throw InputError("", 0, "argument", "unknown option '" + a + "'\n" + kUsage);
      }
    }
    const auto t0 = Clock::now();
    const TetMesh mesh = ReadVolumeMesh(argv[1]);
    const cli::LoadCase lc = cli::ReadLoadCase(argv[2], mesh, /*require_imposed=*/false);
    std::fprintf(stderr, "mesh %s: %d nodes, %d tetrahedra; E = %g Pa, nu = %g, %zu fixed nodes\n",
                 argv[1], mesh.num_nodes(), mesh.num_tets(), lc.material.E_Pa, lc.material.nu,
                 lc.problem.fixed_nodes.size());
    ProgressBar bar;
    std::string note;
    PrecomputeStats stats;
    const Compliance c = Compliance::LoadOrPrecompute(
        out, mesh, lc.material, lc.problem.fixed_nodes, options,
        [&](std::int64_t d, std::int64_t t) { bar(d, t); }, &note, &stats);
    std::fprintf(stderr, "%s\n", note.c_str());
    if (stats.total_s > 0.0) {
      std::fprintf(stderr,
                   "free DOFs %lld, nonzeros in L %lld; assemble %.2f s, analyze %.2f s, factor "
                   "%.2f s, solves %.2f s\n",
                   static_cast<long long>(stats.free_dofs), static_cast<long long>(stats.factor_nonzeros),
                   stats.assemble_s, stats.analyze_s, stats.factor_s, stats.solve_s);
    }
    std::printf("{\"cache\": \"%s\", \"surface_nodes\": %d, \"precision\": \"%s\", "
                "\"storage_bytes\": %zu, \"seconds\": %.3f}\n",
                out.c_str(), c.num_nodes(), c.precision() == Precision::kFloat32 ? "float32" : "float64",
                c.storage_bytes(), std::chrono::duration<double>(Clock::now() - t0).count());
    return 0;
  });
}
