#include "handshare/fem/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "handshare/fem/error.hpp"

namespace handshare::fem {

double SignedVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d) noexcept {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

TetMesh::TetMesh(std::vector<Eigen::Vector3d> p_m, std::vector<Tet> tets,
                 std::vector<std::int64_t> node_ids, std::string source)
    : p_m_(std::move(p_m)),
      tets_(std::move(tets)),
      node_ids_(std::move(node_ids)),
      source_(std::move(source)) {
  const auto n = static_cast<std::int64_t>(p_m_.size());
  if (n > INT32_MAX / 3) throw InputError(source_, 0, "nodes", "too many nodes");
  if (node_ids_.empty()) {
    node_ids_.resize(p_m_.size());
    std::iota(node_ids_.begin(), node_ids_.end(), std::int64_t{1});
  }
  if (node_ids_.size() != p_m_.size()) {
    throw InputError(source_, 0, "node ids", "count differs from the node count");
  }
  index_of_id_.reserve(p_m_.size());
  for (std::int32_t i = 0; i < static_cast<std::int32_t>(p_m_.size()); ++i) {
    if (!p_m_[i].allFinite()) {
      throw InputError(source_, 0, "node " + std::to_string(node_ids_[i]),
                       "coordinate is not a finite number");
    }
    if (!index_of_id_.emplace(node_ids_[i], i).second) {
      throw InputError(source_, 0, "node id", "duplicate node id " + std::to_string(node_ids_[i]));
    }
  }
  if (tets_.empty()) throw InputError(source_, 0, "elements", "no tetrahedra");
  used_.assign(p_m_.size(), false);
  for (std::size_t e = 0; e < tets_.size(); ++e) {
    const Tet& t = tets_[e];
    for (std::int32_t v : t) {
      if (v < 0 || v >= n) {
        throw InputError(source_, 0, "element " + std::to_string(e + 1),
                         "node index " + std::to_string(v) + " out of range");
      }
      used_[v] = true;
    }
    const double vol = SignedVolume(p_m_[t[0]], p_m_[t[1]], p_m_[t[2]], p_m_[t[3]]);
    if (!(vol > 0.0)) {
      throw InputError(source_, 0, "element " + std::to_string(e + 1),
                       std::string(vol < 0.0 ? "inverted" : "degenerate") +
                           " tetrahedron (signed volume " + std::to_string(vol) + " m^3)");
    }
  }
}

std::optional<std::int32_t> TetMesh::IndexOfId(std::int64_t id) const {
  auto it = index_of_id_.find(id);
  if (it == index_of_id_.end()) return std::nullopt;
  return it->second;
}

std::int32_t TetMesh::IndexOfIdOrThrow(std::int64_t id, const std::string& field) const {
  auto idx = IndexOfId(id);
  if (!idx) throw InputError(source_, 0, field, "unknown node id " + std::to_string(id));
  return *idx;
}

void TetMesh::SetNodeSet(std::string name, std::vector<std::int32_t> nodes) {
  for (std::int32_t v : nodes) {
    if (v < 0 || v >= num_nodes()) {
      throw InputError(source_, 0, "node set " + name, "node index out of range");
    }
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  node_sets_[std::move(name)] = std::move(nodes);
}

const std::vector<std::int32_t>* TetMesh::FindNodeSet(std::string_view name) const {
  auto it = node_sets_.find(name);
  return it == node_sets_.end() ? nullptr : &it->second;
}

double TetMesh::Volume() const noexcept {
  double v = 0.0;
  for (const Tet& t : tets_) v += SignedVolume(p_m_[t[0]], p_m_[t[1]], p_m_[t[2]], p_m_[t[3]]);
  return v;
}

Surface ExtractSurface(const TetMesh& mesh) {
  // Each element contributes its 4 faces, oriented outward for a positive tet (a,b,c,d):
  // (a,c,b), (a,b,d), (a,d,c), (b,c,d). A face seen once is on the boundary; twice is interior
  // (with opposite orientations); more is a non-manifold mesh.
  struct Face {
    std::array<std::int32_t, 3> key;
    Triangle oriented;
  };
  std::vector<Face> faces;
  faces.reserve(mesh.tets().size() * 4);
  for (const Tet& t : mesh.tets()) {
    const Triangle f[4] = {{t[0], t[2], t[1]}, {t[0], t[1], t[3]}, {t[0], t[3], t[2]},
                           {t[1], t[2], t[3]}};
    for (const Triangle& tri : f) {
      Face face{{tri[0], tri[1], tri[2]}, tri};
      std::sort(face.key.begin(), face.key.end());
      faces.push_back(face);
    }
  }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.key < b.key; });

  // Cyclic orientation parity of an oriented triangle relative to its sorted key.
  auto parity = [](const Face& f) {
    const auto& o = f.oriented;
    const bool same = (o[0] == f.key[0] && o[1] == f.key[1]) ||
                      (o[1] == f.key[0] && o[2] == f.key[1]) ||
                      (o[2] == f.key[0] && o[0] == f.key[1]);
    return same;
  };

  Surface s;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    const std::size_t count = j - i;
    auto face_name = [&] {
      const auto& ids = mesh.node_ids();
      return "face (" + std::to_string(ids[faces[i].key[0]]) + ", " +
             std::to_string(ids[faces[i].key[1]]) + ", " + std::to_string(ids[faces[i].key[2]]) +
             ")";
    };
    if (count == 1) {
      s.triangles.push_back(faces[i].oriented);
    } else if (count == 2) {
      if (parity(faces[i]) == parity(faces[i + 1])) {
        throw InputError(mesh.source(), 0, face_name(),
                         "two elements lie on the same side of this face (overlapping mesh)");
      }
    } else {
      throw InputError(mesh.source(), 0, face_name(),
                       "shared by " + std::to_string(count) + " elements (non-manifold mesh)");
    }
    i = j;
  }

  std::vector<Eigen::Vector3d> normal_sum(mesh.positions_m().size(), Eigen::Vector3d::Zero());
  std::vector<bool> on_surface(mesh.positions_m().size(), false);
  const auto& p = mesh.positions_m();
  for (const Triangle& t : s.triangles) {
    // Cross product = 2 * area * unit normal: area weighting for free.
    const Eigen::Vector3d n = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
    for (std::int32_t v : t) {
      normal_sum[v] += n;
      on_surface[v] = true;
    }
  }
  for (std::int32_t v = 0; v < mesh.num_nodes(); ++v) {
    if (!on_surface[v]) continue;
    s.nodes.push_back(v);
    const double len = normal_sum[v].norm();
    s.normals.push_back(len > 0.0 ? Eigen::Vector3d(normal_sum[v] / len)
                                  : Eigen::Vector3d::Zero());
  }
  return s;
}

