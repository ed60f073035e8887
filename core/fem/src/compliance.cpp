#include "handshare/fem/compliance.hpp"

#include <unistd.h>

#include <atomic>
#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>
#include <type_traits>
#include <utility>

#include "handshare/fem/error.hpp"
#include "handshare/fem/sparse_cholesky.hpp"
#include "compressed_blocks.hpp"
#include "hash.hpp"
#include "reduce.hpp"

// LAPACK (OpenBLAS through the Debian liblapack.so.3 alternative). Trailing arguments: the
// hidden lengths of the character arguments (gfortran convention).
extern "C" {
void dtrtri_(const char* uplo, const char* diag, const int* n, double* a, const int* lda, int* info,
             std::size_t uplo_len, std::size_t diag_len);
void dlauum_(const char* uplo, const int* n, double* a, const int* lda, int* info, std::size_t uplo_len);
}

namespace handshare::fem {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

constexpr char kMagic[8] = {'H', 'S', 'F', 'E', 'M', 'C', 'C', '\0'};
constexpr std::uint32_t kVersion = 1;

// Cache file header (little-endian host layout; 88 bytes, no padding).
struct FileHeader {
  char magic[8];
  std::uint32_t version;
  std::uint32_t scalar_bytes;
  std::uint64_t input_hash;
  std::uint64_t num_mesh_nodes;
  std::uint64_t num_nodes;
  std::uint64_t num_fixed;
  double E_Pa;
  double nu;
  std::uint64_t payload_bytes;
  std::uint64_t payload_checksum;
  std::uint64_t header_checksum;  // of every byte above
};
static_assert(sizeof(FileHeader) == 88, "cache header layout");

std::uint64_t HeaderChecksum(const FileHeader& h) {
  detail::Hasher64 hasher;
  hasher.Bytes(&h, offsetof(FileHeader, header_checksum));
  return hasher.digest();
}

std::uint64_t NumScalars(std::uint64_t n) { return 9 * (n * (n + 1) / 2); }

// Payload: int32 nodes[N], int32 fixed[F], zero padding to 8 bytes, scalars[9 N (N+1) / 2].
std::uint64_t IndexBytes(std::uint64_t n, std::uint64_t f) {
  const std::uint64_t b = 4 * (n + f);
  return (b + 7) / 8 * 8;
}

std::vector<std::int32_t> SortedFixed(const TetMesh& mesh, std::span<const std::int32_t> fixed) {
  std::vector<std::int32_t> f(fixed.begin(), fixed.end());
  for (std::int32_t v : f) {
    if (v < 0 || v >= mesh.num_nodes()) {
      throw InputError(mesh.source(), 0, "fixed_nodes", "node index " + std::to_string(v) + " out of range");
    }
  }
  std::sort(f.begin(), f.end());
  f.erase(std::unique(f.begin(), f.end()), f.end());
  return f;
}

template <class Scalar>
void ExtractBlocks(const Eigen::MatrixXd& X, std::int32_t s0, std::int32_t s1,
                   const std::vector<std::int64_t>& row_of_slot, Scalar* store) {
  // Column block k (slots s0..s1-1) of C = K_ff^-1 gives every C_nk; keep n <= k.
  for (std::int32_t k = s0; k < s1; ++k) {
    const double* col[3] = {X.col(3 * (k - s0)).data(), X.col(3 * (k - s0) + 1).data(),
                            X.col(3 * (k - s0) + 2).data()};
    Scalar* dst = store + 9 * Compliance::PackedIndex(0, k);
    for (std::int32_t n = 0; n <= k; ++n) {
      const std::int64_t* rows = &row_of_slot[3 * static_cast<std::size_t>(n)];
      for (int a = 0; a < 3; ++a)
        for (int r = 0; r < 3; ++r) dst[3 * a + r] = static_cast<Scalar>(col[a][rows[r]]);
      if (n == k) {
        // Symmetrize the diagonal block (round-off asymmetry of the solves, ~1e-16).
        for (int a = 0; a < 3; ++a)
          for (int r = a + 1; r < 3; ++r) {
            const Scalar m = static_cast<Scalar>(0.5 * (col[a][rows[r]] + col[r][rows[a]]));
            dst[3 * a + r] = m;
            dst[3 * r + a] = m;
          }
      }
      dst += 9;
    }
  }
}

// Chooses the precompute method (kAuto: the one estimated faster) and analyses Kff for it:
// solves_chol for blocked solves, schur_chol (compliance DOFs last) for the Schur complement.
// nf free DOFs, ns = row_of_slot.size() compliance DOFs.
PrecomputeMethod AnalyzeCandidates(const Eigen::SparseMatrix<double>& Kff, std::int64_t nf,
                                   const std::vector<std::int64_t>& row_of_slot, std::int64_t ns,
                                   PrecomputeMethod method, SparseCholesky& solves_chol, SparseCholesky& schur_chol) {
  // Analyse the candidates. Rates (flop/s) of this 2-core machine with OpenBLAS, measured by
  // bench/fem: supernodal factorization, blocked supernodal solves, dense triangular inversion.
  constexpr double kRateFactor = 3.0e10, kRateSolve = 1.0e10, kRateDense = 4.0e10;
  double t_solves = 0.0, t_schur = 0.0;
  if (method != PrecomputeMethod::kSchurComplement) {
    solves_chol.Analyze(Kff);
    t_solves = solves_chol.factor_flops() / kRateFactor +
               4.0 * static_cast<double>(solves_chol.factor_nonzeros()) * static_cast<double>(ns) / kRateSolve;
  }
  if (method != PrecomputeMethod::kBlockedSolves) {
    // Interior (non-compliance) DOFs first in their own fill-reducing order, compliance DOFs
    // last in slot order.
    std::vector<std::uint8_t> is_compliance(static_cast<std::size_t>(nf), 0);
    for (std::int64_t r : row_of_slot) is_compliance[r] = 1;
    detail::DofMap interior;
    interior.free_of_dof.assign(static_cast<std::size_t>(nf), -1);
    for (std::int64_t i = 0; i < nf; ++i) {
      if (!is_compliance[i]) {
        interior.free_of_dof[i] = static_cast<std::int64_t>(interior.free_dofs.size());
        interior.free_dofs.push_back(i);
      }
    }
    std::vector<int> perm;
    perm.reserve(static_cast<std::size_t>(nf));
    if (!interior.free_dofs.empty()) {
      SparseCholesky ordering;
      ordering.Analyze(detail::FreeBlock(Kff, interior));
      for (int k : ordering.Permutation()) perm.push_back(static_cast<int>(interior.free_dofs[k]));
    }
    for (std::int64_t r : row_of_slot) perm.push_back(static_cast<int>(r));
    schur_chol.AnalyzeWithOrdering(Kff, perm);
    const double n = static_cast<double>(ns);
    t_schur = schur_chol.factor_flops() / kRateFactor + (2.0 / 3.0) * n * n * n / kRateDense;
  }
  if (method == PrecomputeMethod::kAuto) {
    method = t_schur < t_solves ? PrecomputeMethod::kSchurComplement : PrecomputeMethod::kBlockedSolves;
  }
  return method;
}

// C = S^-1 = L_ss^-T L_ss^-1 in place of the trailing factor L_ss (ns x ns, the lower triangle
// of A): LAPACK dtrtri then dlauum, the two halves of dpotri.
void InvertTrailingFactor(Eigen::MatrixXd& A, std::int64_t ns, std::int32_t N, const ProgressFn& progress) {
  const int n = static_cast<int>(ns);
  int info = 0;
  if (n > 0) {
    dtrtri_("L", "N", &n, A.data(), &n, &info, 1, 1);
    if (info != 0) throw FemError("dense inversion of the condensed stiffness failed (dtrtri info " + std::to_string(info) + ")");
    if (progress) progress(N / 2, N);
    dlauum_("L", &n, A.data(), &n, &info, 1);
    if (info != 0) throw FemError("dense inversion of the condensed stiffness failed (dlauum info " + std::to_string(info) + ")");
  }
}

// The lower triangle of A holds C; blocks (n <= k) of the packed storage are C_nk = C_kn^T.
template <class Scalar>
void ExtractInverse(const Eigen::MatrixXd& A, std::int32_t N, Scalar* store) {
  for (std::int32_t k = 0; k < N; ++k) {
    Scalar* dst = store + 9 * Compliance::PackedIndex(0, k);
    for (std::int32_t m = 0; m <= k; ++m, dst += 9) {
      for (int a = 0; a < 3; ++a)
        for (int r = 0; r < 3; ++r) {
          // C_mk(r, a) = C(3m + r, 3k + a); read from the lower triangle.
          const std::int64_t i = 3 * m + r, j = 3 * k + a;
          dst[3 * a + r] = static_cast<Scalar>(i >= j ? A(i, j) : A(j, i));
        }
    }
  }
}

// Blocked solves: K_ff X = E for the unit columns E of `block` compliance nodes at a time (0:
// chosen here), each block's columns of C into store.
template <class Scalar>
void SolveColumnBlocks(SparseCholesky& chol, const std::vector<std::int64_t>& row_of_slot, std::int64_t nf,
                       int block, Scalar* store, const ProgressFn& progress) {
  const auto N = static_cast<std::int32_t>(row_of_slot.size() / 3);
  if (block <= 0) {
    // About 256 MiB of right-hand sides, at most 128 nodes (384 columns): past that the BLAS-3
    // supernodal solve gains little.
    const std::int64_t by_memory = (256ll << 20) / (24 * std::max<std::int64_t>(nf, 1));
    block = static_cast<int>(std::clamp<std::int64_t>(by_memory, 1, 128));
  }
  Eigen::MatrixXd X;
  for (std::int32_t s0 = 0; s0 < N; s0 += block) {
    const std::int32_t s1 = std::min(N, s0 + block);
    X.setZero(nf, 3 * (s1 - s0));
    for (std::int32_t k = s0; k < s1; ++k)
      for (int a = 0; a < 3; ++a) X(row_of_slot[3 * k + a], 3 * (k - s0) + a) = 1.0;
    chol.SolveInPlace(X);
    ExtractBlocks(X, s0, s1, row_of_slot, store);
    if (progress) progress(s1, N);
  }
}

// The header of the cache file `in` reads, checked against the file's size and expected_hash.
FileHeader ReadHeader(std::ifstream& in, const fs::path& file, std::uint64_t expected_hash) {
  const std::string name = file.string();
  std::error_code ec;
  const std::uint64_t size = fs::file_size(file, ec);
  if (ec) throw CacheError("compliance cache " + name + ": " + ec.message());
  FileHeader h{};
  if (size < sizeof h) {
    throw CacheError("compliance cache " + name + ": truncated: " + std::to_string(size) +
                     " bytes, the header alone needs " + std::to_string(sizeof h));
  }
  in.read(reinterpret_cast<char*>(&h), sizeof h);
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) {
    throw CacheError("compliance cache " + name + ": not a handshare compliance cache (bad magic)");
  }
  if (h.version != kVersion) {
    throw CacheError("compliance cache " + name + ": format version " + std::to_string(h.version) +
                     ", this build reads version " + std::to_string(kVersion) + " (delete it to rebuild)");
  }
  if (h.header_checksum != HeaderChecksum(h)) {
    throw CacheError("compliance cache " + name + ": corrupt header (checksum mismatch)");
  }
  if (expected_hash != 0 && h.input_hash != expected_hash) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "stale: built for another mesh, material or fixed set (input hash %016llx, expected %016llx)",
                  static_cast<unsigned long long>(h.input_hash), static_cast<unsigned long long>(expected_hash));
    throw CacheError("compliance cache " + name + ": " + buf);
  }
  if ((h.scalar_bytes != 4 && h.scalar_bytes != 8) || h.num_nodes > (1u << 20) ||
      h.num_mesh_nodes > INT32_MAX || h.num_fixed > h.num_mesh_nodes || h.num_nodes > h.num_mesh_nodes ||
      h.payload_bytes != IndexBytes(h.num_nodes, h.num_fixed) + NumScalars(h.num_nodes) * h.scalar_bytes) {
    throw CacheError("compliance cache " + name + ": corrupt header (inconsistent sizes)");
  }
  const std::uint64_t expected_size = sizeof h + h.payload_bytes;
  if (size < expected_size) {
    throw CacheError("compliance cache " + name + ": truncated: " + std::to_string(size) +
                     " bytes, expected " + std::to_string(expected_size));
  }
  if (size > expected_size) {
    throw CacheError("compliance cache " + name + ": " + std::to_string(size - expected_size) +
                     " unexpected trailing bytes");
  }
  return h;
}

}  // namespace

