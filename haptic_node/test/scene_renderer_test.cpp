// SceneRenderer following a body simulated elsewhere: between the (display-rate) samples the
// body moves on at its published velocity from where it was when the sample arrived (dead
// reckoning, capped), instead of standing still and jumping by v / 60 Hz at the next sample.
#include "handshare/haptic/scene_renderer.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "handshare/common/clock.hpp"
#include "handshare/scene/scene.hpp"

namespace handshare::haptic {
namespace {

TEST(SceneRenderer, FollowedBodyGlidesOnAtItsPublishedVelocityBetweenSamples) {
  const auto dir = std::filesystem::temp_directory_path() / "handshare_scene_renderer_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "scenes");
  const auto file = dir / "scenes" / "moon.json";
  std::ofstream(file) << R"({"name": "moon", "gravity_m_per_s2": [0, 0, -1.62], "objects": [
      {"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]},
      {"id": "ball", "kind": "rigid", "shape": "sphere", "position_m": [0, 0, 0.04], "radius_m": 0.04, "mass_kg": 0.2}],
      "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  world::SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  SceneRenderer r(scene::LoadScene(file), options);
  const auto ball = r.models().Find("ball");
  ASSERT_GE(ball, 0);
  DeviceReading far;
  for (auto& p : far.p_WE) p = Eigen::Vector3d(1.0, 1.0, 1.0);
  far.valid = true;
  std::array<Eigen::Vector3d, kFingers> f{};

  auto follow = [&](double age_s) -> Eigen::Vector3d {
    FollowedBodies fb;
    fb.count = 1;
    fb.items[0].object = ball;
    fb.items[0].p_WO_m[0] = 0.0;
    fb.items[0].p_WO_m[1] = 0.0;
    fb.items[0].p_WO_m[2] = 0.2;
    fb.items[0].v_WO_m_per_s[0] = 0.5;
    fb.items[0].received_ns = common::SteadyNowNs() - static_cast<std::uint64_t>(age_s * 1e9);
    r.SetFollowed(fb);
    r.Render(0.0, 1e-3, far, f);
    return r.models().world->pose(ball).translation();
  };
  // A sample that arrived 20 ms ago: 10 mm on (+ the step's own 0.5 mm), not where it was.
  const Eigen::Vector3d p20 = follow(0.020);
  EXPECT_GT(p20.x(), 0.5 * 0.020 + 0.5e-3 - 1e-6);
  EXPECT_LT(p20.x(), 0.5 * 0.025 + 0.5e-3);  // 5 ms for the test's own scheduling
  EXPECT_NEAR(r.models().world->body_velocity_W(ball).x(), 0.5, 1e-3);  // less 1 ms of air damping
  // A sample that stopped coming 10 s ago (a lost server): at most 0.1 s of dead reckoning.
  const Eigen::Vector3d p10 = follow(10.0);
  EXPECT_NEAR(p10.x(), 0.5 * FollowedBodies::kMaxDeadReckoning_s + 0.5e-3, 1e-6);
  std::filesystem::remove_all(dir);
}

// The newest peer set's sender stamp comes back in the report with the step that first used
// it (the bridge turns the two into the set's age at the haptic loop, bench/net); a set the
// loop already used keeps its first step's time. Every report carries its step's time.
TEST(SceneRenderer, ReportsTheStepThatFirstUsedANewPeerSet) {
  const auto dir = std::filesystem::temp_directory_path() / "handshare_scene_renderer_peer_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "scenes");
  const auto file = dir / "scenes" / "flat.json";
  std::ofstream(file) << R"({"name": "flat", "gravity_m_per_s2": [0, 0, -9.81], "objects": [
      {"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]}],
      "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  world::SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  SceneRenderer r(scene::LoadScene(file), options);
  DeviceReading far;
  for (auto& p : far.p_WE) p = Eigen::Vector3d(1.0, 1.0, 1.0);
  far.valid = true;
  std::array<Eigen::Vector3d, kFingers> f{};
  ContactReport report;

  r.Render(0.0, 1e-3, far, f);
  ASSERT_TRUE(r.TakeReport(report));
  EXPECT_EQ(report.peer_stamp_ns, 0u);  // no peer set yet
  EXPECT_EQ(report.peer_seen_ns, 0u);

  RemoteContacts remote;
  remote.newest_stamp_ns = common::SteadyNowNs();
  r.SetRemote(remote);
  const std::uint64_t before = common::SteadyNowNs();
  r.Render(0.0, 1e-3, far, f);
  const std::uint64_t after = common::SteadyNowNs();
  ASSERT_TRUE(r.TakeReport(report));
  EXPECT_EQ(report.peer_stamp_ns, remote.newest_stamp_ns);
  EXPECT_GE(report.peer_seen_ns, before);
  EXPECT_LE(report.peer_seen_ns, after);
  EXPECT_GE(report.step_ns, before);  // the step's own time: the sender's report age
  EXPECT_LE(report.step_ns, after);

  // The same set again (the bridge sends the newest every tick): the first step's time stays.
  const std::uint64_t first_seen = report.peer_seen_ns;
  r.SetRemote(remote);
  r.Render(0.0, 1e-3, far, f);
  ASSERT_TRUE(r.TakeReport(report));
  EXPECT_EQ(report.peer_seen_ns, first_seen);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace handshare::haptic
