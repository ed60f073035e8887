#include "handshare/web_console/console_state.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <nlohmann/json.hpp>

#include "handshare/hiro/hiro_model.hpp"

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
  st.kind = KindOfNode(st.node);
  st.deadline_misses = 3;
  st.sent_bytes_per_s = 2048.5;
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
  EXPECT_EQ(j["stations"][0]["kind"], "haptic");
  EXPECT_EQ(j["stations"][0]["deadline_misses"], 3);
  EXPECT_EQ(j["stations"][0]["sent_bytes_per_s"], 2048.5);
  EXPECT_NEAR(j["stations"][0]["age_s"].get<double>(), 1.5, 1e-6);
  EXPECT_TRUE(j["console"]["actions_enabled"].get<bool>());
}

// Screens, guides and the world server's tick are stations too: their kind comes from their program's node key.
TEST(ConsoleState, AStationsKindIsItsProgramsMemberKind) {
  EXPECT_EQ(KindOfNode("haptic_node/alice"), "haptic");
  EXPECT_EQ(KindOfNode("graphics_node/screen-1"), "graphics");
  EXPECT_EQ(KindOfNode("audio_guide/guide"), "audio_guide");
  EXPECT_EQ(KindOfNode("world_server/tick"), "world_server");  // the world server's tick
  EXPECT_EQ(KindOfNode("alice"), "");
  EXPECT_EQ(KindOfNode("x/haptic_node/alice"), "");
  EXPECT_EQ(UserOfNode("graphics_node/screen-1"), "screen-1");
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
  hands["k"] = HandView{"alice", {0.1, 0.15, 0.25}, {0.0, 0.0, 0.0, 1.0}, {1}, {{0.1, 0.2, 0.3}}, 0.008, 0, {}};  // a stylus
  const auto h = nlohmann::json::parse(HandsJson(hands));
  EXPECT_EQ(h["type"], "hands");
  EXPECT_EQ(h["hands"][0]["user"], "alice");
  EXPECT_EQ(h["hands"][0]["p_WH_m"][1], 0.15);
  EXPECT_EQ(h["hands"][0]["q_WH_wxyz"][3], 1.0);
  EXPECT_EQ(h["hands"][0]["fingers"], nlohmann::json::array({1}));
  EXPECT_EQ(h["hands"][0]["p_WE_m"][0][2], 0.3);
}

