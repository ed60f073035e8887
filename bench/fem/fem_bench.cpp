// fem_bench: the paper's Fig. 10 (update frequency against surface node count for elementary
// displacements, Gauss elimination and Sherman-Morrison-Woodbury), extended to 10,000 surface
// nodes with a per-step CHOLMOD direct solve, plus accuracy-against-time series.
//
//   fem_bench                 Google Benchmark timings of the real-time paths (600 surface
//                             nodes; 10,000 too when its cache exists)
//   fem_bench --csv [--cache-dir DIR] [--max-nodes N] [--model-depth-mm D] [--only-models]
//                             rows method,surface_nodes,contacts,step_us,rel_error,p99_us,
//                             storage_bytes on stdout (step_us is the median; storage_bytes is what
//                             the method keeps besides the mesh: compliance, copies, tables),
//                             progress and precompute timings on stderr; --only-models: the model
//                             rows alone (below)
//
// Models: E = 10 kPa, nu = 0.3 (soft tissue). Cubes of n^3 nodes (edge 0.1 m, bottom fixed) give
// 116..584 free surface nodes for n = 6..12 (the paper's range), 953 (n = 15), 1,961 (n = 21,
// 26k DOF) and 4,441 (n = 31, 86k DOF). 10,000 surface nodes as a solid cube would be a 290k-DOF
// model; the extension uses a plate 0.2 x 0.2 x 0.01 m of 71 x 71 x 3 nodes clamped along one
// edge (10,149 free surface nodes, 45k DOF): the real-time cost depends only on the surface.
//
// Every step: 5 contacts (distinct random free surface nodes, random displacements up to 1 mm),
// cycling through 64 precomputed contact sets, so caches are as cold as random contacts make them;
// the *_coherent rows repeat one set (a finger resting on the object: its columns stay cached).
// step_us is the median over the steps; rel_error is against a direct sparse solve of the same
// contacts (CHOLMOD, reduced system): forces and, for the methods that compute them, every
// surface displacement (max of the two relative errors).
//
// Model rows (`model_linear_PART`, `model_stiffening_PART`, PART tail or belly): the model's
// error, not the solver's. On the
// real meshes of the tail and the belly (world::PrepareDeformable, as the haptic world has
// them), the deformable contact of one haptic step as HapticWorld::StepDeformable runs it: each
// fingertip's patch (ContactPatchFinder::Sphere, at most 16 nodes), one push-only ContactSolver
// solve with a sticking friction patch per fingertip, and with the table each fingertip's
// StiffeningTable::PatchGain (HapticWorld::ApplyFingerPatch). The steps cycle through
// fem_accuracy's four presses (one and five fingers, normal and 30 degrees oblique) at
// --model-depth-mm (4 mm: the tail is pressed 3.2-4.2 mm and the belly 4.0 mm by the scripted
// users). rel_error is the worst force error over those presses against CalculiX's neo-Hookean
// solid, read from fem_accuracy's committed run (bench/fem/fem_stiffening_PART.csv: force_err
// for the linear model, corrected_err with the table), not recomputed here; surface_nodes is the
// part's compliance nodes, contacts the most patch nodes (solver inputs) in one step.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <Eigen/LU>

#include "handshare/fem/assembly.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_patch.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/elementary_displacement.hpp"
#include "handshare/fem/sparse_cholesky.hpp"
#include "handshare/fem/static_solver.hpp"
#include "handshare/fem/stiffening.hpp"
#include "handshare/fem/surface_field.hpp"

#include "press_parts.hpp"
#include "rel_error.hpp"

namespace {

using namespace handshare::fem;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr Material kMat{1e4, 0.3};
constexpr int kContacts = 5;
constexpr int kSets = 64;

double Since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// ------------------------------------------------------------------ models

struct Model {
  std::string name;
  TetMesh mesh;
  std::vector<std::int32_t> fixed;
  std::shared_ptr<const Compliance> c64;
  std::int64_t free_dofs = 0;
};

Model MakeCube(int n) {
  Model m;
  m.name = "cube" + std::to_string(n);
  m.mesh = MakeBoxMesh({0.1, 0.1, 0.1}, {n - 1, n - 1, n - 1});
  m.fixed = NodesOnPlane(m.mesh, 2, 0.0);
  return m;
}

Model MakePlate() {
  Model m;
  m.name = "plate71x71x3";
  m.mesh = MakeBoxMesh({0.2, 0.2, 0.01}, {70, 70, 2});
  m.fixed = NodesOnPlane(m.mesh, 0, 0.0);
  return m;
}

// Loads the float64 compliance from the cache directory, or precomputes and saves it.
void LoadCompliance(Model& m, const fs::path& cache_dir) {
  fs::create_directories(cache_dir);
  const fs::path file = cache_dir / (m.name + ".f64.compliance");
  PrecomputeStats st;
  std::string note;
  Clock::time_point t0 = Clock::now();
  auto progress = [&](std::int64_t d, std::int64_t t) {
    if (d == t || d % 512 == 0) std::fprintf(stderr, "\r  %s: %lld/%lld nodes, %.0f s ", m.name.c_str(),
                                             static_cast<long long>(d), static_cast<long long>(t), Since(t0));
  };
  m.c64 = std::make_shared<Compliance>(
      Compliance::LoadOrPrecompute(file, m.mesh, kMat, m.fixed, {}, progress, &note, &st));
  std::fprintf(stderr, "\n");
  if (st.total_s > 0.0) {
    std::fprintf(stderr,
                 "# precompute %s: %lld free DOF, %d surface nodes, method %s, nnz(L) %lld, %.3g flop; "
                 "assemble %.1f s, analyze %.1f s, factor %.1f s, blocks %.1f s, total %.1f s\n",
                 m.name.c_str(), static_cast<long long>(st.free_dofs), m.c64->num_nodes(),
                 st.method == PrecomputeMethod::kSchurComplement ? "schur" : "solves",
                 static_cast<long long>(st.factor_nonzeros), st.factor_flops, st.assemble_s, st.analyze_s,
                 st.factor_s, st.solve_s, st.total_s);
    m.free_dofs = st.free_dofs;
  } else {
    std::fprintf(stderr, "# %s: %s (%.1f s)\n", m.name.c_str(), note.c_str(), Since(t0));
  }
  if (m.free_dofs == 0) {
    m.free_dofs = 3 * static_cast<std::int64_t>(m.mesh.num_nodes() - static_cast<std::int32_t>(m.fixed.size()));
  }
}

std::vector<std::vector<ContactInput>> RandomSets(const Compliance& c, int count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::int32_t> slot(0, c.num_nodes() - 1);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  std::vector<std::vector<ContactInput>> sets;
  for (int s = 0; s < count; ++s) {
    std::vector<ContactInput> in;
    while (static_cast<int>(in.size()) < kContacts) {
      const std::int32_t node = c.nodes()[slot(rng)];
      bool dup = false;
      for (const auto& x : in) dup = dup || x.node == node;
      if (!dup) in.push_back({node, {u(rng), u(rng), u(rng)}});
    }
    sets.push_back(in);
  }
  return sets;
}

// Reference: direct sparse solve of the reduced system for one contact set.
struct Reference {
  std::vector<Eigen::Vector3d> forces_N;
  std::vector<Eigen::Vector3d> surface_u_m;  // slot order
};

Reference Direct(const Model& m, const std::vector<ContactInput>& set) {
  std::vector<std::int32_t> nodes;
  std::vector<Eigen::Vector3d> u;
  for (const auto& c : set) {
    nodes.push_back(c.node);
    u.push_back(c.u_m);
  }
  StaticSolver solver(m.mesh, kMat, m.fixed, nodes);
  const StaticSolution s = solver.Solve(u);
  Reference r;
  for (const auto& c : set) r.forces_N.push_back(s.reaction_N[c.node]);
  for (std::int32_t v : m.c64->nodes()) r.surface_u_m.push_back(s.u_m[v]);
  return r;
}

using bench::RelError;

// ------------------------------------------------------------------ timing

struct Timing {
  double median_us = 0, p99_us = 0;
  long steps = 0;
};

// Runs step(i) over the contact sets until min_seconds and min_steps are reached.
Timing Time(const std::function<void(int)>& step, double min_seconds, long min_steps) {
  std::vector<double> us;
  step(0);  // warm up
  const auto t0 = Clock::now();
  long i = 0;
  while (i < min_steps || Since(t0) < min_seconds) {
    const auto a = Clock::now();
    step(static_cast<int>(i % kSets));
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - a).count());
    ++i;
    if (Since(t0) > 60.0 && i >= 2) break;  // slow methods: a few steps are enough
  }
  std::sort(us.begin(), us.end());
  Timing t;
  t.steps = i;
  t.median_us = us[us.size() / 2];
  t.p99_us = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  return t;
}