std::vector<std::int32_t> ResolveComplianceNodes(const TetMesh& mesh,
                                                 std::span<const std::int32_t> fixed_nodes,
                                                 std::span<const std::int32_t> requested) {
  const std::vector<std::int32_t> fixed = SortedFixed(mesh, fixed_nodes);
  std::vector<std::uint8_t> is_fixed(static_cast<std::size_t>(mesh.num_nodes()), 0);
  for (std::int32_t v : fixed) is_fixed[v] = 1;
  std::vector<std::int32_t> nodes;
  if (requested.empty()) {
    for (std::int32_t v : ExtractSurface(mesh).nodes) {
      if (!is_fixed[v]) nodes.push_back(v);
    }
    if (nodes.empty()) throw InputError(mesh.source(), 0, "fixed_nodes", "every surface node is fixed");
    return nodes;
  }
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(mesh.num_nodes()), 0);
  for (std::int32_t v : requested) {
    if (v < 0 || v >= mesh.num_nodes()) {
      throw InputError(mesh.source(), 0, "compliance nodes", "node index " + std::to_string(v) + " out of range");
    }
    const std::string id = "node id " + std::to_string(mesh.node_ids()[v]);
    if (is_fixed[v]) throw InputError(mesh.source(), 0, "compliance nodes", id + " is fixed");
    if (!mesh.used_nodes()[v]) throw InputError(mesh.source(), 0, "compliance nodes", id + " belongs to no element");
    if (seen[v]) throw InputError(mesh.source(), 0, "compliance nodes", id + " listed twice");
    seen[v] = 1;
    nodes.push_back(v);
  }
  return nodes;
}

