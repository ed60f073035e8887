#include "handshare/web_console/console_state.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace handshare::web_console {
namespace {

TEST(ConsoleState, TheDocumentCarriesEveryStationAndTheWorld) {
  using namespace std::chrono_literals;
  const auto now = std::chrono::steady_clock::now();
  ConsoleState s;
  s.session = "s1";
  s.console_name = "web-console";
  s.actions_enabled = true;
  s.world = WorldView{true, "start_menu", "Encyclopedia", 3, 60.0, -9.81, 1, {}};
  s.routes.push_back(WorldRoute{"dinosaur", "button_dinosaur", controls::EventKind::kPressed, -1});
  s.boards["en"] = BoardView{7, "Welcome", "Press a button"};
  StationStats st;
  st.node = "haptic_node/alice";
  st.user = UserOfNode(st.node);
  st.rate_Hz = 999.5;
  st.jitter_p99_us = 42.0;
  st.overruns = 2;
  st.received = now - 1500ms;
  s.stations[st.node] = st;
  const auto j = nlohmann::json::parse(ToJson(s, now));
  EXPECT_EQ(j["type"], "state");
  EXPECT_EQ(j["world"]["scene"], "start_menu");
  EXPECT_EQ(j["world"]["tick_Hz"], 60.0);
  EXPECT_EQ(j["routes"][0]["control"], "button_dinosaur");
  EXPECT_EQ(j["boards"]["en"]["message_id"], 7);
  ASSERT_EQ(j["stations"].size(), 1u);
  EXPECT_EQ(j["stations"][0]["user"], "alice");
  EXPECT_EQ(j["stations"][0]["rate_Hz"], 999.5);
  EXPECT_EQ(j["stations"][0]["overruns"], 2);
  EXPECT_NEAR(j["stations"][0]["age_s"].get<double>(), 1.5, 1e-6);
  EXPECT_TRUE(j["console"]["actions_enabled"].get<bool>());
}

TEST(ConsoleState, TextThatIsNotUtf8IsReplacedNotRefused) {
  ConsoleState s;
  s.boards["en"] = BoardView{1, std::string("bad \xff byte"), ""};
  const auto j = nlohmann::json::parse(ToJson(s, std::chrono::steady_clock::now()));
  EXPECT_EQ(j["boards"]["en"]["text"], "bad \xEF\xBF\xBD byte");
  EXPECT_TRUE(j["world"].is_null());
}

TEST(ConsoleState, TheViewGetsEveryObjectAndEveryFingertipTheDeviceHas) {
  ConsoleState s;
  s.world.known = true;
  ViewObject o;
  o.id = "button_dinosaur";
  o.shape = "mesh";
  o.mesh = "/meshes/button.glb";
  o.p_WO_m = {0.0, -0.08, 0.012};
  o.mesh_scale = {2, 2, 2};
  s.world.view.push_back(o);
  const auto j = nlohmann::json::parse(ToJson(s, std::chrono::steady_clock::now()));
  ASSERT_EQ(j["world"]["view"].size(), 1u);
  EXPECT_EQ(j["world"]["view"][0]["mesh"], "/meshes/button.glb");
  EXPECT_EQ(j["world"]["view"][0]["p_WO_m"][1], -0.08);
  EXPECT_EQ(j["world"]["view"][0]["mesh_scale"][0], 2.0);

  std::map<std::string, HandView> hands;
  hands["k"] = HandView{"alice", {1}, {{0.1, 0.2, 0.3}}, 0.008};  // a stylus: the index only
  const auto h = nlohmann::json::parse(HandsJson(hands));
  EXPECT_EQ(h["type"], "hands");
  EXPECT_EQ(h["hands"][0]["user"], "alice");
  EXPECT_EQ(h["hands"][0]["fingers"], nlohmann::json::array({1}));
  EXPECT_EQ(h["hands"][0]["p_WE_m"][0][2], 0.3);
}

}  // namespace
}  // namespace handshare::web_console