void Row(const std::string& method, int nodes, int contacts, const Timing& t, double err, double bytes = 0) {
  std::printf("%s,%d,%d,%.4g,%.3e,%.4g,%.4g\n", method.c_str(), nodes, contacts, t.median_us, err, t.p99_us, bytes);
  std::fflush(stdout);
  std::fprintf(stderr,
               "  %-44s N=%-6d m=%-3d median %10.3f us  p99 %10.3f us  (%ld steps)  rel_error %.2e  %.3g bytes (%.2f N^2)\n",
               method.c_str(), nodes, contacts, t.median_us, t.p99_us, t.steps, err, bytes,
               bytes / (static_cast<double>(nodes) * nodes));
}

// ------------------------------------------------------------------ comparison methods

// Constrained DOFs of a contact set in the free numbering.
struct FreeMap {
  std::vector<std::int64_t> free_of_dof;
  std::vector<std::int64_t> free_dofs;
  explicit FreeMap(const Model& m) {
    std::vector<bool> held(static_cast<std::size_t>(m.mesh.num_nodes()), false);
    for (std::int32_t v : m.fixed) held[v] = true;
    free_of_dof.assign(3 * static_cast<std::size_t>(m.mesh.num_nodes()), -1);
    for (std::int64_t d = 0; d < 3 * static_cast<std::int64_t>(m.mesh.num_nodes()); ++d) {
      if (!held[d / 3]) {
        free_of_dof[d] = static_cast<std::int64_t>(free_dofs.size());
        free_dofs.push_back(d);
      }
    }
  }
};

// CHOLMOD direct solve every step: K_ff with the touched DOFs' rows and columns replaced by the
// identity (explicit zeros keep the pattern, so the symbolic analysis is done once), numeric
// factorization and solve each step. Forces: K_c. u.
class CholmodDirect {
 public:
  explicit CholmodDirect(const Model& m) : map_(m) {
    const auto K = AssembleStiffness(m.mesh, kMat);
    const auto nf = static_cast<Eigen::Index>(map_.free_dofs.size());
    std::vector<Eigen::Triplet<double>> t;
    for (Eigen::Index c = 0; c < nf; ++c) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(K, map_.free_dofs[c]); it; ++it) {
        const std::int64_t r = map_.free_of_dof[it.row()];
        if (r >= 0) t.emplace_back(static_cast<int>(r), static_cast<int>(c), it.value());
      }
    }
    Kff_.resize(nf, nf);
    Kff_.setFromTriplets(t.begin(), t.end());
    Kff_.makeCompressed();
    work_ = Kff_;
    chol_.Analyze(Kff_);
    rhs_.resize(nf);
    is_c_.assign(static_cast<std::size_t>(nf), 0);
  }
  void Step(const std::vector<ContactInput>& set, std::vector<Eigen::Vector3d>& forces) {
    std::vector<std::int64_t> cd;
    for (const auto& c : set)
      for (int a = 0; a < 3; ++a) cd.push_back(map_.free_of_dof[3 * c.node + a]);
    for (auto d : cd) is_c_[d] = 1;
    rhs_.setZero();
    // rhs = -K_fc d* on free rows, d* on touched rows.
    for (std::size_t k = 0; k < cd.size(); ++k) {
      const double val = set[k / 3].u_m[static_cast<int>(k % 3)];
      for (Eigen::SparseMatrix<double>::InnerIterator it(Kff_, cd[k]); it; ++it) rhs_[it.row()] -= it.value() * val;
    }
    for (std::size_t k = 0; k < cd.size(); ++k) rhs_[cd[k]] = set[k / 3].u_m[static_cast<int>(k % 3)];
    std::copy(Kff_.valuePtr(), Kff_.valuePtr() + Kff_.nonZeros(), work_.valuePtr());
    for (Eigen::Index c = 0; c < work_.outerSize(); ++c) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(work_, c); it; ++it) {
        if (is_c_[c] || is_c_[it.row()]) it.valueRef() = (it.row() == c) ? 1.0 : 0.0;
      }
    }
    chol_.Factorize(work_);
    chol_.SolveInPlace(rhs_);
    forces.assign(set.size(), Eigen::Vector3d::Zero());
    for (std::size_t k = 0; k < cd.size(); ++k) {
      double f = 0.0;  // row cd[k] of K_ff times u (K symmetric: column cd[k])
      for (Eigen::SparseMatrix<double>::InnerIterator it(Kff_, cd[k]); it; ++it) f += it.value() * rhs_[it.row()];
      forces[k / 3][static_cast<int>(k % 3)] = f;
    }
    for (auto d : cd) is_c_[d] = 0;
  }
  double u(std::int32_t node, int a) const { return rhs_[map_.free_of_dof[3 * node + a]]; }

 private:
  FreeMap map_;
  Eigen::SparseMatrix<double> Kff_, work_;
  SparseCholesky chol_;
  Eigen::VectorXd rhs_;
  std::vector<std::uint8_t> is_c_;
};

