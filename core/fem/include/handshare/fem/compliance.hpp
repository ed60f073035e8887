#pragma once
/// @file
/// The precomputed compliance of an object: the 3x3 blocks C_nk = (K_ff^-1)_nk [m/N] between
/// its compliance nodes (by default every free surface node), stored once per symmetric pair
/// (upper-triangle blocks, packed by columns), in float32 or float64, with a versioned,
/// checksummed cache file. Precompute and file I/O are offline; the block accessors are
/// real-time safe (noexcept, no allocation).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/assembly.hpp"
#include "handshare/fem/mesh.hpp"

namespace handshare::fem {

/// Storage precision (the value is the scalar size in bytes). kFloat16 (IEEE half, with a float
/// scale per 16-node chunk) only for the surface-field tables (SurfaceField kColumns, T^d), never
/// for the compliance itself.
/// kInt16 (fixed point, one float scale per column, integer dot products) only for the SurfaceField
/// kColumns table (its value 0x102: 2 bytes, not a float).
enum class Precision : std::uint32_t { kFloat16 = 2, kFloat32 = 4, kFloat64 = 8, kInt16 = 0x102 };

/// How the blocks are computed (same numbers to round-off, different cost).
enum class PrecomputeMethod : std::uint32_t {
  /// Pick the cheaper of the two from CHOLMOD's flop estimates.
  kAuto,
  /// Factor K_ff with a fill-reducing ordering, solve for 3 unit loads per compliance node in
  /// blocks of right-hand sides: about 4 nnz(L) flops per column. Best when most nodes are on
  /// the surface (thin objects).
  kBlockedSolves,
  /// Order the compliance DOFs last: the trailing block of the factor is the Cholesky factor of
  /// the Schur complement S onto them (the condensed surface stiffness), and C = S^-1 is one dense
  /// inversion (LAPACK dpotri, (2/3) (3N)^3 flops). Best for solid objects with many interior
  /// nodes.
  kSchurComplement,
};

/// What to precompute.
struct ComplianceOptions {
  Precision precision = Precision::kFloat64;
  /// Compliance nodes (mesh indices, distinct, not fixed, used by an element). Empty: every
  /// surface node that is not fixed, in increasing index order.
  std::vector<std::int32_t> nodes;
  /// Right-hand sides solved together, in nodes (3 columns each); 0 picks a size that keeps the
  /// block under about 256 MiB. kBlockedSolves only.
  int block_nodes = 0;
  PrecomputeMethod method = PrecomputeMethod::kAuto;
};

/// Timings and sizes of one precomputation.
struct PrecomputeStats {
  PrecomputeMethod method = PrecomputeMethod::kAuto;  ///< the one used
  std::int64_t free_dofs = 0;
  std::int64_t factor_nonzeros = 0;
  double factor_flops = 0;
  double assemble_s = 0, analyze_s = 0, factor_s = 0, solve_s = 0, total_s = 0;
};

/// How the blocks are stored.
enum class ComplianceStorage : std::uint32_t {
  /// Every block C_nk, n <= k, packed by columns (exact to the storage precision).
  kPacked,
  /// Hierarchical block low-rank (see Compliance::Compressed): a k-d cluster tree, far cluster
  /// pairs as one U V^T within a relative tolerance where that is smaller, near leaf pairs dense
  /// or low-rank, diagonal leaf tiles as their upper triangle. float32 (low-rank factors float16
  /// on request, CompressionOptions::factor_precision).
  kCompressed,
};

/// Options of Compliance::Compressed.
struct CompressionOptions {
  /// Each low-rank block A is replaced by U V^T only if ||A - U V^T||_F <= tolerance ||A||_F
  /// (checked on the explicit residual), so ||C - C~||_F <= tolerance ||C||_F overall.
  double tolerance = 1e-4;
  /// Most nodes per cluster (k-d tree leaf): tiles are up to 3 leaf_nodes square.
  int leaf_nodes = 32;
  /// Hierarchical (H-matrix) partition: a pair of k-d clusters (s, t) is tried as one low-rank
  /// block when min(diam s, diam t) <= eta dist(s, t) (bounding boxes); it is kept if it meets the
  /// tolerance and stores fewer floats than its split (computed too), else it is split down to
  /// leaf tiles. false: the flat grid of leaf tiles only (every off-diagonal leaf pair on its own).
  bool hierarchical = true;
  /// Admissibility parameter of the hierarchical partition, in (0, 100]. Since a block is kept
  /// only where it beats its split, a larger eta only tries more (nearer) pairs: measured storage
  /// at 584 / 1,961 / 4,441 nodes, tolerance 1e-3, eta 4 -> 16: 7.1 -> 5.6, 2.9 -> 2.6,
  /// 1.6 -> 1.5 N^2 bytes, eta 100 within 1% of 16, at similar build times (measured with the
  /// diagonal tiles stored full; storing their upper triangle takes 0.55 / 0.28 / 0.07 N^2 off).
  double eta = 16.0;
  /// Largest block (entries, 3 |s| x 3 |t|) compressed explicitly; larger admissible pairs are
  /// split (bounds the build memory: 16 bytes per entry, 64 MB at the default).
  std::int64_t max_block_entries = std::int64_t{1} << 22;
  /// Weak admissibility: also try off-diagonal cluster pairs that touch or are near (eta fails)
  /// as one low-rank block, under the same tolerance check and keep-or-split rule (so it never
  /// stores more than without; it costs build time).
  bool weak_admissibility = false;
  /// Storage of the low-rank factors: kFloat32, or kFloat16 (opt-in) where each block's columns
  /// are scaled to a largest entry of 1 and stored in float16 with one float32 scale per rank.
  /// The float16 rounding is part of the explicit residual that picks the rank, so the tolerance
  /// holds as computed; a block whose float16 factors cannot meet it (or do not save memory)
  /// keeps float32 factors. Dense tiles stay float32.
  Precision factor_precision = Precision::kFloat32;
};

/// What a compression produced.
struct CompressionStats {
  std::int64_t tiles = 0;           ///< leaf tiles (cluster pairs I <= J of the tile table)
  std::int64_t low_rank_tiles = 0;  ///< tiles that are views into low-rank factors
  std::int64_t low_rank_blocks = 0; ///< low-rank blocks (one U V^T each; a block spans >= 1 tile)
  double mean_rank = 0;             ///< over the low-rank blocks
  int max_rank = 0;                 ///< over the low-rank blocks
  std::int64_t largest_block_entries = 0;  ///< of the low-rank blocks, 3 |s| x 3 |t|
  std::int64_t dense_bytes = 0;     ///< dense tiles (diagonal and near, O(N))
  std::int64_t factor_bytes = 0;    ///< U, V factors
  std::int64_t table_bytes = 0;     ///< tile table (L (L + 1) / 2 entries) and node orderings
  std::int64_t blocks_tried = 0;    ///< explicit compressions attempted (kept or split)
  double seconds = 0;
  std::int64_t half_blocks = 0;     ///< low-rank blocks with float16 factors
};

namespace detail {
class CompressedBlocks;
}  // namespace detail

/// Progress callback: (compliance nodes done, total). Called from the precomputing thread.
using ProgressFn = std::function<void(std::int64_t done, std::int64_t total)>;

/// Compliance blocks of one object for one material and one fixed boundary.
class Compliance {
 public:
  Compliance() = default;

