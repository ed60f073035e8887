#pragma once
/// One object's surface displacement field as a graphics node holds it, fed by the Deformation
/// topic. Plain data and logic: no middleware, no OpenGL.
///
/// Contract with the publisher (the world server):
///   - node_ids are vertex indices of the object's mesh as scene::LoadMesh loads it (same
///     order, scale 1); ids >= the vertex count are ignored and counted;
///   - u_W_m holds 3 floats per node id: the displacement of that vertex in the world frame W [m];
///   - receiver rule (world_server/.../deformation_delta.hpp): a keyframe sample of a revision
///     not seen before sets every vertex to zero first; every sample then sets
///     u[node_ids[i]] = (u_W_m[3i], u_W_m[3i+1], u_W_m[3i+2]).
/// "Not seen before" is "different from the revision of the last sample applied": split
/// samples of one revision arrive in order from one writer, and a restarted writer that counts
/// from 1 again still gets its first keyframe applied as a keyframe.
///
/// Not real-time (the graphics thread). Apply allocates nothing after construction.
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace handshare::graphics {

/// What a field did with the samples it was given.
struct DeformationStats {
  std::uint64_t samples = 0;           ///< samples applied (keyframes included)
  std::uint64_t keyframes = 0;         ///< keyframe samples that zeroed the field
  std::uint64_t ids_out_of_range = 0;  ///< node ids >= vertex_count, ignored
  std::uint64_t nonfinite = 0;         ///< entries with a non-finite displacement, ignored
  std::uint64_t malformed = 0;         ///< samples with u_W_m.size() != 3 node_ids.size(), ignored whole
};

class DeformationField {
 public:
  /// A field of vertex_count vertices, all at zero displacement, no revision seen.
  explicit DeformationField(std::size_t vertex_count);

  /// Applies one Deformation sample by the receiver rule above. Returns false (and changes
  /// nothing but the malformed count) when u_W_m does not hold 3 values per node id.
  bool Apply(std::uint32_t revision, bool keyframe, std::span<const std::uint32_t> node_ids,
             std::span<const float> u_W_m);

  /// Back to zero displacement with no revision seen (another scene). Keeps the statistics.
  void Reset();

  std::size_t vertex_count() const { return u_W_m_.size(); }
  /// u_W_m()[v]: displacement of vertex v in W [m].
  const std::vector<Eigen::Vector3d>& u_W_m() const { return u_W_m_; }
  /// Revision of the last sample applied; empty before the first (or after Reset).
  std::optional<std::uint32_t> revision() const { return revision_; }
  /// True if any vertex has a non-zero displacement.
  bool displaced() const { return displaced_count_ > 0; }
  /// Bumped on every change of the field, so drawers can cache what they derive from it.
  std::uint64_t version() const { return version_; }
  const DeformationStats& stats() const { return stats_; }

 private:
  void Set(std::size_t vertex, const Eigen::Vector3d& u);

  std::vector<Eigen::Vector3d> u_W_m_;
  std::size_t displaced_count_ = 0;  // vertices with u != 0
  std::optional<std::uint32_t> revision_;
  std::uint64_t version_ = 0;
  DeformationStats stats_;
};

}  // namespace handshare::graphics