TetMesh MakeGridMesh(std::span<const double> xs, std::span<const double> ys,
                     std::span<const double> zs) {
  const std::span<const double> axes[3] = {xs, ys, zs};
  for (int a = 0; a < 3; ++a) {
    if (axes[a].size() < 2) {
      throw InputError("", 0, "grid axis " + std::to_string(a), "needs at least 2 coordinates");
    }
    for (std::size_t i = 1; i < axes[a].size(); ++i) {
      if (!(axes[a][i] > axes[a][i - 1])) {
        throw InputError("", 0, "grid axis " + std::to_string(a),
                         "coordinates must increase strictly");
      }
    }
  }
  const auto nx = static_cast<std::int64_t>(xs.size());
  const auto ny = static_cast<std::int64_t>(ys.size());
  const auto nz = static_cast<std::int64_t>(zs.size());
  std::vector<Eigen::Vector3d> p;
  p.reserve(static_cast<std::size_t>(nx * ny * nz));
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i) p.emplace_back(xs[i], ys[j], zs[k]);

  auto id = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return static_cast<std::int32_t>(i + nx * (j + ny * k));
  };
  // Kuhn split: the 6 monotone paths from corner 000 to 111, one per axis permutation.
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                      {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  std::vector<Tet> tets;
  tets.reserve(static_cast<std::size_t>(6 * (nx - 1) * (ny - 1) * (nz - 1)));
  for (std::int64_t k = 0; k + 1 < nz; ++k)
    for (std::int64_t j = 0; j + 1 < ny; ++j)
      for (std::int64_t i = 0; i + 1 < nx; ++i)
        for (const auto& perm : kPerm) {
          std::int64_t c[3] = {i, j, k};
          Tet t;
          t[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[perm[s]];
            t[s + 1] = id(c[0], c[1], c[2]);
          }
          if (SignedVolume(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) < 0.0) std::swap(t[2], t[3]);
          tets.push_back(t);
        }
  return TetMesh(std::move(p), std::move(tets), {}, "grid mesh");
}

TetMesh MakeBoxMesh(const Eigen::Vector3d& size_m, const std::array<int, 3>& cells) {
  std::vector<double> c[3];
  for (int a = 0; a < 3; ++a) {
    if (cells[a] < 1 || !(size_m[a] > 0.0)) {
      throw InputError("", 0, "box", "needs >= 1 cell and a positive size per axis");
    }
    for (int i = 0; i <= cells[a]; ++i) c[a].push_back(size_m[a] * i / cells[a]);
  }
  return MakeGridMesh(c[0], c[1], c[2]);
}

std::vector<std::int32_t> NodesOnPlane(const TetMesh& mesh, int axis, double value_m,
                                       double tol_m) {
  std::vector<std::int32_t> out;
  for (std::int32_t i = 0; i < mesh.num_nodes(); ++i) {
    if (std::abs(mesh.positions_m()[i][axis] - value_m) <= tol_m) out.push_back(i);
  }
  return out;
}

}  // namespace handshare::fem
