#include "handshare/scene/scene.hpp"

#include <gtest/gtest.h>

#include "handshare/common/utf8.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>

namespace handshare::scene {
namespace {

const std::filesystem::path kScenes = std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes";

// Test files live in a temporary assets tree (scenes/ beside meshes/) so that relative mesh
// paths and goto targets resolve like in the project's own assets folder.
std::filesystem::path TempAssets() {
  const auto root = std::filesystem::temp_directory_path() / "hs_scene_test_assets";
  std::filesystem::create_directories(root / "scenes");
  std::filesystem::create_directories(root / "meshes");
  std::ofstream(root / "scenes" / "start_menu.json") << R"({"name": "start_menu", "messages": [{"language": "en", "text": "t"}]})";
  return root;
}

std::filesystem::path WriteTemp(const std::string& name, const std::string& text) {
  const auto path = TempAssets() / "scenes" / ("hs_scene_test_" + name + ".json");
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

const ControlSpec* FindControl(const Scene& s, const std::string& id) {
  const auto it = std::find_if(s.controls.begin(), s.controls.end(), [&](auto& c) { return c.id == id; });
  return it == s.controls.end() ? nullptr : &*it;
}

const SceneObject* FindObject(const Scene& s, const std::string& id) {
  const auto it = std::find_if(s.objects.begin(), s.objects.end(), [&](auto& o) { return o.id == id; });
  return it == s.objects.end() ? nullptr : &*it;
}

bool HasBothLanguages(const std::vector<Message>& messages) {
  auto has = [&](const char* lang) {
    return std::any_of(messages.begin(), messages.end(), [&](const Message& m) { return m.language == lang; });
  };
  return has("en") && has("ja");
}

// The project's scenes, every file of assets/scenes.
const std::vector<std::string> kProjectScenes = {"commons",           "dinosaur",          "microscopic",
                                                 "microscopic_belly", "microscopic_horn",  "solar_system",
                                                 "start_menu"};

TEST(Scene, SceneNamesListsTheFolder) {
  EXPECT_EQ(SceneNames(kScenes), kProjectScenes);
  EXPECT_TRUE(SceneNames(kScenes / "no_such_folder").empty());
  const std::string err = [] {
    try {
      (void)LoadSceneByName("atlantis", kScenes);
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  }();
  EXPECT_NE(err.find("available: commons dinosaur microscopic microscopic_belly"), std::string::npos) << err;
}

TEST(Scene, EveryProjectSceneLoadsWithMeshesAndBothLanguages) {
  const auto start = std::chrono::steady_clock::now();
  for (const std::string& name : kProjectScenes) {
    const Scene s = LoadSceneByName(name, kScenes);
    EXPECT_EQ(s.name, name);
    EXPECT_TRUE(HasBothLanguages(s.messages)) << name;
    for (const auto& o : s.objects) {
      if (o.shape == Shape::kMesh) {
        ASSERT_NE(o.mesh, nullptr) << name << ": " << o.id;
        EXPECT_TRUE(CheckMesh(*o.mesh).closed_and_outward()) << name << ": " << o.id;
      }
    }
    for (const auto& c : s.controls) {
      for (const Action* a : {&c.action}) {
        if (!a->messages.empty()) {
          EXPECT_TRUE(HasBothLanguages(a->messages)) << c.id;
        }
      }
      for (const auto& a : c.detent_actions) {
        if (!a.messages.empty()) {
          EXPECT_TRUE(HasBothLanguages(a.messages)) << c.id;
        }
      }
      for (const auto& a : c.page_actions) {
        if (!a.messages.empty()) {
          EXPECT_TRUE(HasBothLanguages(a.messages)) << c.id;
        }
      }
      for (std::size_t i = 0; i < c.page_content.size(); ++i) {
        const BookPage& page = c.page_content[i];
        EXPECT_EQ(page.text.size(), 2U) << c.id << " page " << i << ": English and Japanese";
        EXPECT_NE(page.TextIn("ja"), page.TextIn("en")) << c.id << " page " << i;
      }
      // Every control is also an object (its visual) for the nodes that only draw objects.
      const SceneObject* visual = FindObject(s, c.id);
      ASSERT_NE(visual, nullptr) << c.id;
      EXPECT_EQ(visual->kind, ObjectKind::kControl);
    }
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  RecordProperty("load_all_scenes_ms", std::to_string(ms));
}

TEST(Scene, MoonGravityBallAndLeverToMars) {
  const Scene s = LoadSceneByName("solar_system", kScenes);
  EXPECT_DOUBLE_EQ(s.gravity_W_m_per_s2.z(), -1.62);
  const SceneObject* ball = FindObject(s, "ball");
  ASSERT_NE(ball, nullptr);
  EXPECT_EQ(ball->shape, Shape::kSphere);
  EXPECT_DOUBLE_EQ(ball->half_extent_m.x(), 0.04);
  EXPECT_DOUBLE_EQ(ball->mass_kg, 0.2);
  EXPECT_GT(ball->rigid.mu_static, ball->rigid.mu_kinetic);
  ASSERT_NE(FindObject(s, "weight"), nullptr);
  const ControlSpec* lever = FindControl(s, "lever_planet");
  ASSERT_NE(lever, nullptr);
  EXPECT_EQ(lever->type, ControlType::kLever);
  ASSERT_EQ(lever->detent_actions.size(), 2u);
  EXPECT_TRUE(lever->detent_actions[1].set_gravity);
  EXPECT_DOUBLE_EQ(lever->detent_actions[1].gravity_W_m_per_s2.z(), -3.71);
  EXPECT_DOUBLE_EQ(lever->detent_actions[0].gravity_W_m_per_s2.z(), -1.62);
  EXPECT_NE(lever->detent_actions[1].title.find("Mars"), std::string::npos);
}

TEST(Scene, EveryWorldLeadsBackToTheStartAndTheStartToEveryWorld) {
  auto targets = [](const Scene& s) {
    std::vector<std::string> out;
    for (const auto& c : s.controls) {
      if (!c.action.goto_scene.empty()) out.push_back(c.action.goto_scene);
    }
    return out;
  };
  const auto from_start = targets(LoadSceneByName("start_menu", kScenes));
  for (const char* world : {"solar_system", "dinosaur", "microscopic"}) {
    EXPECT_NE(std::find(from_start.begin(), from_start.end(), world), from_start.end()) << world;
    const auto back = targets(LoadSceneByName(world, kScenes));
    EXPECT_NE(std::find(back.begin(), back.end(), "start_menu"), back.end()) << world;
  }
}

TEST(Scene, DinosaurPartsDentSeveralMillimetresAtThreeNewtons) {
  const Scene s = LoadSceneByName("dinosaur", kScenes);
  int parts = 0;
  for (const char* id : {"triceratops_head", "triceratops_tail", "triceratops_leg"}) {
    const SceneObject* o = FindObject(s, id);
    ASSERT_NE(o, nullptr) << id;
    EXPECT_EQ(o->kind, ObjectKind::kDeformable);
    EXPECT_NE(o->fixed.kind, FixedRule::Kind::kNone);
    // Fingertip radius 8 mm, 3 N: "several mm" taken as 2..10 mm.
    const double dent_m = FlatPunchDepth_m(3.0, 0.008, o->deformable.E_Pa, o->deformable.nu);
    EXPECT_GT(dent_m, 0.002) << id;
    EXPECT_LT(dent_m, 0.010) << id;
    // Scaled to the hand: largest size 8..21 cm.
    const double size_m = 2.0 * o->half_extent_m.maxCoeff();
    EXPECT_GT(size_m, 0.08) << id;
    EXPECT_LT(size_m, 0.21) << id;
    ++parts;
  }
  EXPECT_EQ(parts, 3);
}

TEST(Scene, FlatPunchMatchesTheHandWorkedValue) {
  // 3 N * (1 - 0.45^2) / (2 * 0.008 m * 30 kPa) = 4.984 mm (as written in dinosaur.json).
  EXPECT_NEAR(FlatPunchDepth_m(3.0, 0.008, 30000.0, 0.45), 0.0049844, 1e-6);
}

TEST(Scene, TheDaphniaBeats) {
  // Its body flexes (the head nods, the back held) and its spine sways (the band by the root
  // turns): a deformation, not only the rigid bob.
  for (const auto& [world, id] : {std::pair{"microscopic_belly", "daphnia_belly"}, std::pair{"microscopic_horn", "daphnia_horn"}}) {
    const Scene s = LoadSceneByName(world, kScenes);
    ASSERT_NE(FindObject(s, id), nullptr) << world;
    const SceneObject& o = *FindObject(s, id);
    ASSERT_TRUE(o.beat.active()) << world;
    // No rigid bob on top: a touched body's contact points travel in the world frame, and a
    // receiver that maps them with its own pose of a moving body puts them elsewhere.
    EXPECT_FALSE(o.motion.active()) << world;
    EXPECT_NEAR(o.beat.Scale(0.25 * o.beat.period_s), 1.0, 1e-12) << world;
    EXPECT_NEAR(o.beat.Scale(o.beat.period_s), 0.0, 1e-12) << world;
    ASSERT_NE(o.mesh, nullptr);
    std::size_t driven = 0, fixed = 0;
    double largest = 0.0;
    for (const auto& v : o.mesh->vertices_m) {
      if (o.fixed.FixesPoint(v)) {
        ++fixed;
      } else if (o.beat.driven.FixesPoint(v)) {
        ++driven;
        largest = std::max(largest, o.beat.DrivenDisplacement_O(v).norm());
      }
    }
    // Tenths of a millimetre (the spine's turning band) to millimetres (the head): a beat to
    // see and feel, far from tearing the mesh.
    EXPECT_GT(largest, 2e-4) << world;
    EXPECT_LT(largest, 6e-3) << world;
    EXPECT_GT(driven, 10u) << world;
    EXPECT_GT(fixed, 10u) << world;
    EXPECT_LT(driven + fixed, o.mesh->vertices_m.size() / 4) << world;
  }
  // A rotation turns about its centre: u = rotation x (p - center).
  Beat b;
  b.rotation_O_rad = Eigen::Vector3d(0, 0, 0.1);
  b.center_O_m = Eigen::Vector3d(1, 0, 0);
  EXPECT_TRUE(b.DrivenDisplacement_O(Eigen::Vector3d(2, 0, 0)).isApprox(Eigen::Vector3d(0, 0.1, 0)));
  EXPECT_NEAR(b.DrivenDisplacement_O(Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-15);
  EXPECT_EQ(b.Scale(1.0), 0.0);  // no period: not active
}

TEST(Scene, BadBeatsNameTheField) {
  const std::string head = R"({"name": "x", "messages": [{"language": "en", "text": "t"}], "objects": [)";
  const std::string box = R"({"id": "a", "kind": "deformable", "shape": "box", "half_extent_m": [0.05, 0.05, 0.05],
    "position_m": [0,0,0], "material": {"E_Pa": 1e4, "nu": 0.3}, "fixed": {"below_m": -0.04}, )";
  const std::string rigid = ErrorOf("beat_rigid", head + R"({"id": "a", "kind": "rigid", "shape": "sphere",
    "radius_m": 0.1, "position_m": [0,0,0], "beat": {"driven": {"nodes": [1]}, "displacement_m": [0, 0, 0.001],
    "period_s": 1}}]})");
  EXPECT_NE(rigid.find("'objects[0].beat': only deformable objects beat"), std::string::npos) << rigid;
  const std::string still = ErrorOf("beat_still", head + box + R"("beat": {"driven": {"nodes": [1]},
    "period_s": 1}}]})");
  EXPECT_NE(still.find("'objects[0].beat': needs a non-zero displacement_m or rotation_rad"), std::string::npos) << still;
  const std::string both = ErrorOf("beat_both", head + box + R"("beat": {"driven": {"nodes": [1],
    "plane_normal": [0, 0, 1]}, "displacement_m": [0, 0, 0.001], "period_s": 1}}]})");
  EXPECT_NE(both.find("'objects[0].beat.driven': give exactly one of"), std::string::npos) << both;
  const std::string period = ErrorOf("beat_period", head + box + R"("beat": {"driven": {"nodes": [1]},
    "displacement_m": [0, 0, 0.001], "period_s": 0}}]})");
  EXPECT_NE(period.find("objects[0].beat.period_s"), std::string::npos) << period;
  const std::string typo = ErrorOf("beat_typo", head + box + R"("beat": {"driven": {"nodes": [1]},
    "displacment_m": [0, 0, 0.001], "period_s": 1}}]})");
  EXPECT_NE(typo.find("displacment_m"), std::string::npos) << typo;
}

