#pragma once
/// The meshes of scene objects for drawing: each asset path loaded once with scene::LoadMesh
/// (assimp), with its area-weighted vertex normals. No middleware, no OpenGL. Not real-time.
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "handshare/render/scene_view.hpp"

namespace handshare::graphics {

/// Unit area-weighted vertex normals of a triangle mesh (a vertex in no triangle, or only in
/// degenerate ones, gets a zero normal). n is resized to p.size().
void AreaWeightedNormals(const std::vector<Eigen::Vector3d>& p,
                         const std::vector<std::array<std::uint32_t, 3>>& triangles,
                         std::vector<Eigen::Vector3d>& n);

class MeshCache {
 public:
  /// A mesh as loaded, in the object's frame O (render::TriangleMesh with X_WM identity, its
  /// vertices in LoadMesh's order, n_MV its undeformed normals), or why it could not be.
  struct Entry {
    std::shared_ptr<const render::TriangleMesh> mesh;  ///< null when loading failed
    std::filesystem::path file;                        ///< where the uri points
    std::string error;                                 ///< LoadMesh's reason, "" when loaded
  };

  /// assets_dir: what relative mesh uris ("meshes/ball.obj") are relative to.
  explicit MeshCache(std::filesystem::path assets_dir);

  /// The mesh of `uri`: relative to the assets folder, or absolute. Loaded on the first call,
  /// failures included (a missing file is not retried). Never throws for a bad file.
  const Entry& Get(const std::string& uri);

  /// uri resolved against the assets folder.
  std::filesystem::path Resolve(const std::string& uri) const;
  const std::filesystem::path& assets_dir() const { return assets_dir_; }
  /// How many times a file was read (each uri at most once).
  std::size_t loads() const { return loads_; }

 private:
  std::filesystem::path assets_dir_;
  std::map<std::string, Entry> entries_;
  std::size_t loads_ = 0;
};

}  // namespace handshare::graphics
