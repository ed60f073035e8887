#pragma once
/// The worlds' meshes for the browser's view: each mesh file (OBJ, or anything assimp reads)
/// exported once, at the console's start, to binary glTF 2.0 (.glb) with assimp's exporter, as
/// it is in the file (frame M; the view applies the scene's mesh_scale and pose). Not real-time.
#include <filesystem>
#include <string>

namespace handshare::web_console {

/// The .glb bytes of `mesh_file`. Throws std::runtime_error naming the file and assimp's error.
std::string ExportGlb(const std::filesystem::path& mesh_file);

}  // namespace handshare::web_console