TEST(Scene, FixedRulesSelectTheIntendedNodes) {
  const Scene s = LoadSceneByName("dinosaur", kScenes);
  const SceneObject* tail = FindObject(s, "triceratops_tail");
  ASSERT_NE(tail, nullptr);
  ASSERT_NE(tail->mesh, nullptr);
  std::size_t fixed = 0;
  for (const auto& v : tail->mesh->vertices_m) fixed += tail->fixed.FixesPoint(v) ? 1 : 0;
  // The flat base cap and the first ring, not the tail.
  EXPECT_GT(fixed, 10u);
  EXPECT_LT(fixed, tail->mesh->vertices_m.size() / 10);
  EXPECT_TRUE(tail->fixed.FixesPoint(Eigen::Vector3d(0.0, 0.0, 0.0)));
  EXPECT_FALSE(tail->fixed.FixesPoint(Eigen::Vector3d(-0.1, 0.0, 0.0)));
}

TEST(Scene, MalformedJsonNamesFileAndLine) {
  const std::string err = ErrorOf("malformed", "{\n \"name\": \"x\",\n \"messages\": [,]\n}");
  EXPECT_NE(err.find("hs_scene_test_malformed.json:3"), std::string::npos) << err;
}

// Replaces the first `from` in `text` by `to`.
std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