// Gauss elimination on the full system (the paper's comparison): dense K of every DOF, fixed and
// touched DOFs' rows replaced by identity rows, LU with partial pivoting each step.
class GaussFull {
 public:
  explicit GaussFull(const Model& m) : m_(m), K_(AssembleStiffness(m.mesh, kMat)) {
    for (std::int32_t v : m.fixed)
      for (int a = 0; a < 3; ++a) fixed_dofs_.push_back(3 * v + a);
  }
  void Step(const std::vector<ContactInput>& set, std::vector<Eigen::Vector3d>& forces) {
    const auto n = K_.rows();
    A_ = Eigen::MatrixXd(K_);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
    for (auto d : fixed_dofs_) {
      A_.row(d).setZero();
      A_(d, d) = 1.0;
    }
    for (const auto& c : set)
      for (int a = 0; a < 3; ++a) {
        const auto d = 3 * c.node + a;
        A_.row(d).setZero();
        A_(d, d) = 1.0;
        b[d] = c.u_m[a];
      }
    u_ = A_.partialPivLu().solve(b);
    forces.clear();
    for (const auto& c : set) {
      Eigen::Vector3d f;
      for (int a = 0; a < 3; ++a) f[a] = K_.col(3 * c.node + a).dot(u_);
      forces.push_back(f);
    }
  }
  const Eigen::VectorXd& u() const { return u_; }

 private:
  const Model& m_;
  Eigen::SparseMatrix<double> K_;
  std::vector<std::int64_t> fixed_dofs_;
  Eigen::MatrixXd A_;
  Eigen::VectorXd u_;
};

// Sherman-Morrison-Woodbury on a precomputed dense inverse A^-1 = K_ff^-1: imposing u_P = d*
// replaces rows and columns P of A by the identity, K' = (I-QQ^T) A (I-QQ^T) + QQ^T = A + U V^T
// with U = [Q, AQ] and V^T = [(B+I)Q^T - (AQ)^T; -Q^T], B = Q^T A Q (rank 6m). With
// y = A^-1 b', A^-1 U = [A^-1 Q, Q] and H = Q^T A^-1 Q, the capacitance matrix is
// [[(B+I)H, I], [-H, 0]], so u = y - A^-1 U w costs the dense matvec y = A^-1 b' (n^2) per step.
class Woodbury {
 public:
  Woodbury(const Model& m, SparseCholesky& chol, const Eigen::SparseMatrix<double>& Kff) : map_(m), Kff_(Kff) {
    const auto n = Kff.rows();
    Ainv_ = Eigen::MatrixXd::Identity(n, n);
    chol.SolveInPlace(Ainv_);
  }
  void Step(const std::vector<ContactInput>& set, std::vector<Eigen::Vector3d>& forces) {
    const auto n = Ainv_.rows();
    std::vector<std::int64_t> P;
    Eigen::VectorXd d(3 * static_cast<Eigen::Index>(set.size()));
    for (std::size_t k = 0; k < set.size(); ++k)
      for (int a = 0; a < 3; ++a) {
        P.push_back(map_.free_of_dof[3 * set[k].node + a]);
        d[3 * static_cast<Eigen::Index>(k) + a] = set[k].u_m[a];
      }
    const auto p = static_cast<Eigen::Index>(P.size());
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
    for (Eigen::Index k = 0; k < p; ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(Kff_, P[k]); it; ++it) b[it.row()] -= it.value() * d[k];
    for (Eigen::Index k = 0; k < p; ++k) b[P[k]] = d[k];
    y_.noalias() = Ainv_ * b;  // the O(n^2) part
    Eigen::MatrixXd H(p, p), B(p, p);
    for (Eigen::Index i = 0; i < p; ++i)
      for (Eigen::Index j = 0; j < p; ++j) {
        H(i, j) = Ainv_(P[i], P[j]);
        B(i, j) = Kff_.coeff(P[i], P[j]);
      }
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(2 * p, 2 * p);
    M.topLeftCorner(p, p) = (B + Eigen::MatrixXd::Identity(p, p)) * H;
    M.topRightCorner(p, p).setIdentity();
    M.bottomLeftCorner(p, p) = -H;
    Eigen::VectorXd rhs(2 * p), yP(p);
    for (Eigen::Index i = 0; i < p; ++i) yP[i] = y_[P[i]];
    rhs.head(p) = (B + Eigen::MatrixXd::Identity(p, p)) * yP - d;
    rhs.tail(p) = -yP;
    const Eigen::VectorXd w = M.partialPivLu().solve(rhs);
    for (Eigen::Index i = 0; i < p; ++i) {
      y_.noalias() -= Ainv_.col(P[i]) * w[i];
      y_[P[i]] -= w[p + i];
    }
    forces.assign(set.size(), Eigen::Vector3d::Zero());
    for (Eigen::Index k = 0; k < p; ++k) {
      double f = 0.0;
      for (Eigen::SparseMatrix<double>::InnerIterator it(Kff_, P[k]); it; ++it) f += it.value() * y_[it.row()];
      forces[static_cast<std::size_t>(k / 3)][static_cast<int>(k % 3)] = f;
    }
  }
  double u(std::int32_t node, int a) const { return y_[map_.free_of_dof[3 * node + a]]; }

