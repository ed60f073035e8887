#include "handshare/contact/tri_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

namespace handshare::contact {

void TriMesh::Validate() const {
  if (p_O_m.empty() || triangles.empty()) throw std::invalid_argument("TriMesh: no vertices or triangles");
  for (std::size_t i = 0; i < p_O_m.size(); ++i) {
    if (!p_O_m[i].allFinite()) {
      throw std::invalid_argument("TriMesh: vertex " + std::to_string(i) + " is not finite");
    }
  }
  const auto n = static_cast<std::int32_t>(p_O_m.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (std::int32_t v : triangles[t]) {
      if (v < 0 || v >= n) {
        throw std::invalid_argument("TriMesh: triangle " + std::to_string(t) + " index " +
                                    std::to_string(v) + " out of range");
      }
    }
    const auto& tr = triangles[t];
    const double area2 = (p_O_m[tr[1]] - p_O_m[tr[0]]).cross(p_O_m[tr[2]] - p_O_m[tr[0]]).norm();
    if (!(area2 > 0.0)) {
      throw std::invalid_argument("TriMesh: triangle " + std::to_string(t) + " has zero area");
    }
  }
}

namespace {

// Unit icosphere by midpoint subdivision (shared midpoints, so the mesh stays closed).
TriMesh UnitIcosphere(int subdivisions) {
  if (subdivisions < 0 || subdivisions > 7) {
    throw std::invalid_argument("MakeIcosphere: subdivisions must be in 0..7");
  }
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh m;
  m.p_O_m = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
             {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : m.p_O_m) p.normalize();
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> mid;
    auto midpoint = [&](std::int32_t i, std::int32_t j) {
      const auto key = std::minmax(i, j);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.p_O_m.push_back((m.p_O_m[i] + m.p_O_m[j]).normalized());
      const auto k = static_cast<std::int32_t>(m.p_O_m.size() - 1);
      mid.emplace(key, k);
      return k;
    };
    std::vector<std::array<std::int32_t, 3>> next;
    next.reserve(m.triangles.size() * 4);
    for (const auto& tr : m.triangles) {
      const std::int32_t a = midpoint(tr[0], tr[1]);
      const std::int32_t b = midpoint(tr[1], tr[2]);
      const std::int32_t c = midpoint(tr[2], tr[0]);
      next.push_back({tr[0], a, c});
      next.push_back({tr[1], b, a});
      next.push_back({tr[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = std::move(next);
  }
  return m;
}

}  // namespace

TriMesh MakeIcosphere(double radius_m, int subdivisions) {
  if (!(radius_m > 0.0) || !std::isfinite(radius_m)) {
    throw std::invalid_argument("MakeIcosphere: radius must be finite and > 0");
  }
  TriMesh m = UnitIcosphere(subdivisions);
  for (auto& p : m.p_O_m) p *= radius_m;
  return m;
}

TriMesh MakeBoxMesh(const Eigen::Vector3d& size_m) {
  if (!size_m.allFinite() || !(size_m.minCoeff() > 0.0)) {
    throw std::invalid_argument("MakeBoxMesh: sizes must be finite and > 0");
  }
  const Eigen::Vector3d h = 0.5 * size_m;
  TriMesh m;
  for (int i = 0; i < 8; ++i) {
    m.p_O_m.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  }
  // Two counter-clockwise (seen from outside) triangles per face.
  m.triangles = {{0, 2, 3}, {0, 3, 1},   // -z
                 {4, 5, 7}, {4, 7, 6},   // +z
                 {0, 1, 5}, {0, 5, 4},   // -y
                 {2, 6, 7}, {2, 7, 3},   // +y
                 {0, 4, 6}, {0, 6, 2},   // -x
                 {1, 3, 7}, {1, 7, 5}};  // +x
  return m;
}

TriMesh MakeBumpySphere(double radius_m, double bump_m, int subdivisions) {
  if (!(radius_m > 0.0) || !(bump_m >= 0.0) || !(bump_m < 0.5 * radius_m)) {
    throw std::invalid_argument("MakeBumpySphere: need radius > 0 and 0 <= bump < radius / 2");
  }
  TriMesh m = UnitIcosphere(subdivisions);
  // Six bumps around the equator and four across the poles: smooth, non-convex, deterministic.
  for (auto& p : m.p_O_m) {
    const double theta = std::acos(std::clamp(p.z(), -1.0, 1.0));
    const double phi = std::atan2(p.y(), p.x());
    p *= radius_m + bump_m * std::sin(6.0 * phi) * std::sin(4.0 * theta);
  }
  return m;
}

}  // namespace handshare::contact
