#pragma once
/// Offline preparation of a scene's deformable object: its surface mesh (already loaded by the
/// scene loader, frame O) is tetrahedralized by the external tetgen program, its fixed rule
/// becomes fixed nodes (a beat's rule, driven nodes with their static response), and the
/// compliance of its free surface nodes is loaded from the cache or precomputed (CHOLMOD) and
/// saved. Not real-time: run on a loader thread or ahead of time.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/stiffening.hpp"
#include "handshare/fem/mesh.hpp"
#include "handshare/scene/scene.hpp"

namespace handshare::world {

struct PreparedDeformable {
  std::string object_id;
  std::shared_ptr<const fem::TetMesh> mesh;        ///< frame O
  std::shared_ptr<const fem::Surface> surface;
  std::shared_ptr<const fem::Compliance> compliance;
  std::vector<std::int32_t> fixed_nodes;
  /// A beating body (scene::Beat): the nodes it drives (not fixed), and its static response
  /// to the drive at Scale = 1 (every node of `mesh`, frame O: the driven nodes at the beat's
  /// displacement, the fixed ones at zero). The compliance holds both the fixed and the driven
  /// nodes: a fingertip's field adds to Scale(t) mode_O_m (linear elasticity). Both empty for a
  /// body that does not beat.
  std::vector<std::int32_t> driven_nodes;
  std::shared_ptr<const std::vector<Eigen::Vector3d>> mode_O_m;
  /// The scene's stiffening table on this mesh (scene::DeformableMaterial::stiffening_table);
  /// null when the scene names none.
  std::shared_ptr<const fem::StiffeningTable> stiffening;
  std::filesystem::path cache_file;
  std::string cache_note;  ///< why the cache was (not) used
  double prepare_s = 0.0;
};

/// Where compliance caches live: $HANDSHARE_CACHE if set, else $XDG_CACHE_HOME/handshare,
/// else ~/.cache/handshare, else /tmp/handshare-cache.
std::filesystem::path DefaultCacheDir();

/// Prepares one deformable scene object (kind kDeformable, shape kMesh or box/sphere).
/// Compliance is stored in float32 (half the memory; the FEM tests bound its error at 1e-5).
/// @throws scene::SceneError naming the scene file, line and object for a mesh tetgen cannot
///         use or a fixed rule that fixes no node or every node; fem errors pass through.
PreparedDeformable PrepareDeformable(const scene::Scene& scene, const scene::SceneObject& object,
                                     const std::filesystem::path& cache_dir,
                                     const fem::ProgressFn& progress = {});

}  // namespace handshare::world