std::uint64_t Compliance::InputHash(const TetMesh& mesh, const Material& material,
                                    std::span<const std::int32_t> fixed_nodes,
                                    const ComplianceOptions& options) {
  const std::vector<std::int32_t> fixed = SortedFixed(mesh, fixed_nodes);
  const std::vector<std::int32_t> nodes = ResolveComplianceNodes(mesh, fixed, options.nodes);
  detail::Hasher64 h;
  h.Pod(kVersion);
  h.Span(std::span<const Eigen::Vector3d>(mesh.positions_m()));
  h.Span(std::span<const Tet>(mesh.tets()));
  h.Pod(material.E_Pa);
  h.Pod(material.nu);
  h.Span(std::span<const std::int32_t>(fixed));
  h.Span(std::span<const std::int32_t>(nodes));
  h.Pod(static_cast<std::uint32_t>(options.precision));
  return h.digest();
}

void Compliance::BuildLookup(std::int32_t num_mesh_nodes) {
  slot_of_.assign(static_cast<std::size_t>(num_mesh_nodes), -1);
  fixed_flag_.assign(static_cast<std::size_t>(num_mesh_nodes), 0);
  for (std::size_t s = 0; s < nodes_.size(); ++s) slot_of_[nodes_[s]] = static_cast<std::int32_t>(s);
  for (std::int32_t v : fixed_) fixed_flag_[v] = 1;
}