const char* kMsg = R"("messages": [{"language": "en", "text": "t"}])";

TEST(Scene, BadFieldsNameTheField) {
  EXPECT_NE(ErrorOf("nomsg", R"({"name": "x"})").find("'messages': missing"), std::string::npos);
  const std::string bad_kind = ErrorOf("kind", std::string(R"({"name": "x", )") + kMsg + R"(,
    "objects": [{"id": "a", "kind": "liquid", "shape": "sphere", "radius_m": 0.1, "position_m": [0,0,0]}]})");
  EXPECT_NE(bad_kind.find("objects[0].kind"), std::string::npos) << bad_kind;
  const std::string bad_radius = ErrorOf("radius", std::string(R"({"name": "x", )") + kMsg + R"(,
    "objects": [{"id": "a", "kind": "rigid", "shape": "sphere", "radius_m": -1, "position_m": [0,0,0]}]})");
  EXPECT_NE(bad_radius.find("objects[0].radius_m"), std::string::npos) << bad_radius;
  const std::string dup = ErrorOf("dup", std::string(R"({"name": "x", )") + kMsg + R"(,
    "objects": [{"id": "a", "kind": "rigid", "shape": "sphere", "radius_m": 1, "position_m": [0,0,0]},
                {"id": "a", "kind": "rigid", "shape": "sphere", "radius_m": 1, "position_m": [0,0,0]}]})");
  EXPECT_NE(dup.find("duplicate id"), std::string::npos) << dup;
}

