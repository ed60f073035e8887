// Triangle meshes of scene objects, read with assimp.
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <map>
#include <system_error>
#include <tuple>

#include "handshare/scene/scene.hpp"

namespace handshare::scene {

namespace {

// Appends the triangles of `node` and its children, with their accumulated transforms.
void Collect(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
             const Eigen::Vector3d& scale, const Eigen::Isometry3d& X_AM,
             std::map<std::tuple<double, double, double>, std::int32_t>& welded, Mesh& out) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[k]];
    std::vector<std::int32_t> index(mesh.mNumVertices);
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = transform * mesh.mVertices[v];
      // Weld by the file's (transformed) coordinates, so STL's per-facet copies become one node.
      const auto key = std::make_tuple(double(p.x), double(p.y), double(p.z));
      auto [it, inserted] = welded.emplace(key, static_cast<std::int32_t>(out.vertices_m.size()));
      if (inserted) {
        out.vertices_m.push_back(X_AM * Eigen::Vector3d(scale.x() * p.x, scale.y() * p.y, scale.z() * p.z));
      }
      index[v] = it->second;
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines (triangulation did the rest)
      out.triangles.push_back({index[face.mIndices[0]], index[face.mIndices[1]], index[face.mIndices[2]]});
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    Collect(scene, *node.mChildren[c], transform, scale, X_AM, welded, out);
  }
}

}  // namespace

Mesh LoadMesh(const std::filesystem::path& file, const Eigen::Vector3d& scale,
              const Eigen::Isometry3d& X_AM) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    throw SceneError("mesh '" + file.string() + "': no such file");
  }
  if (std::filesystem::file_size(file, ec) == 0) {
    throw SceneError("mesh '" + file.string() + "': empty file");
  }
  Assimp::Importer importer;
  // No normal generation, no vertex joining by attributes: positions and faces are all we need,
  // and welding is done below by position alone.
  const aiScene* scene = importer.ReadFile(file.string(), aiProcess_Triangulate | aiProcess_SortByPType);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    throw SceneError("mesh '" + file.string() + "': cannot read: " + importer.GetErrorString());
  }
  Mesh out;
  std::map<std::tuple<double, double, double>, std::int32_t> welded;
  Collect(*scene, *scene->mRootNode, aiMatrix4x4(), scale, X_AM, welded, out);
  if (out.triangles.empty()) throw SceneError("mesh '" + file.string() + "': no triangles");
  if (scale.prod() < 0.0) {
    for (auto& t : out.triangles) std::swap(t[1], t[2]);  // a mirror turns outward inward
  }
  return out;
}

MeshCheck CheckMesh(const Mesh& mesh) {
  MeshCheck check;
  for (const auto& v : mesh.vertices_m) check.bounds.extend(v);
  std::map<std::pair<std::int32_t, std::int32_t>, int> directed;
  for (const auto& t : mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) ++check.degenerate_triangles;
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
    const Eigen::Vector3d& a = mesh.vertices_m[t[0]];
    const Eigen::Vector3d& b = mesh.vertices_m[t[1]];
    const Eigen::Vector3d& c = mesh.vertices_m[t[2]];
    // Divergence theorem: volume = sum over triangles of a . (b x c) / 6.
    check.signed_volume_m3 += a.dot(b.cross(c)) / 6.0;
  }
  // Closed and consistently oriented: each directed edge once, with its opposite once.
  for (const auto& [edge, count] : directed) {
    if (count > 1) ++check.non_manifold_edges;
    if (directed.find({edge.second, edge.first}) == directed.end()) ++check.boundary_edges;
  }
  return check;
}

}  // namespace handshare::scene
