#pragma once
// The scenes' touchable parts and the fingertip presses users make on them, shared by
// fem_accuracy (the linear model against CalculiX under these presses) and the programs that
// time the haptic step on the same parts (fem_bench's model rows, haptic_bench's part rows).
// Each part is prepared exactly as the haptic world prepares it (world::PrepareDeformable).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "handshare/fem/mesh.hpp"
#include "handshare/fem/stiffening.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/world/deformable_prep.hpp"

namespace handshare::bench {

using Eigen::Vector3d;
namespace fs = std::filesystem;

inline constexpr double kFingertipRadius_m = 0.008;  // the scripts' and haptic_bench's fingertip
inline constexpr double kObliqueAngle_rad = 30.0 * M_PI / 180.0;
inline constexpr double kStickingMu = 1e3;           // a patch that never slips: every held node in 3-D

// A part and where it is pressed (frame O of its object): a ray from `from_O` along `approach_O`
// finds the centre finger's contact point; the five-finger row runs along `row_O`.
struct PartSpec {
  const char* name;
  const char* scene_file;
  const char* object_id;
  Vector3d from_O;
  Vector3d approach_O;
  Vector3d row_O;
  double spacing_m;
  bool rubber_like;
  const char* where;
};

// Where users press: the tail where the tour presses it (alice, x = -95 mm in O), the top of the
// head, the side of the leg the visitor faces, the belly near the head where the beating-belly
// session presses it, the horn near its tip ("Push its tip").
inline const std::vector<PartSpec>& Parts() {
  static const std::vector<PartSpec> parts = {
      {"tail", "dinosaur.json", "triceratops_tail", {-0.095, 0.0, 1.0}, {0, 0, -1}, {1, 0, 0}, 0.018, true,
       "top, 95 mm from the root (the tour's press)"},
      {"head", "dinosaur.json", "triceratops_head", {0.0, 0.0, 1.0}, {0, 0, -1}, {0, 1, 0}, 0.018, true,
       "top of the skull"},
      {"leg", "dinosaur.json", "triceratops_leg", {0.0, -1.0, 0.09}, {0, 1, 0}, {0, 0, 1}, 0.018, true,
       "visitor's side, 9 cm up"},
      {"belly", "microscopic_belly.json", "daphnia_belly", {0.025, 0.0, -1.0}, {0, 0, 1}, {1, 0, 0}, 0.015, true,
       "belly, 25 mm from the body's origin toward the head"},
      {"horn", "microscopic_horn.json", "daphnia_horn", {-0.085, -1.0, 0.0005}, {0, 1, 0}, {1, 0, 0.16}, 0.010, false,
       "top of the spine, 85 mm from its root (near the tip)"},
  };
  return parts;
}

struct PressSpec {
  const char* name;
  int fingers;
  bool oblique;
};

inline const std::vector<PressSpec>& Presses() {
  static const std::vector<PressSpec> presses = {
      {"one_normal", 1, false}, {"one_oblique", 1, true}, {"five_normal", 5, false}, {"five_oblique", 5, true}};
  return presses;
}

[[noreturn]] inline void Fail(const std::string& what) { throw std::runtime_error(what); }

// Ray against the surface triangles: every hit distance t > t_min along dir (Moller-Trumbore).
inline std::vector<std::pair<double, std::size_t>> RayHits(const handshare::fem::TetMesh& mesh,
                                                    const handshare::fem::Surface& s, const Vector3d& o,
                                                    const Vector3d& dir, double t_min) {
  std::vector<std::pair<double, std::size_t>> hits;
  const auto& p = mesh.positions_m();
  for (std::size_t k = 0; k < s.triangles.size(); ++k) {
    const auto& t = s.triangles[k];
    const Vector3d a = p[static_cast<std::size_t>(t[0])];
    const Vector3d e1 = p[static_cast<std::size_t>(t[1])] - a, e2 = p[static_cast<std::size_t>(t[2])] - a;
    const Vector3d h = dir.cross(e2);
    const double det = e1.dot(h);
    if (std::abs(det) < 1e-18) continue;
    const Vector3d sv = o - a;
    const double u = sv.dot(h) / det;
    if (u < 0.0 || u > 1.0) continue;
    const Vector3d q = sv.cross(e1);
    const double v = dir.dot(q) / det;
    if (v < 0.0 || u + v > 1.0) continue;
    const double tt = e2.dot(q) / det;
    if (tt > t_min) hits.emplace_back(tt, k);
  }
  std::sort(hits.begin(), hits.end());
  return hits;
}

inline Vector3d TriangleNormal(const handshare::fem::TetMesh& mesh, const handshare::fem::Triangle& t) {
  const auto& p = mesh.positions_m();
  const Vector3d a = p[static_cast<std::size_t>(t[0])];
  return (p[static_cast<std::size_t>(t[1])] - a).cross(p[static_cast<std::size_t>(t[2])] - a).normalized();
}

// One prepared part.
struct Part {
  const PartSpec* spec = nullptr;
  handshare::scene::Scene scene;
  handshare::world::PreparedDeformable prepared;
  handshare::fem::Material material;
  std::vector<std::int32_t> held_fixed;  // fixed and beat-driven nodes (the compliance holds both)
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
};

// `table`: a stiffening table instead of the scene's (none: the scene's, if it names one).
inline Part PreparePart(const PartSpec& spec, const fs::path& assets, const fs::path& cache, const fs::path& table) {
  Part part;
  part.spec = &spec;
  part.scene = handshare::scene::LoadScene(assets / "scenes" / spec.scene_file);
  const handshare::scene::SceneObject* object = nullptr;
  for (const auto& o : part.scene.objects) {
    if (o.id == spec.object_id) object = &o;
  }
  if (object == nullptr) Fail(std::string(spec.scene_file) + " has no object '" + spec.object_id + "'");
  part.prepared = handshare::world::PrepareDeformable(part.scene, *object, cache);
  if (!table.empty()) {
    part.prepared.stiffening = std::make_shared<handshare::fem::StiffeningTable>(
        *part.prepared.mesh, *part.prepared.surface, handshare::fem::ReadStiffeningSamples(table));
  }
  part.material = {object->deformable.E_Pa, object->deformable.nu};
  part.held_fixed = part.prepared.fixed_nodes;
  part.held_fixed.insert(part.held_fixed.end(), part.prepared.driven_nodes.begin(), part.prepared.driven_nodes.end());
  std::sort(part.held_fixed.begin(), part.held_fixed.end());
  part.X_WO = object->X_WO();
  return part;
}

// The committed stiffening table of a part's mesh (assets/meshes/NAME.stiffening.csv beside
// NAME.obj), or an empty path where the part has none.
inline fs::path CommittedTable(const Part& part, const std::string& object_id) {
  for (const auto& o : part.scene.objects) {
    if (o.id != object_id || o.mesh_path.empty()) continue;
    fs::path t = o.mesh_path;
    t.replace_extension(".stiffening.csv");
    if (fs::is_regular_file(t)) return t;
  }
  return {};
}

struct Finger {
  Vector3d p_O;      // contact point on the rest surface
  Vector3d n_out_O;  // outward normal there (triangle normal)
};

// The fingers of a press: the centre one where the part's ray meets the surface, the others of
// a row along row_O (the horn's follows its curved spine), each where a ray parallel to the
// first meets the surface.
inline std::vector<Finger> FindFingers(const Part& part, int fingers) {
  const auto& mesh = *part.prepared.mesh;
  const auto& surface = *part.prepared.surface;
  std::vector<Finger> out;
  for (int k = 0; k < fingers; ++k) {
    const double offset = fingers == 1 ? 0.0 : (k - (fingers - 1) / 2.0) * part.spec->spacing_m;
    const Vector3d from = part.spec->from_O + offset * part.spec->row_O.normalized();
    const auto hits = RayHits(mesh, surface, from, part.spec->approach_O, 0.0);
    if (hits.empty()) {
      Fail(std::string(part.spec->name) + ": the press ray of finger " + std::to_string(k) + " misses the part");
    }
    out.push_back({from + hits.front().first * part.spec->approach_O, TriangleNormal(mesh, surface.triangles[hits.front().second])});
  }
  return out;
}

}  // namespace handshare::bench