 private:
  FreeMap map_;
  const Eigen::SparseMatrix<double>& Kff_;
  Eigen::MatrixXd Ainv_;
  Eigen::VectorXd y_;
};

// ------------------------------------------------------------------ the sweep

struct Limits {
  std::int64_t gauss_max_dofs = 6000;  // dense LU of the full K: ~(2/3) n^3 flop, seconds per step
  std::int64_t smw_max_dofs = 12000;   // dense K^-1: n^2 doubles (1.2 GB at 12k)
};

void BenchModel(Model& m, const fs::path& cache_dir, const Limits& lim) {
  LoadCompliance(m, cache_dir);
  const int N = m.c64->num_nodes();
  const auto sets = RandomSets(*m.c64, kSets, 1234);
  // References for the error columns: a few sets are enough (a direct solve each).
  constexpr int kRef = 3;
  std::vector<Reference> ref;
  for (int s = 0; s < kRef; ++s) ref.push_back(Direct(m, sets[s]));
  std::vector<Eigen::Vector3d> field(N);
  auto surface_error = [&](const std::function<Eigen::Vector3d(std::int32_t slot)>& u_of, int s) {
    std::vector<Eigen::Vector3d> u(N);
    for (int k = 0; k < N; ++k) u[k] = u_of(k);
    return RelError(u, ref[s].surface_u_m);
  };

  // The symmetric compliance form, float64 and float32 storage.
  for (Precision prec : {Precision::kFloat64, Precision::kFloat32}) {
    const std::string suffix = prec == Precision::kFloat64 ? "" : "_float32";
    auto c = prec == Precision::kFloat64 ? m.c64 : std::make_shared<Compliance>(m.c64->ConvertedTo(prec));
    ContactSolver solver(c, {.max_contacts = kContacts});
    double err_f = 0.0, err_u = 0.0;
    for (int s = 0; s < kRef; ++s) {
      solver.Solve(sets[s]);
      std::vector<Eigen::Vector3d> f(solver.forces_N().begin(), solver.forces_N().end());
      err_f = std::max(err_f, RelError(f, ref[s].forces_N));
      solver.SurfaceDisplacements(field);
      err_u = std::max(err_u, surface_error([&](std::int32_t k) { return field[k]; }, s));
    }
    const double bytes = static_cast<double>(c->storage_bytes());
    Row("compliance_force_only" + suffix, N, kContacts,
        Time([&](int i) { solver.Solve(sets[i]); }, 0.3, 2000), err_f, bytes);
    Row("compliance_full_update" + suffix, N, kContacts,
        Time([&](int i) { solver.Solve(sets[i]); solver.SurfaceDisplacements(field); }, 0.3, 200),
        std::max(err_f, err_u), bytes);
    Row("compliance_full_update" + suffix + "_coherent", N, kContacts,
        Time([&](int) { solver.Solve(sets[0]); solver.SurfaceDisplacements(field); }, 0.3, 200),
        std::max(err_f, err_u), bytes);
    if (prec == Precision::kFloat64) {
      // Regularization eps = rel x mean diagonal of C_kk: error against the exact forces.
      double diag = 0.0;
      for (int k = 0; k < N; ++k) diag += m.c64->Block(k, k).trace() / 3.0;
      diag /= N;
      for (double rel : {1e-3, 1e-2, 1e-1}) {
        ContactSolver reg(c, {.max_contacts = kContacts, .regularization_m_per_N = rel * diag});
        double e = 0.0;
        for (int s = 0; s < kRef; ++s) {
          reg.Solve(sets[s]);
          std::vector<Eigen::Vector3d> f(reg.forces_N().begin(), reg.forces_N().end());
          e = std::max(e, RelError(f, ref[s].forces_N));
        }
        char name[64];
        std::snprintf(name, sizeof name, "compliance_force_only_reg_%g", rel);
        Row(name, N, kContacts, Time([&](int i) { reg.Solve(sets[i]); }, 0.2, 1000), e, bytes);
      }
    }
  }

  // Exact forces (ContactSolver on the float64 compliance) and the surface field from a planar
  // copy of all N columns (both halves: every column streams), float32, float16 and int16.
  for (Precision prec : {Precision::kFloat32, Precision::kFloat16, Precision::kInt16}) {
    const std::string name = std::string("compliance_full_update_columns_") +
                             (prec == Precision::kFloat32 ? "float32" : prec == Precision::kFloat16 ? "float16" : "int16");
    const auto t0 = Clock::now();
    SurfaceField cols(m.c64, {.layout = SurfaceFieldLayout::kColumns, .precision = prec});
    std::fprintf(stderr, "  %s: copy built in %.1f s, kernel %s\n", name.c_str(), Since(t0), cols.kernel_name());
    ContactSolver solver(m.c64, {.max_contacts = kContacts});
    double err = 0.0;
    for (int s = 0; s < kRef; ++s) {
      solver.Solve(sets[s]);
      std::vector<Eigen::Vector3d> f(solver.forces_N().begin(), solver.forces_N().end());
      cols.Evaluate(solver.loads(), field);
      err = std::max({err, RelError(f, ref[s].forces_N), surface_error([&](std::int32_t k) { return field[k]; }, s)});
    }
    const double bytes = static_cast<double>(cols.storage_bytes());  // plus the compliance for the forces
    Row(name, N, kContacts, Time([&](int i) { solver.Solve(sets[i]); cols.Evaluate(solver.loads(), field); }, 0.3, 200), err, bytes);
    Row(name + "_coherent", N, kContacts,
        Time([&](int) { solver.Solve(sets[0]); cols.Evaluate(solver.loads(), field); }, 0.3, 200), err, bytes);
  }

  // Block low-rank compressed compliance (the only storage the step then needs): forces and
  // field from it, at two tolerances.
  // float16 factors only at 1e-3: at 1e-5 no block's float16 factors meet the tolerance.
  struct Variant {
    double tol;
    Precision factors;
  };
  for (const Variant var : {Variant{1e-3, Precision::kFloat32}, Variant{1e-3, Precision::kFloat16},
                            Variant{1e-5, Precision::kFloat32}}) {
    const double tol = var.tol;
    const char* suffix = var.factors == Precision::kFloat16 ? "_f16factors" : "";
    CompressionStats st;
    auto cc = std::make_shared<const Compliance>(
        m.c64->Compressed(m.mesh, {.tolerance = tol, .leaf_nodes = 32, .factor_precision = var.factors}, &st));
    std::fprintf(stderr,
                 "  compressed tol %g%s eta %g: %lld tiles (%lld low-rank views), %lld low-rank blocks (mean rank %.1f, max %d, "
                 "largest %lld entries, %lld tried), %.1f s, %.3g bytes = %.2f N^2 (dense %.2f, factors %.2f, tables %.3f N^2)\n",
                 tol, suffix, CompressionOptions{}.eta, static_cast<long long>(st.tiles), static_cast<long long>(st.low_rank_tiles),
                 static_cast<long long>(st.low_rank_blocks), st.mean_rank, st.max_rank,
                 static_cast<long long>(st.largest_block_entries), static_cast<long long>(st.blocks_tried), st.seconds,
                 static_cast<double>(cc->storage_bytes()), static_cast<double>(cc->storage_bytes()) / (double(N) * N),
                 static_cast<double>(st.dense_bytes) / (double(N) * N), static_cast<double>(st.factor_bytes) / (double(N) * N),
                 static_cast<double>(st.table_bytes) / (double(N) * N));
    ContactSolver solver(cc, {.max_contacts = kContacts});
    double err_f = 0.0, err = 0.0;
    for (int s = 0; s < kRef; ++s) {
      solver.Solve(sets[s]);
      std::vector<Eigen::Vector3d> f(solver.forces_N().begin(), solver.forces_N().end());
      err_f = std::max(err_f, RelError(f, ref[s].forces_N));
      solver.SurfaceDisplacements(field);
      err = std::max({err, err_f, surface_error([&](std::int32_t k) { return field[k]; }, s)});
    }
    char name[80];
    const double bytes = static_cast<double>(cc->storage_bytes());
    std::snprintf(name, sizeof name, "compressed_force_only_tol_%g%s", tol, suffix);
    Row(name, N, kContacts, Time([&](int i) { solver.Solve(sets[i]); }, 0.3, 2000), err_f, bytes);
    std::snprintf(name, sizeof name, "compressed_full_update_tol_%g%s", tol, suffix);
    Row(name, N, kContacts, Time([&](int i) { solver.Solve(sets[i]); solver.SurfaceDisplacements(field); }, 0.3, 200), err, bytes);
  }

  // The paper's form: T^d, T^f tensors (9 N^2 scalars). float32 is the configuration a haptic
  // node would run (SIMD kernel); float64 as well where it fits comfortably (N <= 5,000).
  for (Precision prec : {Precision::kFloat32, Precision::kFloat16, Precision::kFloat64}) {
    if (prec == Precision::kFloat64 && N > 5000) continue;
    const auto t0 = Clock::now();
    auto T = std::make_shared<ElementaryDisplacementTensors>(ElementaryDisplacementTensors::FromCompliance(*m.c64, prec));
    std::fprintf(stderr, "  T^d/T^f built in %.1f s (%.2f GB)\n", Since(t0), T->storage_bytes() / 1e9);
    ElementaryDisplacementSolver paper(T, kContacts);
    double err = 0.0;
    for (int s = 0; s < kRef; ++s) {
      paper.Solve(sets[s]);
      std::vector<Eigen::Vector3d> f(paper.forces_N().begin(), paper.forces_N().end());
      paper.SurfaceDisplacements(field);
      err = std::max({err, RelError(f, ref[s].forces_N), surface_error([&](std::int32_t k) { return field[k]; }, s)});
    }
    const std::string name = prec == Precision::kFloat32   ? "elementary_displacement"
                             : prec == Precision::kFloat16 ? "elementary_displacement_float16"
                                                           : "elementary_displacement_float64";
    const double bytes = static_cast<double>(T->storage_bytes());
    Row(name, N, kContacts, Time([&](int i) { paper.Solve(sets[i]); paper.SurfaceDisplacements(field); }, 0.3, 200), err, bytes);
    if (prec != Precision::kFloat64) {
      // Coherent contacts (the same set every step, as while a finger rests on the object).
      Row(name + "_coherent", N, kContacts,
          Time([&](int) { paper.Solve(sets[0]); paper.SurfaceDisplacements(field); }, 0.3, 200), err, bytes);
    }
  }

  const std::int64_t full_dofs = 3 * static_cast<std::int64_t>(m.mesh.num_nodes());
  if (full_dofs <= lim.gauss_max_dofs) {
    GaussFull gauss(m);
    std::vector<Eigen::Vector3d> f;
    double err = 0.0;
    for (int s = 0; s < kRef; ++s) {
      gauss.Step(sets[s], f);
      err = std::max({err, RelError(f, ref[s].forces_N),
                      surface_error([&](std::int32_t k) { return Eigen::Vector3d(gauss.u().segment<3>(3 * m.c64->nodes()[k])); }, s)});
    }
    Row("gauss_elimination", N, kContacts, Time([&](int i) { gauss.Step(sets[i], f); }, 2.0, 2), err);
  } else {
    std::fprintf(stderr, "  gauss_elimination skipped: %lld DOF > %lld\n", static_cast<long long>(full_dofs),
                 static_cast<long long>(lim.gauss_max_dofs));
  }

  if (m.free_dofs <= lim.smw_max_dofs) {
    FreeMap map(m);
    const auto K = AssembleStiffness(m.mesh, kMat);
    std::vector<Eigen::Triplet<double>> t;
    for (std::size_t c = 0; c < map.free_dofs.size(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(K, map.free_dofs[c]); it; ++it)
        if (map.free_of_dof[it.row()] >= 0) t.emplace_back(static_cast<int>(map.free_of_dof[it.row()]), static_cast<int>(c), it.value());
    Eigen::SparseMatrix<double> Kff(static_cast<Eigen::Index>(map.free_dofs.size()), static_cast<Eigen::Index>(map.free_dofs.size()));
    Kff.setFromTriplets(t.begin(), t.end());
    Kff.makeCompressed();
    SparseCholesky chol;
    chol.Compute(Kff);
    Woodbury smw(m, chol, Kff);
    std::vector<Eigen::Vector3d> f;
    double err = 0.0;
    for (int s = 0; s < kRef; ++s) {
      smw.Step(sets[s], f);
      err = std::max({err, RelError(f, ref[s].forces_N), surface_error([&](std::int32_t k) {
                        const std::int32_t v = m.c64->nodes()[k];
                        return Eigen::Vector3d(smw.u(v, 0), smw.u(v, 1), smw.u(v, 2));
                      }, s)});
    }
    Row("sherman_morrison_woodbury", N, kContacts, Time([&](int i) { smw.Step(sets[i], f); }, 1.0, 5), err);
  } else {
    std::fprintf(stderr, "  sherman_morrison_woodbury skipped: %lld free DOF > %lld\n",
                 static_cast<long long>(m.free_dofs), static_cast<long long>(lim.smw_max_dofs));
  }

  {
    CholmodDirect direct(m);
    std::vector<Eigen::Vector3d> f;
    double err = 0.0;
    for (int s = 0; s < kRef; ++s) {
      direct.Step(sets[s], f);
      err = std::max({err, RelError(f, ref[s].forces_N), surface_error([&](std::int32_t k) {
                        const std::int32_t v = m.c64->nodes()[k];
                        return Eigen::Vector3d(direct.u(v, 0), direct.u(v, 1), direct.u(v, 2));
                      }, s)});
    }
    Row("cholmod_direct", N, kContacts, Time([&](int i) { direct.Step(sets[i], f); }, 2.0, 3), err);
  }
}

// Fingertip patch on graded blocks of increasing resolution: error of the push-only Hertz force
// against the finest mesh of the series (pure discretization error), against the step time.
void BenchResolution(const fs::path& cache_dir) {
  (void)cache_dir;
  const double a = 0.005, R = 4 * a, depth = (0.75 * a) * (0.75 * a) / R;
  struct Point {
    double div;
    int surface;
    int patch;
    Timing t;
    double F;
  };
  std::vector<Point> pts;
  for (double div : {2.0, 3.0, 4.0, 6.0, 8.0}) {
    const double h = a / div;
    auto axis = [&](double ext) {
      std::vector<double> x = {0.0};
      double step = h;
      while (x.back() < ext) {
        if (x.back() >= 1.25 * a) step *= 1.5;
        double next = x.back() + step;
        if (next > ext - 0.5 * step) next = ext;
        x.push_back(next);
      }
      return x;
    };
    const auto half = axis(24 * a);
    std::vector<double> xy, z;
    for (auto it = half.rbegin(); it != half.rend(); ++it) xy.push_back(-*it);
    xy.insert(xy.end(), half.begin() + 1, half.end());
    for (auto it = half.rbegin(); it != half.rend(); ++it) z.push_back(-*it);
    const TetMesh mesh = MakeGridMesh(xy, xy, z);
    const auto fixed = NodesOnPlane(mesh, 2, z.front(), 1e-12);
    ComplianceOptions o;
    for (std::int32_t v : NodesOnPlane(mesh, 2, 0.0, 1e-12))
      if (mesh.positions_m()[v].head<2>().norm() < 1.2 * a) o.nodes.push_back(v);
    const auto t0 = Clock::now();
    auto c = std::make_shared<Compliance>(Compliance::Precompute(mesh, kMat, fixed, o));
    const Surface surf = ExtractSurface(mesh);
    std::fprintf(stderr, "  resolution a/h=%g: %d nodes, compliance of %d patch-region nodes in %.1f s\n", div,
                 mesh.num_nodes(), c->num_nodes(), Since(t0));
    ContactPatchFinder finder(mesh, surf, *c);
    std::vector<ContactInput> patch(static_cast<std::size_t>(c->num_nodes()));
    ContactSolver solver(c, {.max_contacts = c->num_nodes(), .push_only = true});
    int count = 0;
    auto step = [&](int) {
      count = finder.Sphere({0, 0, 0}, Eigen::Vector3d::UnitZ(), R, depth, ContactMode::kNormalOnly, patch).count;
      solver.Solve(std::span(patch.data(), static_cast<std::size_t>(count)));
    };
    Point p{div, static_cast<int>(surf.nodes.size() - fixed.size()), 0, Time(step, 0.3, 100), 0.0};
    p.patch = count;
    p.F = -solver.total_force_N().z();
    pts.push_back(p);
  }
  const double F_ref = pts.back().F;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "sphere_patch_a_over_h_%g", pts[i].div);
    Row(name, pts[i].surface, pts[i].patch, pts[i].t, std::abs(pts[i].F / F_ref - 1.0));
  }
  const double F_hertz = 4.0 / 3.0 * kMat.E_Pa / (1 - kMat.nu * kMat.nu) * std::sqrt(R) * std::pow(depth, 1.5);
  std::fprintf(stderr, "  sphere patch: F(finest) / Hertz = %.4f (block of 24 a: +5%% expected)\n", F_ref / F_hertz);
}