  /// Assembles K, factors K_ff once (CHOLMOD supernodal), and solves for the unit loads of all
  /// compliance nodes in blocks of right-hand sides.
  /// @throws InputError for bad nodes or material; FemError if K_ff is singular.
  static Compliance Precompute(const TetMesh& mesh, const Material& material,
                               std::span<const std::int32_t> fixed_nodes,
                               const ComplianceOptions& options = {},
                               const ProgressFn& progress = {}, PrecomputeStats* stats = nullptr);

  /// Hash of everything the blocks depend on: node positions, elements, material, fixed nodes,
  /// compliance nodes (resolved as Precompute would) and precision.
  static std::uint64_t InputHash(const TetMesh& mesh, const Material& material,
                                 std::span<const std::int32_t> fixed_nodes,
                                 const ComplianceOptions& options);

  /// Writes the cache file (header, node lists, blocks; checksums), atomically (temp + rename).
  /// @throws CacheError if it cannot be written or the compliance is compressed.
  void Save(const std::filesystem::path& file) const;
  /// Reads and verifies a cache file.
  /// @param expected_hash  InputHash of the current mesh and material; 0 skips that check.
  /// @throws CacheError naming the file: missing, not a cache, version, stale (hash), truncated,
  ///         corrupt (checksum).
  static Compliance Load(const std::filesystem::path& file, std::uint64_t expected_hash = 0);

  /// Loads `cache` if it matches the inputs, else precomputes and saves it.
  /// @param note  if given, receives why the cache was (not) used.
  static Compliance LoadOrPrecompute(const std::filesystem::path& cache, const TetMesh& mesh,
                                     const Material& material,
                                     std::span<const std::int32_t> fixed_nodes,
                                     const ComplianceOptions& options = {},
                                     const ProgressFn& progress = {},
                                     std::string* note = nullptr,
                                     PrecomputeStats* stats = nullptr);

