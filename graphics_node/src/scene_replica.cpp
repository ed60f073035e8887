#include "handshare/graphics/scene_replica.hpp"

#include "handshare/scene/scene.hpp"

#include <cmath>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include <nlohmann/json.hpp>

namespace handshare::graphics {

namespace {

/// X_WO from a position and a (w, x, y, z) quaternion; empty if non-finite or |q| ~ 0.
std::optional<Eigen::Isometry3d> PoseOf(const std::array<double, 3>& p, const std::array<double, 4>& q) {
  const Eigen::Vector3d p_WO(p[0], p[1], p[2]);
  const Eigen::Vector4d q_wxyz(q[0], q[1], q[2], q[3]);
  if (!p_WO.allFinite() || !q_wxyz.allFinite() || q_wxyz.norm() < 1e-9) return std::nullopt;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  X.translation() = p_WO;
  return X;
}

void Add(DeformationStats& sum, const DeformationStats& s) {
  sum.samples += s.samples;
  sum.keyframes += s.keyframes;
  sum.ids_out_of_range += s.ids_out_of_range;
  sum.nonfinite += s.nonfinite;
  sum.malformed += s.malformed;
}

render::Rgb RgbOf(const msg::SceneObject& o) { return {o.rgb()[0], o.rgb()[1], o.rgb()[2]}; }

}  // namespace

SceneReplica::SceneReplica(std::filesystem::path assets_dir, std::ostream& errors, std::string prefix)
    : errors_(errors), prefix_(std::move(prefix)), scenes_dir_(assets_dir / "scenes"), meshes_(std::move(assets_dir)) {}

void SceneReplica::OnControlState(const msg::ControlState& state) {
  control_states_[state.control_id().to_string()] = {state.scene().to_string(), state.index(), state.engaged()};
}

std::optional<std::pair<std::int32_t, bool>> SceneReplica::control_state(const std::string& control_id) const {
  const auto it = control_states_.find(control_id);
  if (it == control_states_.end() || it->second.scene != scene_) return std::nullopt;
  return std::pair{it->second.index, it->second.engaged};
}

Eigen::Isometry3d SceneReplica::DrawnPose(const std::string& id, const Eigen::Isometry3d& X_WO) const {
  const auto g = control_geometry_.find(id);
  const auto state = control_state(id);
  if (g == control_geometry_.end() || !state) return X_WO;
  const auto [index, engaged] = *state;
  const auto& angles = g->second.detent_angles_rad;
  if (index >= 0 && static_cast<std::size_t>(index) < angles.size()) {
    // The handle turns about the hinge axis x of C, from z towards -y as the angle grows.
    return X_WO * Eigen::AngleAxisd(angles[static_cast<std::size_t>(index)], Eigen::Vector3d::UnitX());
  }
  if (engaged) return X_WO * Eigen::Translation3d(0.0, 0.0, -g->second.travel_m);
  return X_WO;
}

void SceneReplica::OnSceneState(const msg::SceneState& state) {
  const std::string scene = state.scene().to_string();
  const bool another_scene = !has_scene_ || scene != scene_;
  if (another_scene) {
    // Deformations and poses belong to the scene they were sent for.
    for (const auto& [id, o] : objects_) {
      if (o.field) Add(retired_, o.field->stats());
    }
    objects_.clear();
    reported_.clear();
    if (has_scene_) ++stats_.scene_changes;
    // The controls' geometry, for drawing them in their state (the meshes are not loaded
    // again). No file of that name (a scene these assets do not have): its controls at rest.
    control_geometry_.clear();
    std::error_code ec;
    if (std::filesystem::exists(scenes_dir_ / (scene + ".json"), ec)) {
      try {
        const scene::Scene file = scene::LoadSceneByName(scene, scenes_dir_, scene::LoadOptions{.load_meshes = false});
        for (const auto& c : file.controls) {
          ControlGeometry g;
          if (c.type == scene::ControlType::kLever) {
            for (int k = 0; k < c.lever.detents; ++k) g.detent_angles_rad.push_back(c.lever.detent_angle_rad(k));
          } else if (c.type == scene::ControlType::kButton || c.type == scene::ControlType::kArrow) {
            g.travel_m = c.push.travel_m;
          }
          control_geometry_[c.id] = std::move(g);
        }
      } catch (const std::exception& e) {
        errors_ << prefix_ << "cannot read the controls of scene '" << scene << "' (drawn at rest): " << e.what()
                << "\n";
      }
    }
  }
  has_scene_ = true;
  scene_ = scene;

  std::map<std::string, Object> next;
  order_.clear();
  for (const msg::SceneObject& spec : state.objects()) {
    const std::string id = spec.object_id().to_string();
    if (next.count(id) != 0) continue;  // ids are unique in a valid scene; keep the first
    Object o;
    // A previous revision's pose, mesh and field carry over for an object that remains.
    if (const auto it = objects_.find(id); it != objects_.end()) o = std::move(it->second);
    o.spec = spec;
    o.X_WO_scene = PoseOf(spec.p_WO_m(), spec.q_WO_wxyz()).value_or(Eigen::Isometry3d::Identity());
    std::shared_ptr<const render::TriangleMesh> mesh;
    if (spec.shape() == "mesh") {
      const std::string uri = spec.mesh_uri().to_string();
      const MeshCache::Entry& entry = meshes_.Get(uri);
      mesh = entry.mesh;
      if (!mesh && reported_.insert(id).second) {
        ++stats_.mesh_errors;
        errors_ << prefix_ << "object '" << id << "' of scene '" << scene_ << "': cannot load mesh '"
                << uri << "' (file " << entry.file.string() << "): " << entry.error
                << "; drawing its bounding box instead" << std::endl;
      }
    }
    if (mesh != o.mesh) {
      if (o.field) Add(retired_, o.field->stats());
      o.field = mesh ? std::make_unique<DeformationField>(mesh->p_MV.size()) : nullptr;
      o.mesh = std::move(mesh);
    }
    order_.push_back(id);
    next.emplace(id, std::move(o));
  }
  for (const auto& [id, o] : objects_) {
    if (o.field && next.count(id) == 0) Add(retired_, o.field->stats());
  }
  objects_ = std::move(next);
}

void SceneReplica::OnDeformation(const msg::Deformation& sample) {
  ++stats_.deformation_samples;
  const auto it = objects_.find(sample.object_id().to_string());
  if (it == objects_.end()) {
    ++stats_.deformation_unknown_object;
    return;
  }
  if (!it->second.field) {
    ++stats_.deformation_without_mesh;
    return;
  }
  DeformationField& field = *it->second.field;
  if (sample.surface_node_count() != 0 && sample.surface_node_count() != field.vertex_count()) {
    ++stats_.deformation_count_mismatch;
  }
  field.Apply(sample.revision(), sample.keyframe(), sample.node_ids(), sample.u_W_m());
}

void SceneReplica::OnObjectState(const msg::ObjectState& state) {
  const auto it = objects_.find(state.object_id().to_string());
  if (it == objects_.end()) {
    ++stats_.object_states_unknown;
    return;
  }
  const auto X_WO = PoseOf(state.p_WO_m(), state.q_WO_wxyz());
  if (!X_WO) {
    ++stats_.object_states_nonfinite;
    return;
  }
  it->second.X_WO_state = *X_WO;
  ++stats_.object_states;
}

std::optional<Eigen::Isometry3d> SceneReplica::X_WO(const std::string& object_id) const {
  const auto it = objects_.find(object_id);
  if (it == objects_.end()) return std::nullopt;
  return it->second.X_WO();
}

bool SceneReplica::pose_received(const std::string& object_id) const {
  const auto it = objects_.find(object_id);
  return it != objects_.end() && it->second.X_WO_state.has_value();
}

const DeformationField* SceneReplica::deformation(const std::string& object_id) const {
  const auto it = objects_.find(object_id);
  return it == objects_.end() ? nullptr : it->second.field.get();
}

DeformationStats SceneReplica::deformation_stats() const {
  DeformationStats sum = retired_;
  for (const auto& [id, o] : objects_) {
    if (o.field) Add(sum, o.field->stats());
  }
  return sum;
}

void SceneReplica::AddObjects(render::SceneView& view) const {
  for (const std::string& id : order_) {
    const Object& o = objects_.at(id);
    const Eigen::Isometry3d X_WO = DrawnPose(id, o.X_WO());
    const auto& h = o.spec.half_extent_m();
    if (o.mesh) {
      render::TriangleMesh mesh = *o.mesh;
      mesh.X_WM = X_WO;
      mesh.rgb = RgbOf(o.spec);
      if (o.field && o.field->displaced()) {
        // p_WV = X_WO p_OV + u_W  <=>  p_OV' = p_OV + R_WO^T u_W, drawn with X_WM = X_WO.
        const Eigen::Matrix3d R_OW = X_WO.linear().transpose();
        const auto& u_W = o.field->u_W_m();
        for (std::size_t v = 0; v < mesh.p_MV.size(); ++v) {
          if (!u_W[v].isZero(0.0)) mesh.p_MV[v] += R_OW * u_W[v];
        }
        AreaWeightedNormals(mesh.p_MV, mesh.triangles, mesh.n_MV);
      }
      view.meshes.push_back(std::move(mesh));
    } else if (o.spec.shape() == "sphere") {
      view.spheres.push_back(render::Sphere{X_WO.translation(), h[0], RgbOf(o.spec)});
    } else {
      // Boxes, and meshes that could not be loaded: their bounding box.
      render::Box box;
      box.p_W = X_WO.translation();
      box.half_extents_m = Eigen::Vector3d(h[0], h[1], h[2]);
      box.q_WB = Eigen::Quaterniond(X_WO.linear());
      box.rgb = RgbOf(o.spec);
      view.boxes.push_back(box);
    }
  }
}

void SceneReplica::WriteDeformationJson(const std::filesystem::path& file) const {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (const std::string& id : order_) {
    const Object& o = objects_.at(id);
    if (!o.field || !o.field->revision()) continue;
    nlohmann::ordered_json u = nlohmann::ordered_json::object();
    const auto& u_W = o.field->u_W_m();
    for (std::size_t v = 0; v < u_W.size(); ++v) {
      if (!u_W[v].isZero(0.0)) u[std::to_string(v)] = {u_W[v].x(), u_W[v].y(), u_W[v].z()};
    }
    out[id] = {{"revision", *o.field->revision()},
               {"vertex_count", o.field->vertex_count()},
               {"u_W_m", std::move(u)}};
  }
  std::filesystem::path tmp = file;
  tmp += ".tmp";
  {
    std::ofstream stream(tmp);
    if (!stream) throw std::runtime_error("cannot write deformation file " + tmp.string());
    stream << out.dump(2) << "\n";
    stream.close();
    if (!stream) throw std::runtime_error("cannot write deformation file " + tmp.string());
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) throw std::runtime_error("cannot write deformation file " + file.string() + ": " + ec.message());
}

}  // namespace handshare::graphics
