#include "handshare/scene/scene.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace handshare::scene {
namespace {

std::filesystem::path WriteTemp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("hs_scene_test_" + name + ".json");
  std::ofstream(path) << text;
  return path;
}

std::string ErrorOf(const std::string& name, const std::string& text) {
  const auto path = WriteTemp(name, text);
  try {
    LoadScene(path);
  } catch (const SceneError& e) {
    std::filesystem::remove(path);
    return e.what();
  }
  std::filesystem::remove(path);
  return "";
}

TEST(Scene, EveryProjectSceneLoads) {
  for (const char* name : {"start_menu", "solar_system", "dinosaur", "microscopic"}) {
    const Scene s = LoadSceneByName(name, std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes");
    EXPECT_EQ(s.name, name);
    EXPECT_FALSE(s.messages.empty());
  }
}

TEST(Scene, MoonGravityAndBall) {
  const Scene s = LoadSceneByName("solar_system", std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes");
  EXPECT_DOUBLE_EQ(s.gravity_W_m_per_s2.z(), -1.62);
  const auto ball = std::find_if(s.objects.begin(), s.objects.end(), [](auto& o) { return o.id == "ball"; });
  ASSERT_NE(ball, s.objects.end());
  EXPECT_EQ(ball->shape, Shape::kSphere);
  EXPECT_DOUBLE_EQ(ball->half_extent_m.x(), 0.04);
}

TEST(Scene, MalformedJsonNamesFileAndLine) {
  const std::string err = ErrorOf("malformed", "{\n \"name\": \"x\",\n \"messages\": [,]\n}");
  EXPECT_NE(err.find("hs_scene_test_malformed.json:3"), std::string::npos) << err;
}

TEST(Scene, BadFieldsNameTheField) {
  EXPECT_NE(ErrorOf("nomsg", R"({"name": "x"})").find("'messages': missing"), std::string::npos);
  const std::string bad_kind = ErrorOf("kind", R"({"name": "x", "messages": [{"language": "en", "text": "t"}],
    "objects": [{"id": "a", "kind": "liquid", "shape": "sphere", "radius_m": 0.1, "position_m": [0,0,0]}]})");
  EXPECT_NE(bad_kind.find("objects[0].kind"), std::string::npos) << bad_kind;
  const std::string bad_radius = ErrorOf("radius", R"({"name": "x", "messages": [{"language": "en", "text": "t"}],
    "objects": [{"id": "a", "kind": "rigid", "shape": "sphere", "radius_m": -1, "position_m": [0,0,0]}]})");
  EXPECT_NE(bad_radius.find("objects[0].radius_m"), std::string::npos) << bad_radius;
  const std::string dup = ErrorOf("dup", R"({"name": "x", "messages": [{"language": "en", "text": "t"}],
    "objects": [{"id": "a", "kind": "rigid", "shape": "sphere", "radius_m": 1, "position_m": [0,0,0]},
                {"id": "a", "kind": "rigid", "shape": "sphere", "radius_m": 1, "position_m": [0,0,0]}]})");
  EXPECT_NE(dup.find("duplicate id"), std::string::npos) << dup;
}

TEST(Scene, UnknownSceneListsAvailable) {
  try {
    LoadSceneByName("atlantis", std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("solar_system"), std::string::npos);
  }
}

}  // namespace
}  // namespace handshare::scene
