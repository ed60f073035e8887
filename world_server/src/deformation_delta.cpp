#include "handshare/world_server/deformation_delta.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace handshare::server {

DeformationDelta::DeformationDelta(std::size_t surface_node_count, DeformationDeltaConfig config)
    : config_(config), sent_(3 * surface_node_count, 0.0) {
  if (surface_node_count == 0) throw std::invalid_argument("DeformationDelta: an object without surface nodes");
  if (surface_node_count > UINT32_MAX) throw std::invalid_argument("DeformationDelta: more than 2^32 surface nodes");
  if (!(config.threshold_m > 0.0)) throw std::invalid_argument("DeformationDelta: threshold_m must be > 0");
  if (config.max_nodes_per_sample == 0) throw std::invalid_argument("DeformationDelta: max_nodes_per_sample must be > 0");
  // Storage for the largest update (every node), sized once so that Update never allocates.
  const std::size_t per_sample = std::min(surface_node_count, config.max_nodes_per_sample);
  const std::size_t samples = (surface_node_count + config.max_nodes_per_sample - 1) / config.max_nodes_per_sample;
  samples_.resize(samples);
  for (auto& s : samples_) {
    s.surface_node_count = static_cast<std::uint32_t>(surface_node_count);
    s.node_ids.reserve(per_sample);
    s.u_W_m.reserve(3 * per_sample);
  }
}

DeformationSample& DeformationDelta::Open(bool keyframe) {
  DeformationSample& s = samples_[used_++];  // sized for every node: never out of range
  s.revision = revision_ + 1;
  s.keyframe = keyframe;
  s.node_ids.clear();
  s.u_W_m.clear();
  return s;
}

void DeformationDelta::Add(std::uint32_t node, const double* u) {
  if (used_ == 0 || samples_[used_ - 1].node_ids.size() >= config_.max_nodes_per_sample) Open(keyframe_);
  DeformationSample& s = samples_[used_ - 1];
  s.node_ids.push_back(node);
  for (int k = 0; k < 3; ++k) {
    // The receiver holds the float it is sent; compare later updates against exactly that.
    const float value = static_cast<float>(u[k]);
    s.u_W_m.push_back(value);
    sent_[3 * node + k] = value;
  }
}

std::span<const DeformationSample> DeformationDelta::Update(std::span<const double> u_W_m, Time now) {
  if (u_W_m.size() != sent_.size()) {
    throw std::invalid_argument("DeformationDelta::Update: " + std::to_string(u_W_m.size()) + " values for " +
                                std::to_string(sent_.size() / 3) + " nodes (3 per node expected)");
  }
  used_ = 0;
  if (started_ && now - last_send_ < config_.min_period) return {};
  keyframe_ = !started_ || keyframe_requested_ ||
              (changed_since_keyframe_ && now - last_keyframe_ >= config_.keyframe_period);
  const double threshold2 = config_.threshold_m * config_.threshold_m;
  const std::size_t n = sent_.size() / 3;
  for (std::size_t i = 0; i < n; ++i) {
    const double* u = &u_W_m[3 * i];
    if (!std::isfinite(u[0]) || !std::isfinite(u[1]) || !std::isfinite(u[2])) {
      // A solver fault: send nothing for this node; receivers keep their value, which a
      // keyframe resets to zero.
      ++nonfinite_skipped_;
      if (keyframe_) sent_[3 * i] = sent_[3 * i + 1] = sent_[3 * i + 2] = 0.0;
      continue;
    }
    const auto node = static_cast<std::uint32_t>(i);
    if (keyframe_) {
      // Receivers zero every node on a keyframe: list the ones that are not (near) zero.
      if (config_.keyframe_all_nodes || u[0] * u[0] + u[1] * u[1] + u[2] * u[2] > threshold2) {
        Add(node, u);
      } else {
        sent_[3 * i] = sent_[3 * i + 1] = sent_[3 * i + 2] = 0.0;
      }
    } else {
      const double* s = &sent_[3 * i];
      const double dx = u[0] - s[0], dy = u[1] - s[1], dz = u[2] - s[2];
      if (dx * dx + dy * dy + dz * dz > threshold2) Add(node, u);
    }
  }
  if (keyframe_) {
    if (used_ == 0) Open(true);  // an empty keyframe still says "everything at rest"
    started_ = true;
    keyframe_requested_ = false;
    changed_since_keyframe_ = false;
    last_keyframe_ = now;
    ++keyframes_sent_;
  } else {
    if (used_ == 0) return {};  // nothing moved enough: send nothing
    changed_since_keyframe_ = true;
  }
  ++revision_;
  last_send_ = now;
  return {samples_.data(), used_};
}

}  // namespace handshare::server