// Each hand carries its device state's stamp and the figure the screens draw (figure::DrawnHand):
// the fitted palm and links in skin, a HIRO II user's hand from its joint angles in metal, a
// stylus as a pen; its numbers within a micrometre of the figure's.
TEST(ConsoleState, TheHandsDocumentCarriesEachHandsFigureAndStamp) {
  HandView h;
  h.user = "alice";
  h.stamp_ns = 123456789012345ULL;
  h.device.p_WH_m = {0.05, -0.02, 0.12};
  h.device.q_WH_wxyz = {std::cos(0.35), 0.0, 0.0, std::sin(0.35)};
  const Eigen::Isometry3d X_WH = figure::HandBasePose(h.device.p_WH_m, h.device.q_WH_wxyz);
  const std::array<Eigen::Vector3d, figure::kFingers> tips_H = {
      Eigen::Vector3d(-0.060, 0.040, -0.010), Eigen::Vector3d(-0.036, 0.100, 0.000), Eigen::Vector3d(-0.012, 0.105, 0.000),
      Eigen::Vector3d(0.012, 0.100, 0.000), Eigen::Vector3d(0.036, 0.090, 0.000)};
  for (int f = 0; f < figure::kFingers; ++f) h.device.p_WE[f] = X_WH * tips_H[f];
  h.device.fingertip_radius_m = 0.008;
  std::map<std::string, HandView> hands{{"k", h}};
  const auto doc = nlohmann::json::parse(HandsJson(hands));
  const auto& hand = doc["hands"][0];
  EXPECT_EQ(hand["stamp_ns"], "123456789012345");  // a string: beyond JavaScript's exact integers
  const figure::HandParts parts = figure::DrawnHand(h.device, nullptr);
  const auto& fig = hand["figure"];
  EXPECT_NEAR(fig["rgb"][0].get<double>(), figure::kSkinRgb[0], 1e-6);
  ASSERT_EQ(fig["boxes"].size(), 16u);    // the palm and three links a finger
  ASSERT_EQ(fig["spheres"].size(), 15u);  // three joints a finger
  for (std::size_t i = 0; i < parts.boxes.size(); ++i) {
    const auto& b = fig["boxes"][i];
    const figure::Box& e = parts.boxes[i];
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(b[k].get<double>(), e.p_W[k], 5e-7) << i;
      EXPECT_NEAR(b[3 + k].get<double>(), e.half_extents_m[k], 5e-7) << i;
    }
    const Eigen::Quaterniond q(b[6].get<double>(), b[7].get<double>(), b[8].get<double>(), b[9].get<double>());
    EXPECT_LT(q.angularDistance(e.q_WB), 1e-5) << i;
  }
  for (std::size_t i = 0; i < parts.spheres.size(); ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(fig["spheres"][i][k].get<double>(), parts.spheres[i].p_W[k], 5e-7) << i;
    EXPECT_NEAR(fig["spheres"][i][3].get<double>(), parts.spheres[i].radius_m, 5e-7);
  }
  // The palm's box is where the fitted hand has it: X_WH times its centre in H.
  const Eigen::Vector3d palm_W = X_WH * figure::FitHandToFingertips(X_WH, h.device.p_WE).palm_center_H;
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(fig["boxes"][0][k].get<double>(), palm_W[k], 5e-7);

  // A HIRO II user's hand, with the model: drawn from its joint angles, in metal.
  const hiro::HiroModel model = hiro::HiroModel::Load(std::string(HANDSHARE_SOURCE_ASSETS) + "/devices/hiro2.json");
  hands["k"].device.hiro = true;
  const auto metal = nlohmann::json::parse(HandsJson(hands, &model))["hands"][0]["figure"];
  EXPECT_NEAR(metal["rgb"][0].get<double>(), figure::kHiroRgb[0], 1e-6);
  const figure::HandFigure robot = figure::HiroHandFigure(model, X_WH, hands["k"].device.q_hand_rad);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(metal["spheres"][3][k].get<double>(), robot.joints_W[1][0][k], 5e-7);
  // A stylus: one pen, no joints.
  hands["k"].device.absent_fingers = 0b11101;
  const auto pen = nlohmann::json::parse(HandsJson(hands, &model))["hands"][0]["figure"];
  EXPECT_EQ(pen["boxes"].size(), 1u);
  EXPECT_EQ(pen["spheres"].size(), 0u);
}

// Each body carries its object state's sender stamp.
TEST(ConsoleState, TheBodiesDocumentCarriesEachStateStamp) {
  std::map<std::string, BodyView> bodies;
  bodies["ball"] = BodyView{{0.0, 0.05, 0.09}, {1.0, 0.0, 0.0, 0.0}, "alice", 987654321ULL};
  const auto doc = nlohmann::json::parse(BodiesJson("solar_system", bodies, {}));
  EXPECT_EQ(doc["bodies"][0]["stamp_ns"], "987654321");
}

