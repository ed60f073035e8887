#include "handshare/world/deformable_prep.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <sstream>

#include "handshare/fem/surface_import.hpp"
#include "handshare/fem/static_solver.hpp"

namespace handshare::world {

namespace {

[[noreturn]] void Fail(const scene::Scene& scene, const scene::SceneObject& o, const std::string& what) {
  std::ostringstream s;
  s << scene.file.string() << ":" << o.line << ": object '" << o.id << "': " << what;
  throw scene::SceneError(s.str());
}

fem::TetMesh VolumeMesh(const scene::Scene& scene, const scene::SceneObject& o) {
  if (o.shape == scene::Shape::kBox) {
    // A structured box of about 5 mm cells: enough for a fingertip patch of several nodes.
    std::array<int, 3> cells{};
    for (int k = 0; k < 3; ++k) cells[k] = std::max(2, static_cast<int>(std::lround(2.0 * o.half_extent_m[k] / 0.005)));
    fem::TetMesh box = fem::MakeBoxMesh(2.0 * o.half_extent_m, cells);
    // MakeBoxMesh spans [0, size]: centre it on O as the scene's boxes are.
    std::vector<Eigen::Vector3d> p = box.positions_m();
    for (auto& x : p) x -= o.half_extent_m;
    return fem::TetMesh(std::move(p), box.tets(), box.node_ids(), scene.file.string() + ":" + o.id);
  }
  if (o.shape != scene::Shape::kMesh || !o.mesh) Fail(scene, o, "a deformable must be a mesh or a box");
  fem::SurfaceMeshData surface{o.mesh->vertices_m, o.mesh->triangles};
  fem::TetgenOptions options;
  options.max_radius_edge_ratio = 0.0;  // no -q refinement: no added nodes, cheapest model
  try {
    return fem::TetrahedralizeSurface(surface, options, o.mesh_path.string());
  } catch (const std::exception& e) {
    Fail(scene, o, std::string("cannot tetrahedralize mesh '") + o.mesh_uri + "': " + e.what());
  }
}

// The nodes a rule selects (a fixed rule, a beat's driven one): those behind its plane, or
// its listed nodes, each checked against the mesh.
std::vector<std::int32_t> NodesOf(const scene::Scene& scene, const scene::SceneObject& o, const fem::TetMesh& mesh,
                                  const scene::FixedRule& rule, const std::string& what) {
  std::vector<std::int32_t> nodes;
  if (rule.kind == scene::FixedRule::Kind::kHalfSpace) {
    const auto& p = mesh.positions_m();
    for (std::int32_t i = 0; i < mesh.num_nodes(); ++i) {
      if (mesh.used_nodes()[i] && rule.FixesPoint(p[static_cast<std::size_t>(i)])) nodes.push_back(i);
    }
  } else if (rule.kind == scene::FixedRule::Kind::kNodes) {
    for (const std::int32_t n : rule.nodes) {
      if (n < 0 || n >= mesh.num_nodes()) {
        Fail(scene, o, what + std::to_string(n) + " is not a node of its " + std::to_string(mesh.num_nodes()) +
                           "-node tetrahedral mesh");
      }
      nodes.push_back(n);
    }
  }
  return nodes;
}

}  // namespace

std::filesystem::path DefaultCacheDir() {
  if (const char* c = std::getenv("HANDSHARE_CACHE"); c != nullptr && *c != '\0') return c;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x != nullptr && *x != '\0') {
    return std::filesystem::path(x) / "handshare";
  }
  if (const char* h = std::getenv("HOME"); h != nullptr && *h != '\0') {
    return std::filesystem::path(h) / ".cache" / "handshare";
  }
  return "/tmp/handshare-cache";
}

