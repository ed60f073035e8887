// ScriptedMotion: the scene's motions and beats on the session clock, the one stage the haptic
// renderer and the world server both run before a step.
#include "handshare/world/scripted_motion.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "handshare/testing/allocation_counter.hpp"

namespace handshare::world {
namespace {

scene::Scene WriteAndLoad(const std::string& name, const std::string& objects) {
  const auto dir = std::filesystem::temp_directory_path() / ("handshare_scripted_test_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "scenes");
  const auto file = dir / "scenes" / (name + ".json");
  std::ofstream(file) << R"({"name": ")" << name << R"(", "objects": [)" << objects
                      << R"(], "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  return scene::LoadScene(file);
}

// A bobbing sphere, a ball at rest, a beating block: Apply puts the first where its motion has
// it and the block at its beat's scale, at the session time it is given, and leaves the ball.
TEST(ScriptedMotion, MovesAndBeatsTheScenesObjectsAtTheSessionTime) {
  const scene::Scene s = WriteAndLoad("scripted",
      R"({"id": "bob", "kind": "rigid", "shape": "sphere", "position_m": [0.3, 0, 0.1], "radius_m": 0.02,
          "motion": {"direction": [0, 0, 1], "amplitude_m": 0.01, "period_s": 2.0, "phase_rad": 0.5}},
         {"id": "ball", "kind": "rigid", "shape": "sphere", "position_m": [-0.3, 0, 0.1], "radius_m": 0.02, "mass_kg": 0.1},
         {"id": "block", "kind": "deformable", "shape": "box", "position_m": [0, 0, 0.02],
          "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.3},
          "fixed": {"below_m": -0.0099},
          "beat": {"driven": {"plane_point_m": [0, 0, 0.0099], "plane_normal": [0, 0, -1]},
                   "displacement_m": [0, 0, 0.002], "period_s": 1.0}})");
  SceneModelsOptions options;
  options.cache_dir = std::filesystem::temp_directory_path() / "handshare_scripted_test_cache";
  SceneModels models = BuildSceneModels(s, options);
  const ScriptedMotion scripted(s, models);
  ASSERT_EQ(scripted.moving().size(), 1u);
  EXPECT_EQ(scripted.moving()[0].id, "bob");
  EXPECT_EQ(scripted.moving()[0].object, models.Find("bob"));
  ASSERT_EQ(scripted.beating().size(), 1u);
  EXPECT_EQ(scripted.beating()[0].object, models.Find("block"));
  EXPECT_FALSE(scripted.empty());

  auto& world = *models.world;
  const Eigen::Isometry3d ball = world.pose(models.Find("ball"));
  for (const double t : {0.3, 1.7, 12.25}) {
    const long before = testing::AllocationCount();
    scripted.Apply(world, t);
    EXPECT_EQ(testing::AllocationCount() - before, 0);
    const scene::SceneObject& bob = s.objects[0];
    Eigen::Isometry3d X = bob.X_WO();
    X.translation() += bob.motion.Offset_W(t);
    EXPECT_EQ(world.pose(models.Find("bob")).matrix(), X.matrix()) << t;
    EXPECT_EQ(world.mode_scale(models.Find("block")), s.objects[2].beat.Scale(t)) << t;
    EXPECT_NE(world.mode_scale(models.Find("block")), 0.0) << t;
    EXPECT_EQ(world.pose(models.Find("ball")).matrix(), ball.matrix()) << t;
  }
  EXPECT_TRUE(ScriptedMotion().empty());
}

}  // namespace
}  // namespace handshare::world
