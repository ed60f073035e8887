#include "handshare/graphics/mesh_cache.hpp"

#include <exception>

#include "handshare/scene/scene.hpp"

namespace handshare::graphics {

void AreaWeightedNormals(const std::vector<Eigen::Vector3d>& p,
                         const std::vector<std::array<std::uint32_t, 3>>& triangles,
                         std::vector<Eigen::Vector3d>& n) {
  n.assign(p.size(), Eigen::Vector3d::Zero());
  // The unnormalized face normal's length is twice the face's area: summing it weights by area.
  for (const auto& t : triangles) {
    const Eigen::Vector3d face = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
    for (const std::uint32_t v : t) n[v] += face;
  }
  for (auto& normal : n) {
    const double length = normal.norm();
    if (length > 0.0) normal /= length;
  }
}

MeshCache::MeshCache(std::filesystem::path assets_dir) : assets_dir_(std::move(assets_dir)) {}

std::filesystem::path MeshCache::Resolve(const std::string& uri) const {
  const std::filesystem::path p(uri);
  return p.is_absolute() ? p : assets_dir_ / p;
}

const MeshCache::Entry& MeshCache::Get(const std::string& uri) {
  if (const auto it = entries_.find(uri); it != entries_.end()) return it->second;
  Entry entry;
  entry.file = Resolve(uri);
  if (uri.empty()) {
    entry.error = "no mesh file given (empty mesh_uri)";
  } else {
    ++loads_;
    try {
      const scene::Mesh loaded = scene::LoadMesh(entry.file);
      auto mesh = std::make_shared<render::TriangleMesh>();
      mesh->p_MV = loaded.vertices_m;
      mesh->triangles.reserve(loaded.triangles.size());
      for (const auto& t : loaded.triangles) {
        std::array<std::uint32_t, 3> u{};
        for (int k = 0; k < 3; ++k) {
          // LoadMesh only makes indices of its own vertices; check anyway, a bad index must
          // not reach the drawer.
          if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= loaded.vertices_m.size()) {
            throw scene::SceneError("mesh '" + entry.file.string() + "': triangle index out of range");
          }
          u[k] = static_cast<std::uint32_t>(t[k]);
        }
        mesh->triangles.push_back(u);
      }
      for (const auto& v : mesh->p_MV) {
        if (!v.allFinite()) throw scene::SceneError("mesh '" + entry.file.string() + "': non-finite vertex");
      }
      AreaWeightedNormals(mesh->p_MV, mesh->triangles, mesh->n_MV);
      entry.mesh = std::move(mesh);
    } catch (const std::exception& e) {
      entry.error = e.what();
    }
  }
  return entries_.emplace(uri, std::move(entry)).first->second;
}

}  // namespace handshare::graphics