// ------------------------------------------------------------------ model rows

// The worst force error, linear and corrected, over the presses of `part` at depth_mm in
// fem_accuracy's committed comparison with the neo-Hookean solid (converged runs only).
struct ModelError {
  double linear = 0.0, corrected = 0.0;
  int presses = 0;
};

ModelError CommittedModelError(const fs::path& csv, const std::string& part, double depth_mm) {
  std::ifstream in(csv);
  if (!in) throw std::runtime_error("cannot read " + csv.string());
  auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    return cells;
  };
  std::string line;
  std::getline(in, line);
  std::map<std::string, std::size_t> col;
  const auto header = split(line);
  for (std::size_t i = 0; i < header.size(); ++i) col[header[i]] = i;
  for (const char* name : {"part", "model", "depth_mm", "converged", "force_err", "corrected_err"}) {
    if (!col.count(name)) throw std::runtime_error(csv.string() + ": no column " + name);
  }
  ModelError e;
  while (std::getline(in, line)) {
    const auto c = split(line);
    if (c.size() < header.size() || c[col["part"]] != part || c[col["model"]] != "neo_hooke" ||
        std::abs(std::stod(c[col["depth_mm"]]) - depth_mm) > 1e-9 || c[col["converged"]] != "1") {
      continue;
    }
    e.linear = std::max(e.linear, std::stod(c[col["force_err"]]));
    e.corrected = std::max(e.corrected, std::stod(c[col["corrected_err"]]));
    ++e.presses;
  }
  if (e.presses == 0) {
    throw std::runtime_error(csv.string() + ": no converged neo_hooke press of " + part + " at " + std::to_string(depth_mm) + " mm");
  }
  return e;
}

