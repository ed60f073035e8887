#include "handshare/world/scene_models.hpp"

#include <stdexcept>

namespace handshare::world {

namespace {

contact::Shape ShapeOf(const scene::SceneObject& o) {
  switch (o.shape) {
    case scene::Shape::kSphere:
      return contact::Shape::Sphere(o.half_extent_m.x());
    case scene::Shape::kBox:
      return contact::Shape::Box(2.0 * o.half_extent_m);
    case scene::Shape::kMesh: {
      if (!o.mesh) throw scene::SceneError("object '" + o.id + "': mesh not loaded");
      auto mesh = std::make_shared<contact::TriMesh>();
      mesh->p_O_m = o.mesh->vertices_m;
      mesh->triangles = o.mesh->triangles;
      return contact::Shape::Mesh(std::move(mesh));
    }
  }
  throw std::logic_error("unknown shape");
}

contact::RigidMaterial MaterialOf(const scene::SceneObject& o) {
  contact::RigidMaterial m;
  m.stiffness_N_per_m = o.rigid.stiffness_N_per_m;
  m.damping_N_s_per_m = o.rigid.damping_N_s_per_m;
  m.mu_static = o.rigid.mu_static;
  m.mu_kinetic = o.rigid.mu_kinetic;
  return m;
}

}  // namespace

SceneModels BuildSceneModels(const scene::Scene& scene, const SceneModelsOptions& options) {
  contact::WorldConfig config;
  config.max_hands = options.max_hands;
  config.fingertip_radius_m = options.fingertip_radius_m;
  config.max_force_N = options.max_force_N;
  config.gravity_W_m_per_s2 = scene.gravity_W_m_per_s2;
  SceneModels out;
  out.world = std::make_unique<contact::HapticWorld>(config);
  auto& w = *out.world;
  for (const auto& o : scene.objects) {
    contact::ObjectId id = -1;
    switch (o.kind) {
      case scene::ObjectKind::kControl:
        if (!options.include_controls) continue;
        id = w.AddStatic(ShapeOf(o), MaterialOf(o), o.X_WO());
        break;
      case scene::ObjectKind::kRigid:
        if (o.mass_kg > 0.0) {
          contact::BodyProperties body;
          body.mass_kg = o.mass_kg;
          // Rolling resistance (a felt-covered table): a released ball stops within about
          // 0.3 s instead of rolling for ever, as a frictionless roll on the support would.
          // Angular decay time I / c with I ~ 0.4 m r^2; a little linear drag likewise.
          const double r = o.half_extent_m.maxCoeff();
          body.linear_damping_N_s_per_m = 0.2 * o.mass_kg;
          body.angular_damping_N_m_s = 0.4 * o.mass_kg * r * r / 0.3;
          id = w.AddDynamic(ShapeOf(o), MaterialOf(o), body, o.X_WO());
          out.dynamic_bodies.push_back(id);
        } else {
          id = w.AddStatic(ShapeOf(o), MaterialOf(o), o.X_WO());
          if (o.id == options.support_object && o.shape == scene::Shape::kBox) {
            contact::SupportPlane plane;
            plane.n_W = Eigen::Vector3d::UnitZ();
            plane.offset_m = o.p_WO_m.z() + o.half_extent_m.z();
            w.SetSupport(plane);
          }
        }
        break;
      case scene::ObjectKind::kDeformable: {
        PreparedDeformable prepared = PrepareDeformable(scene, o, options.cache_dir);
        contact::DeformableDesc desc;
        desc.mesh = prepared.mesh;
        desc.compliance = prepared.compliance;
        desc.X_WO = o.X_WO();
        desc.mu_static = o.deformable.mu_static;
        desc.mu_kinetic = o.deformable.mu_kinetic;
        desc.mode_O_m = prepared.mode_O_m;
        if (options.stiffening) desc.stiffening = prepared.stiffening;
        id = w.AddDeformable(desc);
        out.deformables.push_back(std::move(prepared));
        break;
      }
    }
    if (id >= static_cast<contact::ObjectId>(out.ids.size())) out.ids.resize(id + 1);
    out.ids[id] = o.id;
    out.index[o.id] = id;
  }
  w.Init();
  return out;
}

}  // namespace handshare::world
