// The spectator over real Fast DDS on loopback (one domain for this file): what it draws and
// writes comes from the scene state, object state and deformation topics.
#include "handshare/graphics/spectator.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "handshare/render/image.hpp"
#include "test_oracle.hpp"
#include "world_messages.hpp"

namespace handshare::graphics {
namespace {

constexpr int kDomain = 148;

Eigen::Isometry3d At(double x, double y, double z) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = Eigen::Vector3d(x, y, z);
  return X;
}

bool IsRed(const std::uint8_t* px) { return px[0] > 150 && px[1] < 80 && px[2] < 80; }

TEST(Spectator, ShowsObjectStatesAndWritesTheDeformationsItReceived) {
  TempDir dir;
  const std::string session = "spectator-test-" + std::to_string(getpid());
  dds::Participant server(kDomain, session, "server");
  auto scene_writer = dds::MakeWriter<msg::SceneState>(server, dds::topics::kSceneState);
  auto deformation_writer = dds::MakeWriter<msg::Deformation>(server, dds::topics::kDeformation);
  auto object_writer = dds::MakeWriter<msg::ObjectState>(server, dds::topics::kObjectState);

  // A ball the scene puts at A and its object state moves to B; the tail, deformed. Written
  // before the spectator joins: transient-local scene state and deformations reach it late.
  const Eigen::Vector3d p_A(-0.2, 0.0, 0.1);
  const Eigen::Vector3d p_B(-0.1, -0.1, 0.2);
  scene_writer.Write(Scene("dinosaur", 1,
                           {Object("ball", "sphere", "", At(p_A.x(), p_A.y(), p_A.z()), {1, 0, 0},
                                   {0.03, 0, 0}),
                            Object("tail", "mesh", "meshes/triceratops_tail.obj", At(0.15, 0.15, 0.05),
                                   {0.5F, 0.45F, 0.3F})},
                           session));
  // Keyframe revision 1 split in two samples, then a delta; one id beyond the 962 vertices.
  deformation_writer.Write(Deformation("tail", 1, true, {10, 20}, {0.001F, 0, 0, 0, 0.002F, 0}, session));
  deformation_writer.Write(Deformation("tail", 1, true, {30, 5000}, {0, 0, -0.003F, 0.001F, 0.001F, 0.001F}, session));
  deformation_writer.Write(Deformation("tail", 2, false, {20}, {0, 0.0025F, 0}, session));

  std::atomic<bool> stop{false};
  std::thread mover([&] {
    while (!stop) {
      object_writer.Write(State("ball", p_B, {1, 0, 0, 0}, session));
      object_writer.Write(State("moon", p_B, {1, 0, 0, 0}, session));  // not in this scene
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });

  SpectatorConfig config;
  config.where.domain_id = kDomain;
  config.where.session = session;
  config.name = "spectator-test";
  config.headless = true;
  config.frames = 30;
  config.fps = 15.0;  // 2 s: discovery and the best-effort object states have time to arrive
  config.out_dir = (dir.path() / "frames").string();
  config.deformation_out = dir.path() / "deformation.json";
  config.wait_for_scene = std::chrono::duration<double>(10.0);
  int rc = -1;
  testing::internal::CaptureStdout();
  try {
    rc = Spectator(config).Run();
  } catch (...) {
    stop = true;
    mover.join();
    throw;
  }
  const std::string out = testing::internal::GetCapturedStdout();
  stop = true;
  mover.join();
  ASSERT_EQ(rc, 0);
  EXPECT_NE(out.find("1 ids out of range"), std::string::npos) << out;

  // What the spectator received: the receiver rule's result, exactly.
  std::ifstream in(config.deformation_out);
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_TRUE(j.contains("tail")) << j.dump();
  EXPECT_EQ(j.size(), 1U) << "the ball has no mesh to deform";
  EXPECT_EQ(j["tail"]["revision"], 2);
  EXPECT_EQ(j["tail"]["vertex_count"], 962);
  const auto& u = j["tail"]["u_W_m"];
  EXPECT_EQ(u.size(), 3U) << u.dump();
  EXPECT_EQ(u["10"][0].get<float>(), 0.001F);
  EXPECT_EQ(u["20"][1].get<float>(), 0.0025F);
  EXPECT_EQ(u["30"][2].get<float>(), -0.003F);

  // The last frame shows the ball where its object state put it, not where the scene did.
  std::ifstream camera_file(dir.path() / "frames" / "camera.json");
  const nlohmann::json c = nlohmann::json::parse(camera_file);
  render::Camera camera;
  const auto vector = [&](const char* key) {
    return Eigen::Vector3d(c[key][0].get<double>(), c[key][1].get<double>(), c[key][2].get<double>());
  };
  camera.eye_W = vector("eye_W_m");
  camera.target_W = vector("target_W_m");
  camera.up_W = vector("up_W");
  camera.fov_y_rad = c["fov_y_rad"].get<double>();
  camera.width_px = c["width_px"].get<int>();
  camera.height_px = c["height_px"].get<int>();
  const render::ImageRgb8 last = render::ReadPng(dir.path() / "frames" / "frame_00029.png");
  const auto pixel = [&](const Eigen::Vector3d& p_W) {
    const auto q = render::test::OracleProject(camera, p_W);
    return last.At(static_cast<int>(q.col), static_cast<int>(q.row));
  };
  EXPECT_TRUE(IsRed(pixel(p_B))) << "the ball at its object state's pose";
  EXPECT_FALSE(IsRed(pixel(p_A))) << "nothing red left at the scene's pose";
}

}  // namespace
}  // namespace handshare::graphics