// The receiver rule of graphics_node's DeformationField: a keyframe of a new revision starts from
// zero, a delta of the same revision adds to what is there, a bad entry is skipped.
TEST(ViewField, KeyframesStartFromZeroAndDeltasUpdateVertices) {
  ViewField f(4);
  const std::vector<std::uint32_t> ids = {0, 2};
  const std::vector<float> u = {1e-3F, 0.0F, 0.0F, 0.0F, -2e-3F, 0.0F};
  ASSERT_TRUE(f.Apply(1, true, ids, u));
  EXPECT_EQ(f.u_W_m()[2][1], -2e-3F);
  const std::vector<std::uint32_t> delta_ids = {1, 7};  // 7: beyond the mesh
  const std::vector<float> delta = {0.0F, 0.0F, 5e-4F, 1.0F, 1.0F, 1.0F};
  ASSERT_TRUE(f.Apply(1, false, delta_ids, delta));
  EXPECT_EQ(f.u_W_m()[0][0], 1e-3F);  // kept: same revision, not a keyframe
  EXPECT_EQ(f.u_W_m()[1][2], 5e-4F);
  EXPECT_EQ(f.skipped(), 1u);
  const std::vector<std::uint32_t> next_ids = {3};
  const std::vector<float> next = {0.0F, 1e-4F, 0.0F};
  ASSERT_TRUE(f.Apply(2, true, next_ids, next));
  EXPECT_EQ(f.u_W_m()[0][0], 0.0F);  // a new keyframe zeroed it
  EXPECT_EQ(f.u_W_m()[3][1], 1e-4F);
  EXPECT_EQ(*f.revision(), 2u);
  const std::vector<float> short_u = {1.0F};
  EXPECT_FALSE(f.Apply(3, true, next_ids, short_u));
  EXPECT_EQ(*f.revision(), 2u);
  const std::vector<float> nan_u = {std::nanf(""), 0.0F, 0.0F};
  ASSERT_TRUE(f.Apply(2, false, next_ids, nan_u));
  EXPECT_EQ(f.u_W_m()[3][1], 1e-4F);  // the non-finite entry skipped
}

TEST(DeformationJson, ListsTheDisplacedVerticesInWholeMicrometres) {
  std::map<std::string, ViewField> fields;
  fields.emplace("tail", ViewField(3));
  fields.emplace("head", ViewField(2));  // no sample yet: not listed
  const std::vector<std::uint32_t> ids = {0, 1, 2};
  const std::vector<float> u = {0.0F, 0.0F, -3.2504e-3F, 4e-7F, 0.0F, 0.0F, 0.0F, 2.6e-6F, 0.0F};
  fields.at("tail").Apply(5, true, ids, u);
  const auto j = nlohmann::json::parse(DeformationJson("dinosaur", fields));
  EXPECT_EQ(j["type"], "deformation");
  EXPECT_EQ(j["scene"], "dinosaur");
  ASSERT_EQ(j["objects"].size(), 1u);
  const auto& o = j["objects"][0];
  EXPECT_EQ(o["id"], "tail");
  EXPECT_EQ(o["revision"], 5);
  EXPECT_EQ(o["vertex_count"], 3);
  EXPECT_EQ(o["ids"], nlohmann::json::array({0, 2}));  // vertex 1 rounds to 0 um
  EXPECT_EQ(o["u_um"], nlohmann::json::array({0, 0, -3250, 0, 3, 0}));
}

scene::ControlSpec Control(scene::ControlType type) {
  scene::ControlSpec c;
  c.id = "c";
  c.type = type;
  c.push.travel_m = 0.004;
  c.lever.min_angle_rad = 0.0;
  c.lever.max_angle_rad = 0.6;
  c.lever.detents = 3;
  return c;
}