// The error names file, line and field for a field deep in the file.
TEST(Scene, ErrorsNameTheLineOfTheField) {
  const std::string text =
      "{\n"                                                    // 1
      "  \"name\": \"x\",\n"                                   // 2
      "  \"messages\": [{\"language\": \"en\", \"text\": \"t\"}],\n"  // 3
      "  \"objects\": [\n"                                     // 4
      "    {\"id\": \"ok\", \"kind\": \"rigid\", \"shape\": \"box\",\n"  // 5
      "     \"half_extent_m\": [0.1, 0.1, 0.1], \"position_m\": [0, 0, 0]},\n"  // 6
      "    {\"id\": \"soft\", \"kind\": \"deformable\", \"shape\": \"sphere\",\n"  // 7
      "     \"radius_m\": 0.05, \"position_m\": [0, 0, 0.1],\n"  // 8
      "     \"material\": {\n"                                  // 9
      "        \"nu\": 0.45,\n"                                 // 10
      "        \"E_Pa\":\n"                                     // 11
      "           -3},\n"                                       // 12
      "     \"fixed\": {\"below_m\": 0.0}}\n"                   // 13
      "  ]\n"
      "}\n";
  const std::string err = ErrorOf("line", text);
  EXPECT_NE(err.find("hs_scene_test_line.json:11: field 'objects[1].material.E_Pa'"), std::string::npos) << err;

  // A missing field is reported at the object that lacks it.
  const std::string missing = Replace(Replace(text, "\"fixed\": {\"below_m\": 0.0}", "\"mass_kg\": 1.0"), "-3", "3000");
  const std::string err2 = ErrorOf("missing", missing);
  EXPECT_NE(err2.find("hs_scene_test_missing.json:7: field 'objects[1].fixed': missing"), std::string::npos) << err2;

  // A typo is not silently ignored.
  const std::string typo = Replace(text, "\"nu\"", "\"nuu\"");
  const std::string err3 = ErrorOf("typo", typo);
  EXPECT_NE(err3.find(":10: field 'objects[1].material.nuu': unknown field"), std::string::npos) << err3;

  // Duplicate keys (which plain JSON parsers silently merge) are errors, with their line.
  const std::string dup = Replace(text, "\"nu\": 0.45,", "\"nu\": 0.45, \"nu\": 0.3,");
  const std::string err4 = ErrorOf("dupkey", dup);
  EXPECT_NE(err4.find(":10: field 'objects[1].material.nu': duplicate key"), std::string::npos) << err4;

  // Values on the line after a number are attributed to the number's line, not the next one.
  const std::string number_eol = Replace(text, "[0, 0, 0.1]", "[0, 0,\n 1000\n]");
  const std::string err5 = ErrorOf("eol", number_eol);
  EXPECT_NE(err5.find(":9: field 'objects[1].position_m[2]'"), std::string::npos) << err5;
}

// Every Japanese message carries the reading the audio guide speaks: the ja voice cannot read kanji.
TEST(Scene, JapaneseMessagesCarryAKanaReading) {
  std::size_t readings = 0;
  for (const std::string& name : kProjectScenes) {
    const Scene s = LoadSceneByName(name, kScenes);
    for (const Message& m : AllMessages(s)) {
      if (m.language == "en") {
        EXPECT_TRUE(m.reading.empty()) << name;
        continue;
      }
      ++readings;
      EXPECT_FALSE(m.reading.empty()) << name << ": " << m.text;
      EXPECT_FALSE(common::FirstOutsideKanaReading(m.reading).has_value()) << name << ": " << m.reading;
    }
  }
  EXPECT_EQ(readings, 12U);  // the twelve Japanese messages of the project's scenes

  const std::string head = R"({"name": "x", "messages": [{"language": "en", "text": "t"},
    {"language": "ja", "text": "月", )";
  const std::string none = ErrorOf("noreading", head + R"("next_action": "x"}]})");
  EXPECT_NE(none.find(":2: field 'messages[1].reading': missing"), std::string::npos) << none;
  const std::string kanji = ErrorOf("kanji", head + R"("reading": "つき 月"}]})");
  EXPECT_NE(kanji.find("field 'messages[1].reading': byte 7 is not kana"), std::string::npos) << kanji;
  const std::string english = ErrorOf("enreading", R"({"name": "x", "messages": [
    {"language": "en", "text": "t", "reading": "tee"}]})");
  EXPECT_NE(english.find("field 'messages[0].reading': only a ja message has a reading"), std::string::npos) << english;
}