Compliance Compliance::Precompute(const TetMesh& mesh, const Material& material,
                                  std::span<const std::int32_t> fixed_nodes,
                                  const ComplianceOptions& options, const ProgressFn& progress,
                                  PrecomputeStats* stats) {
  const auto t0 = Clock::now();
  material.Validate();
  if (options.precision != Precision::kFloat32 && options.precision != Precision::kFloat64) {
    throw InputError("", 0, "precision", "must be float32 or float64");
  }
  Compliance c;
  c.precision_ = options.precision;
  c.material_ = material;
  c.fixed_ = SortedFixed(mesh, fixed_nodes);
  c.nodes_ = ResolveComplianceNodes(mesh, c.fixed_, options.nodes);
  c.hash_ = InputHash(mesh, material, c.fixed_, options);
  c.BuildLookup(mesh.num_nodes());

  const detail::DofMap map = detail::MakeDofMap(mesh, c.fixed_);
  const Eigen::SparseMatrix<double> K = AssembleStiffness(mesh, material);
  const Eigen::SparseMatrix<double> Kff = detail::FreeBlock(K, map);
  const auto N = static_cast<std::int32_t>(c.nodes_.size());
  const auto nf = static_cast<std::int64_t>(map.free_dofs.size());
  const std::int64_t ns = 3 * static_cast<std::int64_t>(N);
  // Free index of each compliance DOF, slot-major (3 s + axis).
  std::vector<std::int64_t> row_of_slot(static_cast<std::size_t>(ns));
  for (std::int32_t s = 0; s < N; ++s)
    for (int r = 0; r < 3; ++r) row_of_slot[3 * s + r] = map.free_of_dof[3 * c.nodes_[s] + r];
  const std::uint64_t scalars = NumScalars(static_cast<std::uint64_t>(N));
  if (c.precision_ == Precision::kFloat32) {
    c.f32_.resize(scalars);
  } else {
    c.f64_.resize(scalars);
  }
  const auto t1 = Clock::now();

  SparseCholesky solves_chol, schur_chol;
  const PrecomputeMethod method = AnalyzeCandidates(Kff, nf, row_of_slot, ns, options.method, solves_chol, schur_chol);
  SparseCholesky& chol = method == PrecomputeMethod::kSchurComplement ? schur_chol : solves_chol;
  const auto t2 = Clock::now();
  chol.Factorize(Kff);
  const auto t3 = Clock::now();
  if (progress) progress(0, N);

  const bool f32 = c.precision_ == Precision::kFloat32;
  if (method == PrecomputeMethod::kSchurComplement) {
    Eigen::MatrixXd A = chol.TrailingFactor(ns);
    InvertTrailingFactor(A, ns, N, progress);
    if (f32) {
      ExtractInverse(A, N, c.f32_.data());
    } else {
      ExtractInverse(A, N, c.f64_.data());
    }
    if (progress) progress(N, N);
  } else if (f32) {
    SolveColumnBlocks(chol, row_of_slot, nf, options.block_nodes, c.f32_.data(), progress);
  } else {
    SolveColumnBlocks(chol, row_of_slot, nf, options.block_nodes, c.f64_.data(), progress);
  }
  const auto t4 = Clock::now();
  if (stats != nullptr) {
    stats->method = method;
    stats->free_dofs = nf;
    stats->factor_nonzeros = chol.factor_nonzeros();
    stats->factor_flops = chol.factor_flops();
    stats->assemble_s = Seconds(t0, t1);
    stats->analyze_s = Seconds(t1, t2);
    stats->factor_s = Seconds(t2, t3);
    stats->solve_s = Seconds(t3, t4);
    stats->total_s = Seconds(t0, t4);
  }
  return c;
}

