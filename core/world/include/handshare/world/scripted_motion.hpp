#pragma once
/// The scene's objects that move by themselves on the session clock: periodic motions
/// (scene::Motion: the Daphnia swims) and beats (scene::Beat: its body beats). Every process
/// that steps a haptic world of the scene (the haptic renderer at each haptic step, the world
/// server at each tick) applies them through here, so they move the same way everywhere.
/// Built once per scene (allocates); Apply() is real-time safe.
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "handshare/contact/haptic_world.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/world/scene_models.hpp"

namespace handshare::world {

class ScriptedMotion {
 public:
  /// An object that moves periodically: at X_WO (the scene's pose) plus Motion::Offset_W(t).
  struct Moving {
    contact::ObjectId object = -1;  ///< world object index
    std::string id;                 ///< scene object id
    Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
    scene::Motion motion;
  };
  /// A deformable whose mode (DeformableDesc::mode_O_m) beats at Beat::Scale(t).
  struct Beating {
    contact::ObjectId object = -1;
    scene::Beat beat;
  };

  ScriptedMotion() = default;
  /// The active motions and beats of `scene`'s objects that `models` has (copied: the scene
  /// may go away).
  ScriptedMotion(const scene::Scene& scene, const SceneModels& models);

  /// Puts every moving object at its pose at session time t_s (HapticWorld::SetPose, which
  /// zeroes a dynamic body's velocity) and every beating deformable at its beat's scale
  /// (HapticWorld::SetModeScale). Motions first, then beats. noexcept, no allocation.
  void Apply(contact::HapticWorld& world, double t_s) const noexcept;

  std::span<const Moving> moving() const noexcept { return moving_; }
  std::span<const Beating> beating() const noexcept { return beating_; }
  bool empty() const noexcept { return moving_.empty() && beating_.empty(); }

 private:
  std::vector<Moving> moving_;
  std::vector<Beating> beating_;
};

}  // namespace handshare::world