TEST(Scene, ControlErrorsNameTheField) {
  const std::string head = std::string(R"({"name": "x", )") + kMsg + R"(, "controls": [)";
  const std::string bad_goto = ErrorOf("goto", head + R"({"id": "b", "type": "button", "position_m": [0,0,0],
    "action": {"goto": "atlantis"}}]})");
  EXPECT_NE(bad_goto.find("controls[0].action.goto': no scene 'atlantis'"), std::string::npos) << bad_goto;
  const std::string bad_type = ErrorOf("ctype", head + R"({"id": "b", "type": "joystick", "position_m": [0,0,0]}]})");
  EXPECT_NE(bad_type.find("controls[0].type"), std::string::npos) << bad_type;
  const std::string wrong_param = ErrorOf("cparam", head + R"({"id": "b", "type": "button", "position_m": [0,0,0],
    "detents": 3}]})");
  EXPECT_NE(wrong_param.find("controls[0].detents': unknown field for a button"), std::string::npos) << wrong_param;
  const std::string detents = ErrorOf("cdetents", head + R"({"id": "l", "type": "lever", "position_m": [0,0,0],
    "detents": 3, "detent_actions": [{"goto": "start_menu"}]}]})");
  EXPECT_NE(detents.find("controls[0].detent_actions': has 1 entries for 3 detents"), std::string::npos) << detents;
  const std::string click = ErrorOf("cclick", head + R"({"id": "b", "type": "button", "position_m": [0,0,0],
    "travel_m": 0.002, "click_at_m": 0.003}]})");
  EXPECT_NE(click.find("controls[0].click_at_m': beyond travel_m"), std::string::npos) << click;
  const std::string ok = ErrorOf("cok", head + R"({"id": "b", "type": "book", "position_m": [0,0,0],
    "pages": 3, "action": {"goto": "start_menu"}}]})");
  EXPECT_EQ(ok, "");
}

// The start menu's books: opening one shows its first page (its messages, no other world);
// the second page goes to the book's world. Every page has a picture and text in both languages.
TEST(Scene, TheStartMenuBooksHavePagesThatLeadToTheirWorlds) {
  const Scene s = LoadSceneByName("start_menu", kScenes);
  int books = 0;
  for (const char* world : {"solar_system", "dinosaur", "microscopic"}) {
    const ControlSpec* book = FindControl(s, std::string("book_") + world);
    ASSERT_NE(book, nullptr) << world;
    ++books;
    EXPECT_EQ(book->type, ControlType::kBook);
    EXPECT_TRUE(book->action.empty()) << world << ": opening shows page 1, it goes nowhere";
    ASSERT_EQ(book->page_content.size(), 2U) << world;
    EXPECT_EQ(book->book.pages, 2) << world;
    ASSERT_EQ(book->page_actions.size(), 2U) << world;
    EXPECT_TRUE(book->page_actions[0].goto_scene.empty()) << world;
    EXPECT_TRUE(HasBothLanguages(book->page_actions[0].messages)) << world << ": page 1 speaks";
    EXPECT_EQ(book->page_actions[1].goto_scene, world);
    for (const BookPage& page : book->page_content) {
      EXPECT_TRUE(std::filesystem::is_regular_file(page.image_path)) << page.image_path;
      EXPECT_EQ(page.image_path.extension(), ".png");
      EXPECT_FALSE(page.TextIn("en").empty()) << world;
      EXPECT_EQ(page.TextIn("fr"), page.TextIn("en")) << "a language the page lacks reads English";
    }
  }
  EXPECT_EQ(books, 3);
}