Compliance Compliance::SameNodes() const {
  Compliance c;
  c.material_ = material_;
  c.nodes_ = nodes_;
  c.fixed_ = fixed_;
  c.slot_of_ = slot_of_;
  c.fixed_flag_ = fixed_flag_;
  return c;
}

Compliance Compliance::ConvertedTo(Precision precision) const {
  if (compressed_) throw InputError("", 0, "precision", "a compressed compliance is float32 only");
  if (precision != Precision::kFloat32 && precision != Precision::kFloat64) {
    throw InputError("", 0, "precision", "a compliance is stored in float32 or float64");
  }
  Compliance c = SameNodes();
  c.precision_ = precision;
  detail::Hasher64 h;
  h.Pod(hash_);
  h.Pod(static_cast<std::uint32_t>(precision));
  c.hash_ = precision == precision_ ? hash_ : h.digest();
  if (precision == Precision::kFloat32) {
    c.f32_ = f32_.empty() ? std::vector<float>(f64_.begin(), f64_.end()) : f32_;
  } else {
    c.f64_ = f64_.empty() ? std::vector<double>(f32_.begin(), f32_.end()) : f64_;
  }
  return c;
}

Compliance Compliance::Compressed(const TetMesh& mesh, const CompressionOptions& options,
                                  CompressionStats* stats) const {
  if (compressed_) throw InputError("", 0, "compliance", "already compressed");
  if (mesh.num_nodes() != num_mesh_nodes()) {
    throw InputError(mesh.source(), 0, "mesh", "not the mesh this compliance was computed for");
  }
  std::vector<Eigen::Vector3d> p;
  p.reserve(nodes_.size());
  for (std::int32_t v : nodes_) p.push_back(mesh.positions_m()[v]);
  Compliance c = SameNodes();
  c.precision_ = Precision::kFloat32;
  detail::Hasher64 h;
  h.Pod(hash_);
  h.Pod(options.tolerance);
  h.Pod(options.leaf_nodes);
  h.Pod(options.hierarchical);
  h.Pod(options.eta);
  h.Pod(options.max_block_entries);
  h.Pod(options.weak_admissibility);
  h.Pod(options.factor_precision);
  c.hash_ = h.digest();
  c.compressed_ = std::make_shared<const detail::CompressedBlocks>(
      detail::CompressedBlocks::Build(p, *this, options, stats));
  return c;
}

