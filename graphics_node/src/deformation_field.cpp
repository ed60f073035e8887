#include "handshare/graphics/deformation_field.hpp"

#include <cmath>

namespace handshare::graphics {

DeformationField::DeformationField(std::size_t vertex_count)
    : u_W_m_(vertex_count, Eigen::Vector3d::Zero()) {}

void DeformationField::Set(std::size_t vertex, const Eigen::Vector3d& u) {
  const bool was = !u_W_m_[vertex].isZero(0.0);
  const bool is = !u.isZero(0.0);
  u_W_m_[vertex] = u;
  if (was != is) {
    if (is) {
      ++displaced_count_;
    } else {
      --displaced_count_;
    }
  }
}

bool DeformationField::Apply(std::uint32_t revision, bool keyframe,
                             std::span<const std::uint32_t> node_ids,
                             std::span<const float> u_W_m) {
  if (u_W_m.size() != 3 * node_ids.size()) {
    ++stats_.malformed;
    return false;
  }
  // Receiver rule: the first sample of a new keyframe revision starts from zero.
  if (keyframe && revision_ != revision) {
    if (displaced_count_ > 0) {
      for (auto& u : u_W_m_) u.setZero();
      displaced_count_ = 0;
    }
    ++stats_.keyframes;
  }
  for (std::size_t i = 0; i < node_ids.size(); ++i) {
    if (node_ids[i] >= u_W_m_.size()) {
      ++stats_.ids_out_of_range;
      continue;
    }
    const Eigen::Vector3d u(u_W_m[3 * i], u_W_m[3 * i + 1], u_W_m[3 * i + 2]);
    if (!u.allFinite()) {
      ++stats_.nonfinite;
      continue;
    }
    Set(node_ids[i], u);
  }
  revision_ = revision;
  ++stats_.samples;
  ++version_;
  return true;
}

void DeformationField::Reset() {
  for (auto& u : u_W_m_) u.setZero();
  displaced_count_ = 0;
  revision_.reset();
  ++version_;
}

}  // namespace handshare::graphics