// One haptic step's deformable contact on a part (see the file comment), the four presses at
// depth_mm cycling, with and without the part's committed stiffening table.
void BenchModels(const fs::path& cache_dir, double depth_mm) {
  namespace hb = handshare::bench;
  for (const std::string name : {"tail", "belly"}) {
    const hb::PartSpec* spec = nullptr;
    for (const auto& p : hb::Parts()) {
      if (p.name == name) spec = &p;
    }
    const auto t0 = Clock::now();
    hb::Part part = hb::PreparePart(*spec, HANDSHARE_SOURCE_ASSETS, cache_dir / "parts", {});
    const fs::path table_file = hb::CommittedTable(part, spec->object_id);
    if (table_file.empty()) throw std::runtime_error(name + ": no committed stiffening table");
    const auto table = std::make_shared<const StiffeningTable>(*part.prepared.mesh, *part.prepared.surface,
                                                               ReadStiffeningSamples(table_file));
    const ModelError err = CommittedModelError(fs::path(HANDSHARE_BENCH_FEM_DIR) / ("fem_stiffening_" + name + ".csv"), name, depth_mm);
    const auto& C = part.prepared.compliance;
    std::fprintf(stderr, "# part %s: %d compliance nodes, table %s (%zu samples, %zu nodes covered), prepared in %.1f s; "
                 "committed errors at %.1f mm over %d presses: linear %.2f %%, corrected %.2f %%\n",
                 name.c_str(), C->num_nodes(), table_file.filename().c_str(), table->num_samples(), table->covered_nodes(),
                 Since(t0), depth_mm, err.presses, 100 * err.linear, 100 * err.corrected);

    // The presses: fingertips where fem_accuracy puts them, each with a sticking patch (oblique:
    // the stick of a press 30 degrees off the normal along the row).
    const double depth_m = 1e-3 * depth_mm;
    struct Press {
      std::vector<hb::Finger> fingers;
      std::vector<FrictionPatch> patches;
    };
    std::vector<Press> presses;
    for (const hb::PressSpec& ps : hb::Presses()) {
      Press p{hb::FindFingers(part, ps.fingers), {}};
      for (const hb::Finger& f : p.fingers) {
        FrictionPatch fp;
        fp.n_out = f.n_out_O;
        if (ps.oblique) {
          const Eigen::Vector3d row = spec->row_O.normalized();
          fp.slide_m = std::tan(hb::kObliqueAngle_rad) * depth_m * (row - row.dot(f.n_out_O) * f.n_out_O).normalized();
        }
        fp.mu_static = fp.mu_kinetic = hb::kStickingMu;
        p.patches.push_back(fp);
      }
      presses.push_back(std::move(p));
    }
    // As the haptic world sizes them (SceneModelsOptions: 4 hands, 16 nodes a fingertip).
    constexpr int kHands = 4, kFingers = 5, kMaxPatch = 16;
    ContactPatchFinder finder(*part.prepared.mesh, *part.prepared.surface, *C);
    std::vector<ContactInput> in(static_cast<std::size_t>(kHands * kFingers * kMaxPatch));
    ContactSolver solver(C, {.max_contacts = kHands * kFingers * kMaxPatch, .push_only = true,
                             .max_friction_patches = kHands * kFingers});
    std::array<std::pair<std::int32_t, std::int32_t>, kFingers> finger_inputs{};
    double felt = 0.0;  // the fingertips' summed force, so that nothing is optimized away
    int most_held = 0;
    auto step = [&](int i, const StiffeningTable* t) {
      const Press& p = presses[static_cast<std::size_t>(i) % presses.size()];
      std::int32_t m = 0;
      for (std::size_t k = 0; k < p.fingers.size(); ++k) {
        const PatchResult r = finder.Sphere(p.fingers[k].p_O, p.fingers[k].n_out_O, hb::kFingertipRadius_m, depth_m,
                                            ContactMode::kNormalOnly, std::span(in).subspan(static_cast<std::size_t>(m), kMaxPatch));
        for (std::int32_t q = m; q < m + r.count; ++q) in[static_cast<std::size_t>(q)].patch = static_cast<std::int16_t>(k);
        finger_inputs[k] = {m, r.count};
        m += r.count;
      }
      solver.Solve(std::span<const ContactInput>(in.data(), static_cast<std::size_t>(m)), p.patches);
      const auto forces = solver.forces_N();
      for (std::size_t k = 0; k < p.fingers.size(); ++k) {
        const auto [b, n] = finger_inputs[k];
        Eigen::Vector3d f = Eigen::Vector3d::Zero();
        for (std::int32_t q = b; q < b + n; ++q) f += forces[static_cast<std::size_t>(q)];
        if (t != nullptr) {
          f *= t->PatchGain(std::span<const ContactInput>(in.data() + b, static_cast<std::size_t>(n)),
                            forces.subspan(static_cast<std::size_t>(b), static_cast<std::size_t>(n)), p.fingers[k].n_out_O,
                            solver.patch_states()[k].slide_m);
        }
        felt += f.norm();
      }
      most_held = std::max(most_held, m);
    };
    const int nodes = C->num_nodes();
    const double bytes = static_cast<double>(C->storage_bytes());
    // Each row is timed twice, alternating, and the second of each kept: the first warms the caches.
    for (int round = 0; round < 2; ++round) {
      const Timing lin = Time([&](int i) { step(i, nullptr); }, 0.5, 20000);
      const Timing cor = Time([&](int i) { step(i, table.get()); }, 0.5, 20000);
      if (round == 1) {
        Row("model_linear_" + name, nodes, most_held, lin, err.linear, bytes);
        // The table's per-node gains: 6 floats and a flag per mesh node.
        Row("model_stiffening_" + name, nodes, most_held, cor, err.corrected,
            bytes + static_cast<double>(part.prepared.mesh->num_nodes()) * (6 * sizeof(float) + 4));
      }
    }
    std::fprintf(stderr, "  (summed felt force over the timed steps %.3g N)\n", felt);
  }
}