PreparedDeformable PrepareDeformable(const scene::Scene& scene, const scene::SceneObject& o,
                                     const std::filesystem::path& cache_dir,
                                     const fem::ProgressFn& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  if (o.kind != scene::ObjectKind::kDeformable) Fail(scene, o, "is not deformable");
  PreparedDeformable out;
  out.object_id = o.id;
  auto mesh = std::make_shared<fem::TetMesh>(VolumeMesh(scene, o));

  // Fixed nodes from the scene's rule, in frame O.
  const auto& p = mesh->positions_m();
  if (o.fixed.kind == scene::FixedRule::Kind::kNone) {
    Fail(scene, o, "a deformable needs fixed nodes (field 'fixed'), else it floats away");
  }
  out.fixed_nodes = NodesOf(scene, o, *mesh, o.fixed, "fixed node ");
  if (out.fixed_nodes.empty()) Fail(scene, o, "its fixed rule holds no node of the tetrahedral mesh");
  if (static_cast<std::int32_t>(out.fixed_nodes.size()) >= mesh->num_nodes()) {
    Fail(scene, o, "its fixed rule holds every node: nothing can deform");
  }

  // A beat: its driven nodes (fixed ones stay fixed), held by the compliance as well.
  std::vector<std::int32_t> held = out.fixed_nodes;
  if (o.beat.active()) {
    std::vector<char> fixed(static_cast<std::size_t>(mesh->num_nodes()), 0);
    for (const auto n : out.fixed_nodes) fixed[static_cast<std::size_t>(n)] = 1;
    std::vector<char> driven(fixed.size(), 0);
    for (const auto n : NodesOf(scene, o, *mesh, o.beat.driven, "driven node ")) driven[static_cast<std::size_t>(n)] = 1;
    for (std::int32_t i = 0; i < mesh->num_nodes(); ++i) {
      if (driven[static_cast<std::size_t>(i)] != 0 && fixed[static_cast<std::size_t>(i)] == 0) out.driven_nodes.push_back(i);
    }
    if (out.driven_nodes.empty()) Fail(scene, o, "its beat drives no node that is not fixed");
    held.insert(held.end(), out.driven_nodes.begin(), out.driven_nodes.end());
    std::sort(held.begin(), held.end());
    if (static_cast<std::int32_t>(held.size()) >= mesh->num_nodes()) {
      Fail(scene, o, "its fixed and driven nodes are every node: nothing is left to follow the beat");
    }
  }

  fem::Material material;
  material.E_Pa = o.deformable.E_Pa;
  material.nu = o.deformable.nu;
  fem::ComplianceOptions options;
  options.precision = fem::Precision::kFloat32;
  std::filesystem::create_directories(cache_dir);
  out.cache_file = cache_dir / (scene.name + "." + o.id + ".f32.compliance");
  auto compliance = std::make_shared<fem::Compliance>(fem::Compliance::LoadOrPrecompute(
      out.cache_file, *mesh, material, held, options, progress, &out.cache_note));
  if (!out.driven_nodes.empty()) {
    // The beat's mode: one static solve, the driven nodes at the beat's displacement.
    fem::StaticSolver solver(*mesh, material, out.fixed_nodes, out.driven_nodes);
    std::vector<Eigen::Vector3d> drive;
    drive.reserve(out.driven_nodes.size());
    for (const auto n : out.driven_nodes) drive.push_back(o.beat.DrivenDisplacement_O(p[static_cast<std::size_t>(n)]));
    out.mode_O_m = std::make_shared<const std::vector<Eigen::Vector3d>>(solver.Solve(drive).u_m);
  }
  out.surface = std::make_shared<fem::Surface>(fem::ExtractSurface(*mesh));
  out.mesh = std::move(mesh);
  out.compliance = std::move(compliance);
  if (!o.deformable.stiffening_table_path.empty()) {
    const auto samples = fem::ReadStiffeningSamples(o.deformable.stiffening_table_path);
    out.stiffening = std::make_shared<fem::StiffeningTable>(*out.mesh, *out.surface, samples);
  }
  out.prepare_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace handshare::world
