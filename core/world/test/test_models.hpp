#pragma once
// Scene models for the world tests that use the project's real scenes: prepared once into
// HANDSHARE_CACHE (ctest sets it to the build tree's cache), else into a folder of the temp dir.
#include <cstdlib>
#include <filesystem>

#include "handshare/world/scene_models.hpp"

namespace handshare::world::test {

inline SceneModels BuildCached(const scene::Scene& s, const char* temp_folder) {
  SceneModelsOptions options;
  const char* cache = std::getenv("HANDSHARE_CACHE");
  options.cache_dir = cache != nullptr ? std::filesystem::path(cache) : std::filesystem::temp_directory_path() / temp_folder;
  return BuildSceneModels(s, options);
}

}  // namespace handshare::world::test