std::size_t Compliance::storage_bytes() const noexcept {
  return f32_.size() * sizeof(float) + f64_.size() * sizeof(double) +
         (compressed_ ? compressed_->storage_bytes() : 0);
}

Eigen::Matrix3d Compliance::Block(std::int32_t n, std::int32_t k) const noexcept {
  if (compressed_) return compressed_->Block(n, k);
  const bool transpose = n > k;
  if (transpose) std::swap(n, k);
  const std::int64_t off = 9 * PackedIndex(n, k);
  Eigen::Matrix3d B;
  if (precision_ == Precision::kFloat32) {
    B = Eigen::Map<const Eigen::Matrix3f>(f32_.data() + off).cast<double>();
  } else {
    B = Eigen::Map<const Eigen::Matrix3d>(f64_.data() + off);
  }
  if (transpose) B.transposeInPlace();
  return B;
}

void Compliance::Save(const fs::path& file) const {
  if (compressed_) {
    throw CacheError("compliance cache " + file.string() +
                     ": a compressed compliance is not cached; save the packed one and compress after Load");
  }
  FileHeader h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.version = kVersion;
  h.scalar_bytes = static_cast<std::uint32_t>(precision_);
  h.input_hash = hash_;
  h.num_mesh_nodes = slot_of_.size();
  h.num_nodes = nodes_.size();
  h.num_fixed = fixed_.size();
  h.E_Pa = material_.E_Pa;
  h.nu = material_.nu;
  const std::uint64_t idx_bytes = IndexBytes(h.num_nodes, h.num_fixed);
  const std::uint64_t blk_bytes = NumScalars(h.num_nodes) * h.scalar_bytes;
  h.payload_bytes = idx_bytes + blk_bytes;

  std::vector<unsigned char> idx(idx_bytes, 0);
  std::memcpy(idx.data(), nodes_.data(), 4 * nodes_.size());
  std::memcpy(idx.data() + 4 * nodes_.size(), fixed_.data(), 4 * fixed_.size());
  const void* blocks = precision_ == Precision::kFloat32 ? static_cast<const void*>(f32_.data())
                                                         : static_cast<const void*>(f64_.data());
  detail::Hasher64 sum;
  sum.Bytes(idx.data(), idx.size());
  sum.Bytes(blocks, blk_bytes);
  h.payload_checksum = sum.digest();
  h.header_checksum = HeaderChecksum(h);

  // A name of this writer's own: several processes (or a superseded build beside a new one)
  // may compute the same cache at once; each renames a complete file over it.
  static std::atomic<std::uint64_t> writes{0};
  fs::path tmp = file;
  tmp += "." + std::to_string(getpid()) + "." + std::to_string(writes.fetch_add(1)) + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw CacheError("cannot write compliance cache " + tmp.string() + ": " + std::strerror(errno));
    out.write(reinterpret_cast<const char*>(&h), sizeof h);
    out.write(reinterpret_cast<const char*>(idx.data()), static_cast<std::streamsize>(idx.size()));
    out.write(static_cast<const char*>(blocks), static_cast<std::streamsize>(blk_bytes));
    out.flush();
    if (!out) throw CacheError("writing compliance cache " + tmp.string() + " failed (disk full?)");
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec) throw CacheError("cannot rename " + tmp.string() + " to " + file.string() + ": " + ec.message());
}

