// Samples survive Serialize -> Deserialize unchanged (generated operator==), and a payload that
// is cut short or padded says where it went wrong.
#include "handshare/dds/serialization.hpp"

#include <gtest/gtest.h>

namespace handshare::dds {
namespace {

msg::Deformation SomeDeformation() {
  msg::Deformation d;
  d.object_id("tail");
  d.session("museum");
  d.revision(7);
  d.keyframe(true);
  d.surface_node_count(100);
  d.node_ids({1, 5, 99});
  d.u_W_m({0.001f, 0.0f, -0.002f, 0.0f, 0.0f, 0.0f, 0.0005f, 0.0f, 0.0f});
  return d;
}

msg::SceneState SomeScene() {
  msg::SceneState s;
  s.session("museum");
  s.scene("solar_system");
  s.revision(3);
  s.gravity_W_m_per_s2({0.0, 0.0, -1.62});
  msg::SceneObject o;
  o.object_id("moon");
  o.kind(msg::OBJECT_RIGID);
  o.shape("mesh");
  o.mesh_uri("meshes/moon.obj");
  o.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  s.objects().push_back(o);
  s.session_epoch_unix_ns(1700000000123456789ULL);
  return s;
}

TEST(Serialization, RoundTripsEveryKindOfField) {
  const auto d = SomeDeformation();
  const auto bytes = Serialize(d);
  msg::Deformation back;
  Deserialize(bytes, back);
  EXPECT_EQ(back, d);

  const auto s = SomeScene();
  msg::SceneState scene_back;
  Deserialize(Serialize(s), scene_back);
  EXPECT_EQ(scene_back, s);

  msg::DeviceState dev;
  dev.user("alice");
  dev.stamp_ns(123456789);
  dev.p_WE_m()[4] = {0.1, 0.2, 0.3};
  dev.fault(true);
  msg::DeviceState dev_back;
  Deserialize(Serialize(dev), dev_back);
  EXPECT_EQ(dev_back, dev);

  msg::ControlEvent e;
  e.control_id("arrow_next");
  e.kind(msg::CONTROL_PAGE_TURNED);
  e.error_m(0.004);
  msg::ControlEvent e_back;
  Deserialize(Serialize(e), e_back);
  EXPECT_EQ(e_back, e);
}

TEST(Serialization, ATruncatedPayloadSaysWhere) {
  const auto bytes = Serialize(SomeDeformation());
  const std::span<const std::uint8_t> cut(bytes.data(), bytes.size() - 8);
  msg::Deformation back;
  try {
    Deserialize(cut, back);
    FAIL() << "a cut payload deserialized";
  } catch (const SerializationError& e) {
    EXPECT_LE(e.offset(), cut.size());
    EXPECT_NE(std::string(e.what()).find("of " + std::to_string(cut.size()) + " bytes"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("handshare::msg::Deformation"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Deserialize(std::span<const std::uint8_t>(bytes.data(), 2), back), SerializationError);
}

TEST(Serialization, ABadHeaderOrLeftOverBytesAreRefused) {
  auto bytes = Serialize(SomeScene());
  msg::SceneState back;
  auto bad_header = bytes;
  bad_header[1] = 7;
  EXPECT_THROW(Deserialize(bad_header, back), SerializationError);
  bytes.resize(bytes.size() + 16, 0);
  try {
    Deserialize(bytes, back);
    FAIL() << "left-over bytes were accepted";
  } catch (const SerializationError& e) {
    EXPECT_NE(std::string(e.what()).find("left over"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace handshare::dds