  /// A copy stored in another precision (e.g. a float64 cache used as float32). The input hash
  /// is recomputed from the stored one, so caches of both precisions can live side by side.
  /// @throws InputError for a compressed compliance or kFloat16.
  Compliance ConvertedTo(Precision precision) const;

  /// A compressed copy (storage kCompressed, float32; low-rank factors float16 on request),
  /// built offline from this packed one: an H-matrix (far cluster pairs as one U V^T each; see
  /// CompressionOptions) instead of 9 N^2 / 2 scalars. Diagonal tiles (every node with its
  /// cluster, so C_kk and the coupling of nearby touched nodes) stay dense (their upper
  /// triangle) and exact to float32;
  /// far couplings carry at most the tolerance. Everything real-time (ContactSolver,
  /// SurfaceField, Block) works on it unchanged. Not saved by Save() (rebuilt from the cache).
  /// @param mesh  the mesh it was computed for (node positions for the clustering).
  /// @throws InputError for bad options, another mesh, or an already compressed compliance.
  Compliance Compressed(const TetMesh& mesh, const CompressionOptions& options = {},
                        CompressionStats* stats = nullptr) const;
  ComplianceStorage storage() const noexcept {
    return compressed_ ? ComplianceStorage::kCompressed : ComplianceStorage::kPacked;
  }
  /// The compressed blocks (internal), or nullptr when packed.
  const detail::CompressedBlocks* compressed() const noexcept { return compressed_.get(); }

  // ---- Accessors (real-time safe) ----

  /// Number N of compliance nodes ("slots").
  std::int32_t num_nodes() const noexcept { return static_cast<std::int32_t>(nodes_.size()); }
  /// Number of nodes of the mesh it was computed for.
  std::int32_t num_mesh_nodes() const noexcept { return static_cast<std::int32_t>(slot_of_.size()); }
  /// Slot -> mesh node index.
  std::span<const std::int32_t> nodes() const noexcept { return nodes_; }
  /// Fixed mesh nodes (sorted).
  std::span<const std::int32_t> fixed_nodes() const noexcept { return fixed_; }
  /// Mesh node index -> slot, -1 if not a compliance node or out of range.
  std::int32_t SlotOf(std::int32_t mesh_node) const noexcept {
    return (mesh_node >= 0 && mesh_node < num_mesh_nodes()) ? slot_of_[mesh_node] : -1;
  }
  /// True if the mesh node is fixed.
  bool IsFixed(std::int32_t mesh_node) const noexcept {
    return mesh_node >= 0 && mesh_node < num_mesh_nodes() && fixed_flag_[mesh_node] != 0;
  }
  Precision precision() const noexcept { return precision_; }
  const Material& material() const noexcept { return material_; }
  std::uint64_t input_hash() const noexcept { return hash_; }

  /// C_nk [m/N] for slots n, k in any order (C_kn = C_nk^T).
  Eigen::Matrix3d Block(std::int32_t n, std::int32_t k) const noexcept;

  /// Index of the stored block (n, k), n <= k: k (k + 1) / 2 + n. Each block is 9 scalars,
  /// column-major.
  static std::int64_t PackedIndex(std::int32_t n, std::int32_t k) noexcept {
    return static_cast<std::int64_t>(k) * (k + 1) / 2 + n;
  }
  /// Raw packed storage (valid for the matching precision and kPacked, else nullptr).
  const float* data_f32() const noexcept { return f32_.empty() ? nullptr : f32_.data(); }
  const double* data_f64() const noexcept { return f64_.empty() ? nullptr : f64_.data(); }
  /// Bytes of block storage: 9 N (N + 1) / 2 scalars when packed; tiles, factors and the
  /// cluster tables when compressed.
  std::size_t storage_bytes() const noexcept;

 private:
  /// A compliance of the same nodes, material and fixed set, with no blocks yet.
  Compliance SameNodes() const;
  void BuildLookup(std::int32_t num_mesh_nodes);

  Precision precision_ = Precision::kFloat64;
  Material material_;
  std::uint64_t hash_ = 0;
  std::vector<std::int32_t> nodes_;
  std::vector<std::int32_t> fixed_;
  std::vector<std::int32_t> slot_of_;
  std::vector<std::uint8_t> fixed_flag_;
  std::vector<float> f32_;
  std::vector<double> f64_;
  std::shared_ptr<const detail::CompressedBlocks> compressed_;
};

/// Resolves ComplianceOptions::nodes (empty -> free surface nodes) and checks them.
std::vector<std::int32_t> ResolveComplianceNodes(const TetMesh& mesh,
                                                 std::span<const std::int32_t> fixed_nodes,
                                                 std::span<const std::int32_t> requested);

}  // namespace handshare::fem