TEST(Scene, BookPageErrorsNameTheField) {
  const auto root = TempAssets();
  std::filesystem::create_directories(root / "images");
  std::ofstream(root / "images" / "p.png") << "not checked here: graphics nodes read it";
  std::ofstream(root / "images" / "p.jpg") << "x";
  const std::string head = std::string(R"({"name": "x", )") + kMsg +
                           R"(, "controls": [{"id": "b", "type": "book", "position_m": [0,0,0], "pages": )";
  const auto error = [&](const std::string& name, const std::string& pages, const std::string& more = "") {
    return ErrorOf(name, head + pages + more + "}]}");
  };
  EXPECT_EQ(error("bp_ok", R"([{"text": [{"language": "en", "text": "a"}, {"language": "ja", "text": "あ"}],
    "image": "images/p.png"}, {"action": {"goto": "start_menu"}}])"), "");
  const std::string empty = error("bp_empty", "[]");
  EXPECT_NE(empty.find("'controls[0].pages': a book needs at least one page"), std::string::npos) << empty;
  const std::string both = error("bp_both", R"([{"image": "images/p.png"}])", R"(, "page_actions": [{"title": "t"}])");
  EXPECT_NE(both.find("'controls[0].page_actions': give each page's action in pages[i].action"), std::string::npos) << both;
  const std::string blank = error("bp_blank", R"([{"note": "nothing"}])");
  EXPECT_NE(blank.find("'controls[0].pages[0]': a page needs text, an image or an action"), std::string::npos) << blank;
  const std::string jpg = error("bp_jpg", R"([{"image": "images/p.jpg"}])");
  EXPECT_NE(jpg.find("'controls[0].pages[0].image': 'images/p.jpg' is not a PNG file"), std::string::npos) << jpg;
  const std::string missing = error("bp_missing", R"([{"image": "images/none.png"}])");
  EXPECT_NE(missing.find("'controls[0].pages[0].image': image file"), std::string::npos) << missing;
  EXPECT_NE(missing.find("none.png' does not exist"), std::string::npos) << missing;
  const std::string twice = error("bp_twice", R"([{"text": [{"language": "en", "text": "a"}, {"language": "en", "text": "b"}]}])");
  EXPECT_NE(twice.find("'controls[0].pages[0].text[1].language': a second 'en' text"), std::string::npos) << twice;
  const std::string lang = error("bp_lang", R"([{"text": [{"language": "fr", "text": "a"}]}])");
  EXPECT_NE(lang.find("'controls[0].pages[0].text[0].language': 'fr' is not en or ja"), std::string::npos) << lang;
  const std::string typo = error("bp_typo", R"([{"texts": []}])");
  EXPECT_NE(typo.find("'controls[0].pages[0].texts': unknown field"), std::string::npos) << typo;
  const std::string goto_ = error("bp_goto", R"([{"action": {"goto": "atlantis"}}])");
  EXPECT_NE(goto_.find("'controls[0].pages[0].action.goto': no scene 'atlantis'"), std::string::npos) << goto_;
  const std::string many = error("bp_actions", "2", R"(, "page_actions": [{"title": "a"}, {"title": "b"}, {"title": "c"}])");
  EXPECT_NE(many.find("'controls[0].page_actions': more than 2 entries"), std::string::npos) << many;
}

// Every object a visitor touches and every control of the encyclopedia is named on screen, in
// English and Japanese; the floors are not.
TEST(Scene, ObjectsAndControlsHaveLabelsInBothLanguages) {
  int labelled = 0;
  for (const std::string& name : kProjectScenes) {
    const Scene s = LoadSceneByName(name, kScenes);
    for (const SceneObject& o : s.objects) {
      if (o.id == "ground" || o.id == "table") {
        EXPECT_TRUE(o.label.empty()) << name << ": " << o.id;
        continue;
      }
      ASSERT_EQ(o.label.size(), 2U) << name << ": " << o.id;
      EXPECT_NE(TextIn(o.label, "en"), TextIn(o.label, "ja")) << name << ": " << o.id;
      ++labelled;
    }
  }
  // commons 5, dinosaur 5, microscopic 5, its belly 3 and horn 3, solar system 5, start menu 6
  EXPECT_EQ(labelled, 5 + 5 + 5 + 3 + 3 + 5 + 6);
  const std::string head = std::string(R"({"name": "x", )") + kMsg + R"(, "objects": [{"id": "b", "kind": "rigid",
    "shape": "sphere", "radius_m": 0.01, "position_m": [0,0,0], "label": )";
  const std::string lang = ErrorOf("label_lang", head + R"([{"language": "de", "text": "Ball"}]}]})");
  EXPECT_NE(lang.find("'objects[0].label[0].language': 'de' is not en or ja"), std::string::npos) << lang;
  const std::string empty = ErrorOf("label_empty", head + R"([{"language": "en", "text": ""}]}]})");
  EXPECT_NE(empty.find("'objects[0].label[0].text': must have 1..127 bytes"), std::string::npos) << empty;
  const std::string longer = ErrorOf("label_long", head + R"([{"language": "en", "text": ")" + std::string(128, 'x') + R"("}]}]})");
  EXPECT_NE(longer.find("'objects[0].label[0].text': longer than 127 bytes"), std::string::npos) << longer;
  const std::string control = ErrorOf("label_control", std::string(R"({"name": "x", )") + kMsg +
      R"(, "controls": [{"id": "b", "type": "button", "position_m": [0,0,0], "label": "Go"}]})");
  EXPECT_NE(control.find("'controls[0].label': expected an array, got string"), std::string::npos) << control;
}