Compliance Compliance::Load(const fs::path& file, std::uint64_t expected_hash) {
  const std::string name = file.string();
  std::ifstream in(file, std::ios::binary);
  if (!in) throw CacheError("compliance cache " + name + ": cannot open: " + std::strerror(errno));
  const FileHeader h = ReadHeader(in, file, expected_hash);
  Compliance c;
  c.precision_ = static_cast<Precision>(h.scalar_bytes);
  c.material_ = Material{h.E_Pa, h.nu};
  c.hash_ = h.input_hash;
  const std::uint64_t idx_bytes = IndexBytes(h.num_nodes, h.num_fixed);
  std::vector<unsigned char> idx(idx_bytes);
  in.read(reinterpret_cast<char*>(idx.data()), static_cast<std::streamsize>(idx_bytes));
  const std::uint64_t scalars = NumScalars(h.num_nodes);
  void* blocks = nullptr;
  if (c.precision_ == Precision::kFloat32) {
    c.f32_.resize(scalars);
    blocks = c.f32_.data();
  } else {
    c.f64_.resize(scalars);
    blocks = c.f64_.data();
  }
  in.read(static_cast<char*>(blocks), static_cast<std::streamsize>(scalars * h.scalar_bytes));
  if (!in) throw CacheError("compliance cache " + name + ": read error (truncated while reading?)");
  detail::Hasher64 sum;
  sum.Bytes(idx.data(), idx.size());
  sum.Bytes(blocks, scalars * h.scalar_bytes);
  if (sum.digest() != h.payload_checksum) {
    throw CacheError("compliance cache " + name + ": corrupt data (checksum mismatch)");
  }
  c.nodes_.resize(h.num_nodes);
  c.fixed_.resize(h.num_fixed);
  std::memcpy(c.nodes_.data(), idx.data(), 4 * h.num_nodes);
  std::memcpy(c.fixed_.data(), idx.data() + 4 * h.num_nodes, 4 * h.num_fixed);
  const auto nm = static_cast<std::int32_t>(h.num_mesh_nodes);
  for (std::int32_t v : c.nodes_) {
    if (v < 0 || v >= nm) throw CacheError("compliance cache " + name + ": corrupt node list");
  }
  for (std::int32_t v : c.fixed_) {
    if (v < 0 || v >= nm) throw CacheError("compliance cache " + name + ": corrupt fixed list");
  }
  c.BuildLookup(nm);
  return c;
}

Compliance Compliance::LoadOrPrecompute(const fs::path& cache, const TetMesh& mesh,
                                        const Material& material,
                                        std::span<const std::int32_t> fixed_nodes,
                                        const ComplianceOptions& options,
                                        const ProgressFn& progress, std::string* note,
                                        PrecomputeStats* stats) {
  const std::uint64_t hash = InputHash(mesh, material, fixed_nodes, options);
  std::string why;
  if (fs::exists(cache)) {
    try {
      Compliance c = Load(cache, hash);
      if (note != nullptr) *note = "loaded " + cache.string();
      return c;
    } catch (const CacheError& e) {
      why = std::string(e.what()) + "; recomputing";
    }
  } else {
    why = "no cache at " + cache.string() + "; computing";
  }
  Compliance c = Precompute(mesh, material, fixed_nodes, options, progress, stats);
  c.Save(cache);
  if (note != nullptr) *note = why + "; saved " + cache.string();
  return c;
}

}  // namespace handshare::fem
