#include "handshare/fem/contact_patch.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "handshare/fem/error.hpp"

namespace handshare::fem {
namespace {

constexpr std::int64_t kBits = 21;
constexpr std::int64_t kMaxCell = (1ll << kBits) - 1;

std::int64_t Key(std::int64_t ix, std::int64_t iy, std::int64_t iz) noexcept {
  return (ix << (2 * kBits)) | (iy << kBits) | iz;
}

}  // namespace

ContactPatchFinder::ContactPatchFinder(const TetMesh& mesh, const Surface& surface,
                                       const Compliance& compliance) {
  if (compliance.num_mesh_nodes() != mesh.num_nodes()) {
    throw InputError(mesh.source(), 0, "compliance",
                     "computed for a mesh with " + std::to_string(compliance.num_mesh_nodes()) +
                         " nodes, this one has " + std::to_string(mesh.num_nodes()));
  }
  const std::int32_t N = compliance.num_nodes();
  mesh_node_of_slot_.assign(compliance.nodes().begin(), compliance.nodes().end());
  p_mesh_m_ = mesh.positions_m();
  p_m_.resize(N);
  n_.assign(N, Eigen::Vector3d::Zero());
  for (std::int32_t s = 0; s < N; ++s) p_m_[s] = mesh.positions_m()[mesh_node_of_slot_[s]];
  for (std::size_t i = 0; i < surface.nodes.size(); ++i) {
    const std::int32_t s = compliance.SlotOf(surface.nodes[i]);
    if (s >= 0) n_[s] = surface.normals[i];
  }
  // Cell size: twice the mean surface edge length, so a query visits few, well-filled cells.
  double edge_sum = 0.0;
  std::size_t edges = 0;
  const auto& p = mesh.positions_m();
  for (const Triangle& t : surface.triangles) {
    for (int e = 0; e < 3; ++e) {
      edge_sum += (p[t[(e + 1) % 3]] - p[t[e]]).norm();
      ++edges;
    }
  }
  Eigen::Vector3d lo = p_m_.empty() ? Eigen::Vector3d::Zero() : p_m_[0];
  Eigen::Vector3d hi = lo;
  for (const auto& x : p_m_) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  cell_m_ = edges > 0 ? 2.0 * edge_sum / static_cast<double>(edges) : 1.0;
  cell_m_ = std::max(cell_m_, (hi - lo).maxCoeff() / static_cast<double>(kMaxCell - 2));
  if (!(cell_m_ > 0.0)) cell_m_ = 1.0;
  origin_m_ = lo;
  std::vector<std::pair<std::int64_t, std::int32_t>> entries(N);
  for (std::int32_t s = 0; s < N; ++s) {
    const Eigen::Vector3d c = ((p_m_[s] - origin_m_) / cell_m_).array().floor();
    entries[s] = {Key(static_cast<std::int64_t>(c.x()), static_cast<std::int64_t>(c.y()),
                      static_cast<std::int64_t>(c.z())),
                  s};
  }
  std::sort(entries.begin(), entries.end());
  keys_.resize(N);
  slots_.resize(N);
  for (std::int32_t i = 0; i < N; ++i) {
    keys_[i] = entries[i].first;
    slots_[i] = entries[i].second;
  }
}

template <class DepthFn>
PatchResult ContactPatchFinder::Collect(const Eigen::Vector3d& p_W, const Eigen::Vector3d& n_in,
                                        double a_m, ContactMode mode, std::span<ContactInput> out,
                                        const DepthFn& depth_at_r) const noexcept {
  PatchResult res;
  res.contact_radius_m = a_m;
  const double nn = n_in.norm();
  if (!p_W.allFinite() || !n_in.allFinite() || !(nn > 0.0) || !(a_m > 0.0) || !std::isfinite(a_m)) {
    return res;
  }
  const Eigen::Vector3d n = n_in / nn;
  // Nodes within a of the contact point in the tangent plane, close to that plane, and on a part
  // of the surface that faces the fingertip (not the far side of a thin object).
  const double slab_m = std::max(a_m, cell_m_);
  auto visit = [&](std::int32_t s) {
    const Eigen::Vector3d d = p_m_[s] - p_W;
    const double h = d.dot(n);
    if (std::abs(h) > slab_m) return;
    const double r = (d - h * n).norm();
    if (r >= a_m) return;
    if (n_[s].dot(n) < 0.3) return;
    const double w = depth_at_r(r);
    if (!(w > 0.0)) return;
    ContactInput c;
    c.node = mesh_node_of_slot_[s];
    c.u_m = -w * n;
    c.n_out = n;
    c.mode = mode;
    if (res.count < static_cast<std::int32_t>(out.size())) {
      out[res.count++] = c;
      return;
    }
    // Full: keep the closest nodes (replace the farthest if this one is closer).
    res.truncated = true;
    std::int32_t worst = -1;
    double worst_r = r;
    for (std::int32_t k = 0; k < res.count; ++k) {
      const Eigen::Vector3d dk = p_mesh_m_[out[k].node] - p_W;
      const double rk = (dk - dk.dot(n) * n).norm();
      if (rk > worst_r) {
        worst_r = rk;
        worst = k;
      }
    }
    if (worst >= 0) out[worst] = c;
  };
  // The nodes it takes lie in the cylinder r < a, |h| <= slab about n: its bounding box reaches
  // slab |n_k| + a sqrt(1 - n_k^2) along axis k (a flat patch's box is a wide and 2 slab deep,
  // where a ball of the cylinder's corner radius visited about three times the cells). The
  // slack covers the round-off of h and r; the cells are visited in the same order as before,
  // so the same nodes come out in the same order.
  const Eigen::Array3d reach =
      slab_m * n.array().abs() + a_m * (1.0 - n.array().square()).max(0.0).sqrt() + 1e-9 * (slab_m + a_m);
  const Eigen::Vector3d lo = ((p_W.array() - reach - origin_m_.array()) / cell_m_).floor();
  const Eigen::Vector3d hi = ((p_W.array() + reach - origin_m_.array()) / cell_m_).floor();
  const double cells = (hi - lo + Eigen::Vector3d::Ones()).prod();
  if (!(cells < static_cast<double>(keys_.size()))) {
    for (std::int32_t s = 0; s < static_cast<std::int32_t>(p_m_.size()); ++s) visit(s);
    return res;
  }
  const auto clamp = [](double v) {
    return static_cast<std::int64_t>(std::clamp(v, 0.0, static_cast<double>(kMaxCell)));
  };
  // The cells of one (ix, iy) column have consecutive keys, and the columns come in increasing
  // key order: one search per column, each starting where the last one ended. Visits the same
  // nodes in the same order as one search per cell.
  const std::int64_t iz0 = clamp(lo.z()), iz1 = clamp(hi.z());
  auto from = keys_.begin();
  for (std::int64_t ix = clamp(lo.x()); ix <= clamp(hi.x()); ++ix)
    for (std::int64_t iy = clamp(lo.y()); iy <= clamp(hi.y()); ++iy) {
      const std::int64_t key_hi = Key(ix, iy, iz1);
      auto it = std::lower_bound(from, keys_.end(), Key(ix, iy, iz0));
      for (; it != keys_.end() && *it <= key_hi; ++it) {
        visit(slots_[static_cast<std::size_t>(it - keys_.begin())]);
      }
      from = it;
    }
  return res;
}

PatchResult ContactPatchFinder::Sphere(const Eigen::Vector3d& p_W, const Eigen::Vector3d& n_out,
                                       double R_m, double depth_m, ContactMode mode,
                                       std::span<ContactInput> out) const noexcept {
  if (!(R_m > 0.0) || !(depth_m > 0.0) || !std::isfinite(R_m) || !std::isfinite(depth_m)) {
    return {};
  }
  // Paraboloid approximation of the sphere (as in Hertz theory): overlap delta - r^2 / (2R),
  // zero at a = sqrt(2 R delta).
  const double a = std::sqrt(2.0 * R_m * depth_m);
  return Collect(p_W, n_out, a, mode, out,
                 [&](double r) { return depth_m - r * r / (2.0 * R_m); });
}

PatchResult ContactPatchFinder::FlatPunch(const Eigen::Vector3d& p_W, const Eigen::Vector3d& n_out,
                                          double a_m, double depth_m, ContactMode mode,
                                          std::span<ContactInput> out) const noexcept {
  if (!(depth_m > 0.0) || !std::isfinite(depth_m)) return {};
  return Collect(p_W, n_out, a_m, mode, out, [&](double) { return depth_m; });
}

}  // namespace handshare::fem
