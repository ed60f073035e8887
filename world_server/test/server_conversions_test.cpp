// The world server's conversions between DDS samples and its own types, without a participant.
#include "server_conversions.hpp"

#include <gtest/gtest.h>

#include "handshare/dds/sample_checks.hpp"

#include <limits>

namespace handshare::server {
namespace {

TEST(ServerConversions, TheSceneStateCarriesTheWorldItsRevisionAndTheSessionClock) {
  scene::Scene s;
  s.name = "solar_system";
  s.gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -1.62);
  scene::SceneObject ball;
  ball.id = "ball";
  ball.kind = scene::ObjectKind::kRigid;
  ball.shape = scene::Shape::kSphere;
  ball.p_WO_m = Eigen::Vector3d(0.1, 0.2, 0.3);
  ball.half_extent_m = Eigen::Vector3d(0.04, 0.04, 0.04);
  ball.mass_kg = 0.2;
  s.objects.push_back(ball);
  const msg::SceneState m = ToSceneState(s, "museum", 7, 1'700'000'000'000'000'000ULL, 60.0);
  EXPECT_EQ(m.session().to_string(), "museum");
  EXPECT_EQ(m.tick_Hz(), 60.0f);  // haptic nodes pace solo contact sets to it
  EXPECT_EQ(m.scene().to_string(), "solar_system");
  EXPECT_EQ(m.revision(), 7u);
  EXPECT_EQ(m.session_epoch_unix_ns(), 1'700'000'000'000'000'000ULL);
  EXPECT_EQ(m.gravity_W_m_per_s2()[2], -1.62);
  ASSERT_EQ(m.objects().size(), 1u);
  EXPECT_EQ(m.objects()[0].object_id().to_string(), "ball");
  EXPECT_EQ(m.objects()[0].kind(), msg::OBJECT_RIGID);
  EXPECT_EQ(m.objects()[0].shape().to_string(), "sphere");
  EXPECT_EQ(m.objects()[0].p_WO_m()[1], 0.2);
  EXPECT_EQ(m.objects()[0].mass_kg(), 0.2);
}

TEST(ServerConversions, AControlStateRecordBecomesASample) {
  ControlStateRecord r;
  r.control_id = "lever_planet";
  r.scene = "solar_system";
  r.index = 1;
  r.user = "alice";
  r.changes = 3;
  const msg::ControlState m = ToControlState(r, "museum");
  EXPECT_EQ(m.control_id().to_string(), "lever_planet");
  EXPECT_EQ(m.session().to_string(), "museum");
  EXPECT_EQ(m.scene().to_string(), "solar_system");
  EXPECT_EQ(m.index(), 1);
  EXPECT_FALSE(m.engaged());
  EXPECT_EQ(m.user().to_string(), "alice");
  EXPECT_EQ(m.changes(), 3u);
  EXPECT_EQ(dds::CheckControlState(m, "museum"), "");
}

TEST(ServerConversions, AControlEventBecomesAnInputAndALogRow) {
  msg::ControlEvent e;
  e.user("alice");
  e.control_id("book_dinosaur");
  e.kind(msg::CONTROL_OPENED);
  e.index(0);
  e.value(1.0);
  e.error_m(0.003);
  const auto input = ToControlInput(e);
  ASSERT_TRUE(input.has_value());
  EXPECT_EQ(input->control_id, "book_dinosaur");
  EXPECT_EQ(input->kind, controls::EventKind::kOpened);
  EXPECT_EQ(input->index, 0);
  EXPECT_EQ(input->user, "alice");
  const ControlRecord r = ToControlRecord(e, *input, 42);
  EXPECT_EQ(r.kind, controls::EventKind::kOpened);  // logged as opened, not as pressed
  EXPECT_EQ(r.unix_ns, 42u);
  ASSERT_TRUE(r.error_m.has_value());
  EXPECT_EQ(*r.error_m, 0.003);
  e.error_m(std::numeric_limits<double>::quiet_NaN());
  EXPECT_FALSE(ToControlRecord(e, *input, 42).error_m.has_value());
}

TEST(ServerConversions, AControlEventOfAnUnknownKindIsDropped) {
  msg::ControlEvent e;
  e.control_id("button");
  e.kind(static_cast<msg::ControlEventKind>(17));
  EXPECT_FALSE(ToControlInput(e).has_value());
}

TEST(ServerConversions, BoardAndDeformationSamplesCarryTheirFields) {
  const msg::MessageBoard b = ToMessageBoard({"en", "Lift the ball.", "Pull the lever.", ""}, "museum", 3);
  EXPECT_EQ(b.message_id(), 3u);
  EXPECT_EQ(b.language().to_string(), "en");
  EXPECT_EQ(b.text().to_string(), "Lift the ball.");
  EXPECT_EQ(b.next_action().to_string(), "Pull the lever.");
  const msg::MessageBoard ja = ToMessageBoard({"ja", "月", "", "つき"}, "museum", 3);
  EXPECT_EQ(ja.language().to_string(), "ja");
  EXPECT_EQ(ja.reading().to_string(), "つき");
  DeformationSample s;
  s.revision = 9;
  s.keyframe = true;
  s.surface_node_count = 100;
  s.node_ids = {4, 5};
  s.u_W_m = {0.f, 0.f, -1e-3f, 0.f, 1e-4f, 0.f};
  const msg::Deformation d = ToDeformation("tail", "museum", s);
  EXPECT_EQ(d.object_id().to_string(), "tail");
  EXPECT_EQ(d.revision(), 9u);
  EXPECT_TRUE(d.keyframe());
  EXPECT_EQ(d.surface_node_count(), 100u);
  ASSERT_EQ(d.node_ids().size(), 2u);
  EXPECT_EQ(d.node_ids()[1], 5u);
  ASSERT_EQ(d.u_W_m().size(), 6u);
  EXPECT_EQ(d.u_W_m()[2], -1e-3f);
}

TEST(ServerConversions, ABodyStateBecomesAnObjectStateSample) {
  BodyState b;
  b.object_id = "ball";
  b.owner = "alice";
  b.X_WO.translation() = Eigen::Vector3d(0.1, 0.2, 0.3);
  b.X_WO.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  b.v_WO_m_per_s = Eigen::Vector3d(0.0, 0.4, -0.5);
  const msg::ObjectState m = ToObjectState(b, "museum", 1234);
  EXPECT_EQ(m.object_id().to_string(), "ball");
  EXPECT_EQ(m.session().to_string(), "museum");
  EXPECT_EQ(m.owner().to_string(), "alice");
  EXPECT_EQ(m.stamp_ns(), 1234u);
  EXPECT_EQ(m.p_WO_m()[0], 0.1);
  EXPECT_EQ(m.p_WO_m()[2], 0.3);
  EXPECT_EQ(m.v_WO_m_per_s()[1], 0.4);
  EXPECT_EQ(m.v_WO_m_per_s()[2], -0.5);
  EXPECT_NEAR(m.q_WO_wxyz()[0], std::cos(0.25), 1e-15);
  EXPECT_NEAR(m.q_WO_wxyz()[3], std::sin(0.25), 1e-15);
  EXPECT_EQ(m.q_WO_wxyz()[1], 0.0);
  EXPECT_TRUE(dds::CheckObjectState(m, "museum").empty());
}

TEST(ServerConversions, TheRosterNamesThePresentMembersUpToTheIdlsBound) {
  std::vector<std::string> ids;
  for (int i = 0; i < 70; ++i) ids.push_back("member-" + std::to_string(i));
  const msg::SessionRoster r = ToSessionRoster(ids, "museum");
  EXPECT_EQ(r.session().to_string(), "museum");
  ASSERT_EQ(r.members().size(), kMaxRoster);
  EXPECT_EQ(r.members()[0].to_string(), "member-0");
  EXPECT_TRUE(dds::CheckSessionRoster(r, "museum").empty());
  EXPECT_EQ(ToSessionRoster({}, "museum").members().size(), 0u);
}

}  // namespace
}  // namespace handshare::server
