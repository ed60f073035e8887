#pragma once
// The world tests that use the project's real scenes: a scene reduced to one of its
// deformables, and its models prepared once into HANDSHARE_CACHE (ctest sets it to the build
// tree's cache), else into a folder of the temp dir.
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "handshare/scene/scene.hpp"
#include "handshare/world/scene_models.hpp"

namespace handshare::world::test {

// assets/scenes/<scene_file> with only the deformable `id`.
inline scene::Scene OneDeformable(const char* scene_file, const char* id) {
  scene::Scene s = scene::LoadScene(std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes" / scene_file);
  std::erase_if(s.objects, [&](const scene::SceneObject& o) { return o.id != id; });
  if (s.objects.size() != 1 || s.objects[0].kind != scene::ObjectKind::kDeformable) {
    throw std::runtime_error(std::string(scene_file) + " has no single deformable " + id);
  }
  return s;
}

inline SceneModels BuildCached(const scene::Scene& s, const char* temp_folder) {
  SceneModelsOptions options;
  const char* cache = std::getenv("HANDSHARE_CACHE");
  options.cache_dir = cache != nullptr ? std::filesystem::path(cache) : std::filesystem::temp_directory_path() / temp_folder;
  return BuildSceneModels(s, options);
}

}  // namespace handshare::world::test
