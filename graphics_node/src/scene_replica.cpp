#include "handshare/graphics/scene_replica.hpp"

#include "handshare/scene/scene.hpp"
#include "handshare/contact/finger_contact.hpp"  // contact::ToPose

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <system_error>

#include <nlohmann/json.hpp>

namespace handshare::graphics {

namespace {

/// X_WO from a position and a (w, x, y, z) quaternion (contact::ToPose); empty if non-finite or
/// |q| <= 0.5 (the sample checks refuse such a state before it gets here).
std::optional<Eigen::Isometry3d> PoseOf(const std::array<double, 3>& p, const std::array<double, 4>& q) {
  Eigen::Isometry3d X;
  if (!contact::ToPose(p, q, X)) return std::nullopt;
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

// Where an object's label points: 1 cm above its top, over its middle (a mesh's drawn
// vertices; a sphere's or box's centre and half height).
template <typename Object>
Eigen::Vector3d LabelPoint(const Object& o, const Eigen::Isometry3d& X_WO) {
  constexpr double kAbove_m = 0.01;
  if (o.mesh && !o.mesh->p_MV.empty()) {
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& p : o.mesh->p_MV) box.extend(X_WO * p);
    return Eigen::Vector3d(box.center().x(), box.center().y(), box.max().z() + kAbove_m);
  }
  const auto& h = o.spec.half_extent_m();
  const double up = o.spec.shape() == "sphere" ? h[0] : h[2];
  return X_WO.translation() + Eigen::Vector3d(0.0, 0.0, up + kAbove_m);
}

}  // namespace

SceneReplica::SceneReplica(std::filesystem::path assets_dir, std::ostream& errors, std::string prefix,
                           std::string language)
    : errors_(errors),
      prefix_(std::move(prefix)),
      scenes_dir_(assets_dir / "scenes"),
      language_(std::move(language)),
      meshes_(std::move(assets_dir)) {}

void SceneReplica::OnControlState(const msg::ControlState& state) {
  control_states_[state.control_id().to_string()] = {state.scene().to_string(), state.index(), state.engaged(),
                                                     state.moving(), state.position()};
}

const SceneReplica::ControlDrawn* SceneReplica::drawn_state(const std::string& control_id) const {
  const auto it = control_states_.find(control_id);
  return it == control_states_.end() || it->second.scene != scene_ ? nullptr : &it->second;
}

std::optional<std::pair<std::int32_t, bool>> SceneReplica::control_state(const std::string& control_id) const {
  const ControlDrawn* s = drawn_state(control_id);
  if (s == nullptr) return std::nullopt;
  return std::pair{s->index, s->engaged};
}

Eigen::Isometry3d SceneReplica::DrawnPose(const std::string& id, const Eigen::Isometry3d& X_WO) const {
  const auto g = control_geometry_.find(id);
  const ControlDrawn* drawn = drawn_state(id);
  if (g == control_geometry_.end() || drawn == nullptr) return X_WO;
  if (drawn->moving) {  // where the hand has it now
    if (!g->second.detent_angles_rad.empty()) return X_WO * Eigen::AngleAxisd(drawn->position, Eigen::Vector3d::UnitX());
    if (g->second.travel_m > 0.0) {
      return X_WO * Eigen::Translation3d(0.0, 0.0, -std::clamp(drawn->position, 0.0, g->second.travel_m));
    }
  }
  const auto index = drawn->index;
  const bool engaged = drawn->engaged;
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
    labels_.clear();
    looks_.clear();
    std::error_code ec;
    if (std::filesystem::exists(scenes_dir_ / (scene + ".json"), ec)) {
      try {
        const scene::Scene file = scene::LoadSceneByName(scene, scenes_dir_, scene::LoadOptions{.load_meshes = false});
        for (const auto& o : file.objects) {  // objects and the controls' visuals
          if (const std::string& label = scene::TextIn(o.label, language_); !label.empty()) labels_[o.id] = label;
          looks_[o.id] = render::Appearance{static_cast<float>(o.appearance.specular),
                                            static_cast<float>(o.appearance.shininess),
                                            static_cast<float>(o.appearance.opacity)};
        }
        for (const auto& c : file.controls) {
          ControlGeometry g;
          if (c.type == scene::ControlType::kLever) {
            for (int k = 0; k < c.lever.detents; ++k) g.detent_angles_rad.push_back(c.lever.detent_angle_rad(k));
          } else if (c.type == scene::ControlType::kButton || c.type == scene::ControlType::kArrow) {
            g.travel_m = c.push.travel_m;
          } else if (c.type == scene::ControlType::kBook) {
            g.book = true;
            g.X_WC.linear() = c.q_WC.toRotationMatrix();
            g.X_WC.translation() = c.p_WC_m;
            g.size_m = c.size_m;
            for (const scene::BookPage& page : c.page_content) g.pages.push_back({page.TextIn(language_), page.image_path});
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
  it->second.state_stamp_ns = state.stamp_ns();
  ++stats_.object_states;
}

std::string SceneReplica::pose_stamps() const {
  std::string out;
  for (const std::string& id : order_) {
    const Object& o = objects_.at(id);
    if (!o.X_WO_state) continue;
    out += (out.empty() ? "" : ";") + id + "@" + std::to_string(o.state_stamp_ns);
  }
  return out;
}

std::string SceneReplica::field_revisions() const {
  std::string out;
  for (const std::string& id : order_) {
    const Object& o = objects_.at(id);
    if (!o.field || !o.field->revision()) continue;
    out += (out.empty() ? "" : ";") + id + "@" + std::to_string(*o.field->revision());
  }
  return out;
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

std::shared_ptr<const render::ImageRgb8> SceneReplica::PageImage(const std::filesystem::path& file) const {
  if (file.empty()) return nullptr;
  if (const auto it = page_images_.find(file); it != page_images_.end()) return it->second;
  std::shared_ptr<const render::ImageRgb8> image;
  try {
    image = std::make_shared<const render::ImageRgb8>(render::ReadPng(file));
  } catch (const std::exception& e) {
    errors_ << prefix_ << "cannot read the book page picture " << file.string() << " (drawn blank): " << e.what()
            << std::endl;
  }
  page_images_.emplace(file, image);
  return image;
}

void SceneReplica::AddBook(render::SceneView& view, const std::string& id, const ControlGeometry& book,
                           const render::Rgb& rgb) const {
  // In C: spine along y at x = -w/2, the closed book's top at z = 0, its back cover at z = -t.
  const double w = book.size_m.x();
  const double h = book.size_m.y();
  const double t = book.size_m.z();
  const double cover = std::min(0.003, t / 5.0);  // a cover's thickness
  const double inset = std::min(0.003, w / 20.0);  // how far the pages stay inside the covers
  const render::Rgb paper{0.96F, 0.94F, 0.88F};
  const Eigen::Quaterniond q_WC(book.X_WC.linear());
  const auto box = [&](const Eigen::Vector3d& lo_C, const Eigen::Vector3d& hi_C, const render::Rgb& colour) {
    render::Box b;
    b.p_W = book.X_WC * (0.5 * (lo_C + hi_C));
    b.half_extents_m = 0.5 * (hi_C - lo_C);
    b.q_WB = q_WC;
    b.rgb = colour;
    view.boxes.push_back(b);
  };
  const render::Rgb spine{0.7F * rgb.r, 0.7F * rgb.g, 0.7F * rgb.b};
  box({-0.5 * w, -0.5 * h, -t}, {0.5 * w, 0.5 * h, -t + cover}, rgb);  // the back cover
  const ControlDrawn* state = drawn_state(id);
  const bool open = state != nullptr && state->engaged;
  if (!open) {
    // The front cover, shut, or lifted by a hand: turned about the spine's top edge (x = -w/2,
    // z = 0) towards -x by the cover's angle.
    const double angle = state != nullptr && state->moving ? std::clamp(state->position, 0.0, std::numbers::pi) : 0.0;
    render::Box front;
    const Eigen::Isometry3d X_CF = Eigen::Translation3d(-0.5 * w, 0.0, 0.0) *
                                   Eigen::AngleAxisd(-angle, Eigen::Vector3d::UnitY()) *
                                   Eigen::Translation3d(0.5 * w, 0.0, -0.5 * cover);
    const Eigen::Isometry3d X_WF = book.X_WC * X_CF;
    front.p_W = X_WF.translation();
    front.half_extents_m = Eigen::Vector3d(0.5 * w, 0.5 * h, 0.5 * cover);
    front.q_WB = Eigen::Quaterniond(X_WF.linear());
    front.rgb = rgb;
    view.boxes.push_back(front);
    box({-0.5 * w, -0.5 * h, -t}, {-0.5 * w + cover, 0.5 * h, 0.0}, spine);          // the spine
    box({-0.5 * w + cover, -0.5 * h + inset, -t + cover}, {0.5 * w - inset, 0.5 * h - inset, -cover}, paper);
    return;
  }
  // Open: the front cover lies flat on the left, the pages on both sides up to z = 0.
  box({-1.5 * w, -0.5 * h, -t}, {-0.5 * w, 0.5 * h, -t + cover}, rgb);
  box({-0.5 * w - 0.5 * cover, -0.5 * h, -t}, {-0.5 * w + 0.5 * cover, 0.5 * h, -t + 2.0 * cover}, spine);
  box({-0.5 * w, -0.5 * h + inset, -t + cover}, {0.5 * w - inset, 0.5 * h - inset, 0.0}, paper);
  box({-1.5 * w + inset, -0.5 * h + inset, -t + cover}, {-0.5 * w, 0.5 * h - inset, 0.0}, paper);
  const int index = std::max(0, state->index);
  if (static_cast<std::size_t>(index) >= book.pages.size()) return;  // a blank spread
  const auto& spread = book.pages[static_cast<std::size_t>(index)];
  constexpr double kAbove = 0.0004;  // the print lies on the paper, not in it
  const auto page = [&](double x0, double x1) {
    render::Page p;
    const double y0 = -0.5 * h + inset;
    const double y1 = 0.5 * h - inset;
    p.corners_W = {book.X_WC * Eigen::Vector3d(x0, y0, kAbove), book.X_WC * Eigen::Vector3d(x1, y0, kAbove),
                   book.X_WC * Eigen::Vector3d(x1, y1, kAbove), book.X_WC * Eigen::Vector3d(x0, y1, kAbove)};
    p.paper = paper;
    return p;
  };
  render::Page left = page(-1.5 * w + inset, -0.5 * w);
  left.image = PageImage(spread.image);
  render::Page right = page(-0.5 * w, 0.5 * w - inset);
  right.text = spread.text;
  if (left.image) view.pages.push_back(std::move(left));
  if (!right.text.empty()) view.pages.push_back(std::move(right));
}

void SceneReplica::AddObjects(render::SceneView& view) const {
  for (const std::string& id : order_) {
    const Object& o = objects_.at(id);
    if (const auto label = labels_.find(id); label != labels_.end()) {
      render::Label l;
      l.p_W = LabelPoint(o, DrawnPose(id, o.X_WO()));
      l.text = label->second;
      view.labels.push_back(std::move(l));
    }
    if (const auto g = control_geometry_.find(id); g != control_geometry_.end() && g->second.book) {
      AddBook(view, id, g->second, RgbOf(o.spec));
      continue;
    }
    const Eigen::Isometry3d X_WO = DrawnPose(id, o.X_WO());
    const auto& h = o.spec.half_extent_m();
    const auto look_it = looks_.find(id);
    const render::Appearance look = look_it == looks_.end() ? render::Appearance{} : look_it->second;
    if (o.mesh) {
      render::TriangleMesh mesh = *o.mesh;
      mesh.X_WM = X_WO;
      mesh.rgb = RgbOf(o.spec);
      mesh.look = look;
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
      view.spheres.push_back(render::Sphere{X_WO.translation(), h[0], RgbOf(o.spec), look});
    } else {
      // Boxes, and meshes that could not be loaded: their bounding box.
      render::Box box;
      box.p_W = X_WO.translation();
      box.half_extents_m = Eigen::Vector3d(h[0], h[1], h[2]);
      box.q_WB = Eigen::Quaterniond(X_WO.linear());
      box.rgb = RgbOf(o.spec);
      box.look = look;
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
