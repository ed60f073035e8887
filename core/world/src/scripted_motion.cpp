#include "handshare/world/scripted_motion.hpp"

namespace handshare::world {

ScriptedMotion::ScriptedMotion(const scene::Scene& scene, const SceneModels& models) {
  for (const auto& o : scene.objects) {
    const contact::ObjectId object = models.Find(o.id);
    if (object < 0) continue;
    if (o.motion.active()) moving_.push_back({object, o.id, o.X_WO(), o.motion});
    if (o.beat.active()) beating_.push_back({object, o.beat});
  }
}

void ScriptedMotion::Apply(contact::HapticWorld& world, double t_s) const noexcept {
  for (const Moving& m : moving_) {
    Eigen::Isometry3d X = m.X_WO;
    X.translation() += m.motion.Offset_W(t_s);
    world.SetPose(m.object, X);
  }
  for (const Beating& b : beating_) world.SetModeScale(b.object, b.beat.Scale(t_s));
}

}  // namespace handshare::world