int RunCsv(int argc, char** argv) {
  fs::path cache_dir = "fem_bench_cache";
  int max_nodes = 20000;
  double model_depth_mm = 4.0;
  bool only_models = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--cache-dir" && i + 1 < argc) cache_dir = argv[++i];
    if (a == "--max-nodes" && i + 1 < argc) max_nodes = std::atoi(argv[++i]);
    if (a == "--model-depth-mm" && i + 1 < argc) model_depth_mm = std::atof(argv[++i]);
    if (a == "--only-models") only_models = true;
  }
  const auto t0 = Clock::now();
  std::printf("method,surface_nodes,contacts,step_us,rel_error,p99_us,storage_bytes\n");
  if (only_models) {
    BenchModels(cache_dir, model_depth_mm);
    return 0;
  }
  Limits lim;
  std::fprintf(stderr, "# cut-offs: gauss_elimination up to %lld DOF, sherman_morrison_woodbury up to %lld free DOF\n",
               static_cast<long long>(lim.gauss_max_dofs), static_cast<long long>(lim.smw_max_dofs));
  std::vector<std::function<Model()>> models;
  for (int n : {6, 7, 8, 9, 10, 11, 12, 15, 21, 31}) models.emplace_back([n] { return MakeCube(n); });
  models.emplace_back(MakePlate);
  for (auto& make : models) {
    Model m = make();
    const auto surface = ExtractSurface(m.mesh).nodes.size();
    if (static_cast<int>(surface) > max_nodes + static_cast<int>(m.fixed.size())) continue;
    std::fprintf(stderr, "# %s: %d nodes (%.1f min so far)\n", m.name.c_str(), m.mesh.num_nodes(), Since(t0) / 60);
    BenchModel(m, cache_dir, lim);
  }
  BenchResolution(cache_dir);
  BenchModels(cache_dir, model_depth_mm);
  std::fprintf(stderr, "# total %.1f min\n", Since(t0) / 60);
  return 0;
}