TEST(Scene, AppearanceIsReadAndCheckedAndDefaultsToMattAndOpaque) {
  const Scene micro = LoadSceneByName("microscopic_belly", kScenes);
  const SceneObject* belly = FindObject(micro, "daphnia_belly");
  ASSERT_NE(belly, nullptr);
  EXPECT_DOUBLE_EQ(belly->appearance.opacity, 0.75);
  EXPECT_DOUBLE_EQ(belly->appearance.specular, 0.5);
  const Scene solar = LoadSceneByName("solar_system", kScenes);
  const SceneObject* ground = FindObject(solar, "ground");
  ASSERT_NE(ground, nullptr);
  EXPECT_DOUBLE_EQ(ground->appearance.opacity, 1.0);
  EXPECT_DOUBLE_EQ(ground->appearance.specular, 0.0);
  const std::string head = std::string(R"({"name": "x", )") + kMsg + R"(, "objects": [{"id": "b", "kind": "rigid",
    "shape": "sphere", "radius_m": 0.01, "position_m": [0,0,0], "appearance": )";
  const std::string clear = ErrorOf("look_opacity", head + R"({"opacity": 0.0}}]})");
  EXPECT_NE(clear.find("'objects[0].appearance.opacity': value 0 outside [0.05, 1]"), std::string::npos) << clear;
  const std::string typo = ErrorOf("look_typo", head + R"({"shine": 1}}]})");
  EXPECT_NE(typo.find("'objects[0].appearance.shine': unknown field"), std::string::npos) << typo;
}

TEST(Scene, ObjectsAndControlsFitTheSceneStateMessage) {
  // 60 objects + 5 controls > 64 entries of the scene-state message.
  std::string text = std::string(R"({"name": "x", )") + kMsg + R"(, "objects": [)";
  for (int i = 0; i < 60; ++i) {
    text += (i ? "," : "") + std::string(R"({"id": "o)") + std::to_string(i) +
            R"(", "kind": "rigid", "shape": "sphere", "radius_m": 0.01, "position_m": [0,0,0]})";
  }
  text += R"(], "controls": [)";
  for (int i = 0; i < 5; ++i) {
    text += (i ? "," : "") + std::string(R"({"id": "b)") + std::to_string(i) +
            R"(", "type": "button", "position_m": [0,0,0]})";
  }
  text += "]}";
  const std::string err = ErrorOf("many", text);
  EXPECT_NE(err.find("field 'controls': 65 objects and controls together; at most 64"), std::string::npos) << err;
}

TEST(Scene, BadMeshNamesSceneFieldAndMeshPath) {
  const auto root = TempAssets();
  std::ofstream(root / "meshes" / "empty.obj").close();
  std::ofstream(root / "meshes" / "garbage.ply") << "this is not a ply file\n\x01\x02\x03";
  std::ofstream(root / "meshes" / "points.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  auto scene_with_mesh = [&](const std::string& mesh) {
    return std::string(R"({"name": "x", )") + kMsg + R"(,
    "objects": [{"id": "m", "kind": "rigid", "shape": "mesh", "mesh": ")" + mesh + R"(", "position_m": [0,0,0]}]})";
  };
  for (const std::string mesh : {"meshes/nonexistent.obj", "meshes/empty.obj", "meshes/garbage.ply", "meshes/points.obj"}) {
    const std::string err = ErrorOf("mesh", scene_with_mesh(mesh));
    EXPECT_NE(err.find("hs_scene_test_mesh.json:2: field 'objects[0].mesh'"), std::string::npos) << err;
    EXPECT_NE(err.find((root / mesh).string()), std::string::npos) << err;
  }
  // Without loading meshes a missing file is still reported.
  const auto path = WriteTemp("nomesh", scene_with_mesh("meshes/nonexistent.obj"));
  EXPECT_THROW(LoadScene(path, LoadOptions{.load_meshes = false}), SceneError);
  std::filesystem::remove(path);
}

