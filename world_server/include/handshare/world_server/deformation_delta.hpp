#pragma once
/// What to publish of one deformable object's surface displacements (the Deformation topic):
/// only the nodes that moved more than a threshold since they were last sent, a keyframe when a
/// reader joins and periodically while the object keeps changing, and nothing at all while it
/// rests. Samples carry at most max_nodes_per_sample nodes (the IDL's kMaxSurfaceDelta = 4096);
/// a larger update is split into several samples with the same revision. Pure logic, no DDS.
///
/// Receiver rule (what graphics nodes do with the samples):
///   - a keyframe sample of a revision not seen before: set every node to zero, then apply;
///   - any sample: u[node_ids[i]] = (u_W_m[3i], u_W_m[3i+1], u_W_m[3i+2]).
/// Invariant: after every Update, each node's displacement as the receiver holds it is within
/// threshold_m of the true one (a keyframe leaves out nodes whose |u| <= threshold_m unless
/// keyframe_all_nodes). Nodes that were never sent are zero for the receiver.
///
/// Not real-time: meant for the world server's tick (<= 60 Hz). After warm-up (the first
/// keyframe) Update allocates nothing.
#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

namespace handshare::server {

struct DeformationDeltaConfig {
  double threshold_m = 1e-4;           // re-send a node when it moved more than this [m]
  std::chrono::nanoseconds keyframe_period = std::chrono::seconds(2);  // while the object changes
  std::chrono::nanoseconds min_period = std::chrono::nanoseconds(1'000'000'000 / 60);  // <= 60 Hz
  std::size_t max_nodes_per_sample = 4096;  // msg::kMaxSurfaceDelta
  bool keyframe_all_nodes = false;      // keyframes carry every node, not only displaced ones
};

/// One Deformation sample's content (the world server adds object_id and session).
struct DeformationSample {
  std::uint32_t revision = 0;          // one per Update that sends; shared by its split samples
  bool keyframe = false;
  std::uint32_t surface_node_count = 0;
  std::vector<std::uint32_t> node_ids;
  std::vector<float> u_W_m;            // 3 per node id, in W [m]
};

class DeformationDelta {
 public:
  using Time = std::chrono::steady_clock::time_point;

  /// Throws std::invalid_argument for 0 nodes, a non-positive threshold or sample size.
  DeformationDelta(std::size_t surface_node_count, DeformationDeltaConfig config = {});

  /// A reader joined: the next Update sends a keyframe (even if nothing changed).
  void RequestKeyframe() { keyframe_requested_ = true; }

  /// u_W_m: 3 x surface_node_count displacements (x, y, z per node) at time now. Returns the
  /// samples to publish now, empty when nothing needs sending or when called sooner than
  /// min_period after the last send (changes are kept for the next call). The first call
  /// sends a keyframe. Non-finite displacements are skipped and counted. The span is valid
  /// until the next call. Throws std::invalid_argument for a wrong size.
  std::span<const DeformationSample> Update(std::span<const double> u_W_m, Time now);

  std::size_t surface_node_count() const { return sent_.size() / 3; }
  std::uint32_t revision() const { return revision_; }
  /// What the receivers hold (3 per node), for tests and for a late check.
  std::span<const double> sent() const { return sent_; }
  std::uint64_t nonfinite_skipped() const { return nonfinite_skipped_; }
  std::uint64_t keyframes_sent() const { return keyframes_sent_; }

 private:
  // Appends node i with displacement u (3 values) to the current samples.
  void Add(std::uint32_t node, const double* u);
  DeformationSample& Open(bool keyframe);

  DeformationDeltaConfig config_;
  std::vector<double> sent_;
  std::vector<DeformationSample> samples_;  // storage reused between calls
  std::size_t used_ = 0;                    // samples_ in use by the current call
  bool keyframe_ = false;
  std::uint32_t revision_ = 0;
  bool started_ = false;
  bool keyframe_requested_ = false;
  bool changed_since_keyframe_ = false;
  Time last_send_{};
  Time last_keyframe_{};
  std::uint64_t nonfinite_skipped_ = 0;
  std::uint64_t keyframes_sent_ = 0;
};

}  // namespace handshare::server