// Drawn as graphics_node's SceneReplica::DrawnPose draws them.
TEST(DrawnControl, ALeverTurnsToItsDetentAndAPressedButtonGoesDownItsTravel) {
  const std::array<double, 3> p = {0.25, 0.1, 0.0};
  const std::array<double, 4> q_z90 = {std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)};  // 90 degrees about z
  const ControlView lever = DrawnControl(Control(scene::ControlType::kLever), {2, false, false, 0.0, "alice"}, p, q_z90, {"en"});
  EXPECT_EQ(lever.type, "lever");
  EXPECT_EQ(lever.user, "alice");
  // q_z90 * (0.6 rad about x): w = cos(0.3) sqrt(0.5), x = y = sin(0.3) sqrt(0.5), z = cos(0.3) sqrt(0.5)
  EXPECT_NEAR(lever.q_WO_wxyz[0], std::cos(0.3) * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(lever.q_WO_wxyz[1], std::sin(0.3) * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(lever.q_WO_wxyz[2], std::sin(0.3) * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(lever.q_WO_wxyz[3], std::cos(0.3) * std::sqrt(0.5), 1e-12);
  EXPECT_EQ(lever.p_WO_m, p);
  const ControlView moving = DrawnControl(Control(scene::ControlType::kLever), {0, false, true, 0.2, "bob"}, p, {1, 0, 0, 0}, {"en"});
  EXPECT_NEAR(moving.q_WO_wxyz[1], std::sin(0.1), 1e-12);  // where the hand has it, not its detent
  const std::array<double, 4> q_x180 = {0.0, 1.0, 0.0, 0.0};  // upside down: its -z is +z of W
  const ControlView button = DrawnControl(Control(scene::ControlType::kButton), {-1, true, false, 0.0, ""}, p, q_x180, {"en"});
  EXPECT_NEAR(button.p_WO_m[2], 0.004, 1e-12);
  const ControlView half = DrawnControl(Control(scene::ControlType::kArrow), {-1, false, true, 0.009, ""}, p, {1, 0, 0, 0}, {"en"});
  EXPECT_NEAR(half.p_WO_m[2], -0.004, 1e-12);  // clamped to its travel
  const ControlView rest = DrawnControl(Control(scene::ControlType::kButton), {-1, false, false, 0.0, ""}, p, {1, 0, 0, 0}, {"en"});
  EXPECT_EQ(rest.p_WO_m, p);
}

TEST(DrawnControl, AnOpenBookShowsItsPageInEachLanguage) {
  scene::ControlSpec book = Control(scene::ControlType::kBook);
  book.size_m = {0.1, 0.14, 0.02};
  book.page_content.resize(2);
  book.page_content[1].text = {{"en", "The Moon"}, {"ja", "月"}};
  book.page_content[1].image_uri = "images/moon_mars.png";
  book.page_content[1].image_path = "/somewhere/assets/images/moon_mars.png";
  const ControlView open = DrawnControl(book, {1, true, false, 0.0, "alice"}, {0, 0, 0}, {1, 0, 0, 0}, {"en", "ja"});
  EXPECT_EQ(open.type, "book");
  EXPECT_EQ(open.page_picture, "/pictures/moon_mars.png") << "its picture, where the console serves it";
  EXPECT_EQ(DrawnControl(book, {0, true, false, 0.0, "alice"}, {0, 0, 0}, {1, 0, 0, 0}, {"en"}).page_picture, "")
      << "a spread without a picture";
  EXPECT_EQ(open.page_text.at("en"), "The Moon");
  EXPECT_EQ(open.page_text.at("ja"), "月");
  EXPECT_EQ(open.size_m[1], 0.14);
  const ControlView shut = DrawnControl(book, {1, false, false, 0.0, "alice"}, {0, 0, 0}, {1, 0, 0, 0}, {"en", "ja"});
  EXPECT_TRUE(shut.page_text.empty());
  EXPECT_EQ(shut.page_picture, "");
  const auto j = nlohmann::json::parse(BodiesJson("start_menu", {{"ball", BodyView{{0, 0.05, 0.1}, {1, 0, 0, 0}, "alice"}}},
                                                  {open}));
  EXPECT_EQ(j["type"], "bodies");
  EXPECT_EQ(j["bodies"][0]["id"], "ball");
  EXPECT_EQ(j["bodies"][0]["owner"], "alice");
  EXPECT_EQ(j["bodies"][0]["p_WO_m"][2], 0.1);
  EXPECT_EQ(j["controls"][0]["page_text"]["ja"], "月");
  EXPECT_EQ(j["controls"][0]["page_picture"], "/pictures/moon_mars.png");
  EXPECT_EQ(j["controls"][0]["engaged"], true);
}

}  // namespace
}  // namespace handshare::web_console