// ------------------------------------------------------------------ Google Benchmark mode

struct GbModel {
  Model m;
  std::shared_ptr<const Compliance> c32;
  std::vector<std::vector<ContactInput>> sets;
};

GbModel* GetGbModel(int which) {
  static std::unique_ptr<GbModel> models[2];
  if (!models[which]) {
    auto g = std::make_unique<GbModel>();
    g->m = which == 0 ? MakeCube(12) : MakePlate();
    const fs::path dir = std::getenv("HANDSHARE_FEM_BENCH_CACHE") ? std::getenv("HANDSHARE_FEM_BENCH_CACHE") : "fem_bench_cache";
    if (which == 1 && !fs::exists(dir / (g->m.name + ".f64.compliance"))) return nullptr;
    LoadCompliance(g->m, dir);
    g->c32 = std::make_shared<Compliance>(g->m.c64->ConvertedTo(Precision::kFloat32));
    g->sets = RandomSets(*g->m.c64, kSets, 99);
    models[which] = std::move(g);
  }
  return models[which].get();
}

void BM_ForceOnly(benchmark::State& state) {
  GbModel* g = GetGbModel(static_cast<int>(state.range(0)));
  if (g == nullptr) {
    state.SkipWithError("no cache for the 10,000-node plate: run fem_bench --csv first");
    return;
  }
  ContactSolver solver(state.range(1) ? g->c32 : g->m.c64, {.max_contacts = kContacts});
  int i = 0;
  for (auto _ : state) {
    solver.Solve(g->sets[i++ % kSets]);
    benchmark::DoNotOptimize(solver.forces_N().data());
  }
  state.counters["surface_nodes"] = g->m.c64->num_nodes();
}

void BM_FullUpdate(benchmark::State& state) {
  GbModel* g = GetGbModel(static_cast<int>(state.range(0)));
  if (g == nullptr) {
    state.SkipWithError("no cache for the 10,000-node plate: run fem_bench --csv first");
    return;
  }
  ContactSolver solver(state.range(1) ? g->c32 : g->m.c64, {.max_contacts = kContacts});
  std::vector<Eigen::Vector3d> field(g->m.c64->num_nodes());
  int i = 0;
  for (auto _ : state) {
    solver.Solve(g->sets[i++ % kSets]);
    solver.SurfaceDisplacements(field);
    benchmark::DoNotOptimize(field.data());
  }
  state.counters["surface_nodes"] = g->m.c64->num_nodes();
}

// The paper's form with float32 T^d (built on first use: 9 N^2 floats, 3.7 GB for the plate).
void BM_PaperFullUpdate(benchmark::State& state) {
  GbModel* g = GetGbModel(static_cast<int>(state.range(0)));
  if (g == nullptr) {
    state.SkipWithError("no cache for the 10,000-node plate: run fem_bench --csv first");
    return;
  }
  auto T = std::make_shared<ElementaryDisplacementTensors>(
      ElementaryDisplacementTensors::FromCompliance(*g->m.c64, Precision::kFloat32));
  ElementaryDisplacementSolver paper(T, kContacts);
  std::vector<Eigen::Vector3d> field(g->m.c64->num_nodes());
  int i = 0;
  for (auto _ : state) {
    paper.Solve(g->sets[i++ % kSets]);
    paper.SurfaceDisplacements(field);
    benchmark::DoNotOptimize(field.data());
  }
  state.counters["surface_nodes"] = g->m.c64->num_nodes();
}

// Args: {model: 0 = cube n=12 (584 nodes), 1 = plate (10,149 nodes); float32 storage}.
BENCHMARK(BM_ForceOnly)->Args({0, 0})->Args({0, 1})->Args({1, 0})->Args({1, 1})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FullUpdate)->Args({0, 0})->Args({0, 1})->Args({1, 0})->Args({1, 1})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PaperFullUpdate)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--csv") {
      try {
        return RunCsv(argc, argv);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "fem_bench: error: %s\n", e.what());
        return 1;
      }
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
