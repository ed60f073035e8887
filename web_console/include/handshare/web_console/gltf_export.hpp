#pragma once
/// The worlds' meshes for the browser's view: each mesh file (OBJ, or anything assimp reads)
/// exported once, at the console's start, to binary glTF 2.0 (.glb) with assimp's exporter, as
/// it is in the file (frame M; the view applies the scene's mesh_scale and pose). Not real-time.
///
/// The glTF's vertices are the mesh's as scene::LoadMesh reads it, in its order (vertex k of
/// the glTF is vertex k of LoadMesh, the node id k of the Deformation topic), so that the view
/// moves a deformed vertex by the displacement the world server sent for it. Normals are the
/// area-weighted vertex normals the graphics node draws with.
#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace handshare::web_console {

/// A mesh exported for the view.
struct GlbMesh {
  std::string glb;                ///< the .glb bytes
  std::size_t vertex_count = 0;   ///< = LoadMesh's vertex count (deformation node ids below it)
};

/// The .glb of `mesh_file`. Throws std::runtime_error naming the file and what failed (it cannot
/// be read, assimp cannot export it, or the export did not keep LoadMesh's vertices in order).
GlbMesh ExportGlb(const std::filesystem::path& mesh_file);

/// The POSITION attribute of a .glb's first mesh's first primitive, in its order (frame M [m]).
/// Throws std::runtime_error saying what is wrong when `glb` is not such a binary glTF 2.0.
std::vector<std::array<float, 3>> GlbPositions(const std::string& glb);

}  // namespace handshare::web_console
