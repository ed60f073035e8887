#pragma once
/// A scene turned into a contact::HapticWorld, with the mapping between the scene's object ids
/// and the world's object indices. Every process builds it the same way from the same scene
/// file, so a contact one haptic node reports (object id, contact point, imposed displacement)
/// means the same thing to its peers and to the world server.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "handshare/contact/haptic_world.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/world/deformable_prep.hpp"

namespace handshare::world {

struct SceneModelsOptions {
  std::filesystem::path cache_dir = DefaultCacheDir();
  double fingertip_radius_m = 0.008;
  double max_force_N = 3.5;
  int max_hands = 4;               ///< hands that may touch one deformable together
  bool include_controls = false;   ///< controls are rendered by handshare::controls, not here
  /// Rest dynamic bodies on the top face of the static box with this id (if present).
  std::string support_object = "ground";
  /// The large-deformation correction where a deformable's scene names a stiffening table
  /// (docs/fem.md, "A correction beyond the paper"); false: the paper's linear force.
  bool stiffening = true;
};

struct SceneModels {
  std::unique_ptr<contact::HapticWorld> world;
  std::vector<std::string> ids;                    ///< world object index -> scene object id
  std::map<std::string, contact::ObjectId> index;  ///< scene object id -> world object index
  std::vector<contact::ObjectId> dynamic_bodies;
  std::vector<PreparedDeformable> deformables;
  contact::ObjectId Find(const std::string& id) const {
    const auto it = index.find(id);
    return it == index.end() ? -1 : it->second;
  }
};

/// Builds (and Init()s) the haptic world of a scene: static rigid objects (mass 0), dynamic
/// bodies (mass > 0) under the scene's gravity resting on the support, deformables from their
/// prepared FEM models. Not real-time.
SceneModels BuildSceneModels(const scene::Scene& scene, const SceneModelsOptions& options = {});

}  // namespace handshare::world