TEST(Scene, DeformablesNeedAUsableFixedRule) {
  const std::string head = std::string(R"({"name": "x", )") + kMsg + R"(, "objects": [)";
  const std::string tail_mesh = (std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "meshes" / "triceratops_tail.obj").string();
  const std::string nothing_fixed = ErrorOf("nofix", head + R"({"id": "t", "kind": "deformable", "shape": "mesh",
    "mesh": ")" + tail_mesh + R"(", "position_m": [0,0,0], "material": {"E_Pa": 30000, "nu": 0.45},
    "fixed": {"below_m": -5}}]})");
  EXPECT_NE(nothing_fixed.find("objects[0].fixed': fixes no vertex"), std::string::npos) << nothing_fixed;
  const std::string two_rules = ErrorOf("tworules", head + R"({"id": "t", "kind": "deformable", "shape": "sphere",
    "radius_m": 0.05, "position_m": [0,0,0], "material": {"E_Pa": 30000, "nu": 0.45},
    "fixed": {"below_m": 0, "nodes": [1, 2]}}]})");
  EXPECT_NE(two_rules.find("objects[0].fixed': give exactly one"), std::string::npos) << two_rules;
  const std::string bad_nu = ErrorOf("nu", head + R"({"id": "t", "kind": "deformable", "shape": "sphere",
    "radius_m": 0.05, "position_m": [0,0,0], "material": {"E_Pa": 30000, "nu": 0.5}, "fixed": {"nodes": [0]}}]})");
  EXPECT_NE(bad_nu.find("objects[0].material.nu': value 0.5 outside"), std::string::npos) << bad_nu;
}

// Fingertip friction on a deformable's skin: given, it is read; absent, it is 0 (frictionless);
// mu_kinetic defaults to mu_static and may not exceed it.
TEST(Scene, DeformableFrictionIsReadAndChecked) {
  const std::string head = std::string(R"({"name": "x", )") + kMsg + R"(, "objects": [)";
  auto object = [&](const std::string& material) {
    return head + R"({"id": "t", "kind": "deformable", "shape": "sphere", "radius_m": 0.05,
      "position_m": [0,0,0], "material": {"E_Pa": 30000, "nu": 0.45)" + material + R"(},
      "fixed": {"nodes": [0]}}]})";
  };
  const Scene given = LoadScene(WriteTemp("mu", object(R"(, "mu_static": 0.8, "mu_kinetic": 0.6)")));
  EXPECT_EQ(given.objects[0].deformable.mu_static, 0.8);
  EXPECT_EQ(given.objects[0].deformable.mu_kinetic, 0.6);
  const Scene absent = LoadScene(WriteTemp("nomu", object("")));
  EXPECT_EQ(absent.objects[0].deformable.mu_static, 0.0);
  EXPECT_EQ(absent.objects[0].deformable.mu_kinetic, 0.0);
  const Scene static_only = LoadScene(WriteTemp("mus", object(R"(, "mu_static": 0.7)")));
  EXPECT_EQ(static_only.objects[0].deformable.mu_kinetic, 0.7);
  const std::string above = ErrorOf("muk", object(R"(, "mu_static": 0.5, "mu_kinetic": 0.6)"));
  EXPECT_NE(above.find("objects[0].material.mu_kinetic': larger than mu_static"), std::string::npos) << above;
  const std::string negative = ErrorOf("mun", object(R"(, "mu_static": -0.1)"));
  EXPECT_NE(negative.find("objects[0].material.mu_static'"), std::string::npos) << negative;
}

// A deformable's stiffening table (docs/fem.md, "A correction beyond the paper"): resolved like a
// mesh, relative to the assets folder; a file that is not there is named.
TEST(Scene, AStiffeningTableIsResolvedAndAMissingOneNamed) {
  const std::string head = std::string(R"({"name": "x", )") + kMsg + R"(, "objects": [)";
  auto object = [&](const std::string& table) {
    return head + R"({"id": "t", "kind": "deformable", "shape": "sphere", "radius_m": 0.05,
      "position_m": [0,0,0], "material": {"E_Pa": 30000, "nu": 0.45, "stiffening_table": ")" + table + R"("},
      "fixed": {"nodes": [0]}}]})";
  };
  const std::filesystem::path file = WriteTemp("stiff", object("stiffening.csv"));
  const std::filesystem::path table = file.parent_path().parent_path() / "stiffening.csv";
  std::ofstream(table) << "x\n";
  const Scene given = LoadScene(file);
  EXPECT_EQ(given.objects[0].deformable.stiffening_table_uri, "stiffening.csv");
  EXPECT_EQ(given.objects[0].deformable.stiffening_table_path, table);
  std::filesystem::remove(table);
  const std::string missing = ErrorOf("stiff_missing", object("no_such_table.csv"));
  EXPECT_NE(missing.find("objects[0].material.stiffening_table': no such file"), std::string::npos) << missing;
  const std::string no_table = head + R"({"id": "t", "kind": "deformable", "shape": "sphere", "radius_m": 0.05,
      "position_m": [0,0,0], "material": {"E_Pa": 30000, "nu": 0.45}, "fixed": {"nodes": [0]}}]})";
  EXPECT_TRUE(LoadScene(WriteTemp("nostiff", no_table)).objects[0].deformable.stiffening_table_path.empty());
}

TEST(Scene, UnknownSceneListsAvailable) {
  try {
    LoadSceneByName("atlantis", kScenes);
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("solar_system"), std::string::npos);
  }
}

}  // namespace
}  // namespace handshare::scene
