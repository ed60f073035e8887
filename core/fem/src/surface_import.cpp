// Surface meshes through assimp, tetrahedralization through the external tetgen program, and
// the reader of any mesh file by its extension. Uses mesh_io.cpp's readers; they never call here.
// TetGen is GPL: it is only ever run as a separate process (posix_spawn), never linked.

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "handshare/fem/error.hpp"
#include "handshare/fem/mesh_io.hpp"
#include "handshare/fem/surface_import.hpp"
#include "run_program.hpp"

namespace handshare::fem {
namespace {

namespace fs = std::filesystem;

// A temporary directory removed on scope exit.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "handshare-tetgen-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) {
      throw FemError(std::string("cannot create a temporary directory: ") + std::strerror(errno));
    }
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const noexcept { return path_; }

 private:
  fs::path path_;
};

std::string FormatG(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace

SurfaceMeshData ReadSurfaceMesh(const fs::path& file) {
  const std::string name = file.string();
  if (!fs::exists(file)) throw InputError(name, 0, "file", "does not exist");
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFile(name, aiProcess_Triangulate | aiProcess_PreTransformVertices);
  if (scene == nullptr) {
    throw InputError(name, 0, "surface mesh", std::string("assimp: ") + importer.GetErrorString());
  }
  SurfaceMeshData out;
  // Weld bitwise-identical positions: STL repeats every vertex per triangle.
  std::map<std::array<double, 3>, std::int32_t> index;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    std::vector<std::int32_t> local(mesh->mNumVertices);
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& a = mesh->mVertices[v];
      const std::array<double, 3> key = {a.x, a.y, a.z};
      if (!std::isfinite(key[0]) || !std::isfinite(key[1]) || !std::isfinite(key[2])) {
        throw InputError(name, 0, "vertex " + std::to_string(v), "coordinate is not finite");
      }
      auto [it, inserted] = index.emplace(key, static_cast<std::int32_t>(out.p_m.size()));
      if (inserted) out.p_m.emplace_back(key[0], key[1], key[2]);
      local[v] = it->second;
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      const std::array<std::int32_t, 3> t = {local[face.mIndices[0]], local[face.mIndices[1]],
                                             local[face.mIndices[2]]};
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;  // collapsed by welding
      out.triangles.push_back(t);
    }
  }
  if (out.triangles.empty()) throw InputError(name, 0, "surface mesh", "no triangles");
  return out;
}

void CheckClosed(const SurfaceMeshData& s, const std::string& source) {
  std::map<std::pair<std::int32_t, std::int32_t>, int> edge_use;
  for (const auto& t : s.triangles) {
    for (int e = 0; e < 3; ++e) {
      auto a = t[e], b = t[(e + 1) % 3];
      if (a > b) std::swap(a, b);
      ++edge_use[{a, b}];
    }
  }
  for (const auto& [edge, n] : edge_use) {
    if (n != 2) {
      throw InputError(source, 0, "surface",
                       "not a closed surface: the edge between vertices " +
                           std::to_string(edge.first + 1) + " and " + std::to_string(edge.second + 1) +
                           " belongs to " + std::to_string(n) + " triangle(s), not 2");
    }
  }
}

TetMesh TetrahedralizeSurface(const SurfaceMeshData& s, const TetgenOptions& options,
                              const std::string& source) {
  CheckClosed(s, source);
  TempDir dir;
  {
    // TetGen .smesh: nodes (0-based), facets, no holes, no regions.
    std::ofstream out(dir.path() / "surface.smesh");
    out << s.p_m.size() << " 3 0 0\n";
    for (std::size_t i = 0; i < s.p_m.size(); ++i) {
      out << i << ' ' << FormatG(s.p_m[i].x()) << ' ' << FormatG(s.p_m[i].y()) << ' '
          << FormatG(s.p_m[i].z()) << '\n';
    }
    out << s.triangles.size() << " 0\n";
    for (const auto& t : s.triangles) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
    out << "0\n0\n";
    if (!out) throw FemError("cannot write " + (dir.path() / "surface.smesh").string());
  }
  // -p: tetrahedralize a piecewise linear complex; -z: number from zero; -Q: quiet;
  // -q: radius-edge quality bound; -a: volume bound.
  std::string flags = "-pzQ";
  if (options.max_radius_edge_ratio > 0.0) flags += "q" + FormatG(options.max_radius_edge_ratio);
  if (options.max_volume_m3 > 0.0) flags += "a" + FormatG(options.max_volume_m3);
  const fs::path log = dir.path() / "tetgen.log";
  const int rc = detail::RunProgram({options.program, flags, "surface.smesh"}, dir.path(), log, "tetgen");
  if (rc != 0 || !fs::exists(dir.path() / "surface.1.ele")) {
    throw FemError("tetgen failed on " + source + " (exit code " + std::to_string(rc) +
                   ", flags " + flags + "): " + detail::Tail(log, 600));
  }
  TetMesh tetgen_mesh = ReadTetgen(dir.path() / "surface.1");
  // Keep the node sets but name the original surface as the source in later messages.
  std::vector<Eigen::Vector3d> p = tetgen_mesh.positions_m();
  std::vector<Tet> tets = tetgen_mesh.tets();
  std::vector<std::int64_t> ids = tetgen_mesh.node_ids();
  TetMesh mesh(std::move(p), std::move(tets), std::move(ids), source + " (tetgen " + flags + ")");
  for (const auto& [name, nodes] : tetgen_mesh.node_sets()) mesh.SetNodeSet(name, nodes);
  return mesh;
}

TetMesh TetrahedralizeSurfaceFile(const fs::path& surface_file, const TetgenOptions& options) {
  return TetrahedralizeSurface(ReadSurfaceMesh(surface_file), options, surface_file.string());
}

TetMesh ReadVolumeMesh(const fs::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".msh") return ReadGmshMsh(file);
  if (ext == ".node" || ext == ".ele") return ReadTetgen(file);
  if (ext == ".inp") return ReadAbaqusInp(file);
  if (ext == ".obj" || ext == ".stl" || ext == ".ply" || ext == ".off") {
    return TetrahedralizeSurfaceFile(file);
  }
  throw InputError(file.string(), 0, "extension",
                   "unknown mesh format '" + ext +
                       "' (expected .msh, .node/.ele, .inp, or a surface .obj/.stl/.ply/.off)");
}

}  // namespace handshare::fem
