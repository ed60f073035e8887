#include "handshare/web_console/world_routes.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace handshare::web_console {
namespace {

scene::Scene Load(const std::string& name) {
  return scene::LoadSceneByName(name, HANDSHARE_SOURCE_SCENES, {.load_meshes = false});
}

TEST(WorldRoutes, TheStartMenuLinksToThreeWorldsThroughItsButtons) {
  const auto routes = WorldRoutes(Load("start_menu"));
  ASSERT_EQ(routes.size(), 3u);
  for (const char* world : {"solar_system", "dinosaur", "microscopic"}) {
    const WorldRoute* r = FindRoute(routes, world);
    ASSERT_NE(r, nullptr) << world;
    EXPECT_EQ(r->control_id, std::string("button_") + world);  // a button, not the book that also goes there
    EXPECT_EQ(r->kind, controls::EventKind::kPressed);
    EXPECT_EQ(r->index, -1);
  }
  EXPECT_EQ(FindRoute(routes, "start_menu"), nullptr);
}

TEST(WorldRoutes, ABookGoesThereByTurningToThePageWhoseActionItIs) {
  scene::Scene s = Load("start_menu");
  std::erase_if(s.controls, [](const auto& c) { return c.type != scene::ControlType::kBook; });
  const auto routes = WorldRoutes(s);
  const WorldRoute* r = FindRoute(routes, "dinosaur");
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->control_id, "book_dinosaur");
  EXPECT_EQ(r->kind, controls::EventKind::kPageTurned);
  EXPECT_EQ(r->index, 1);  // page 1 only shows a message; page 2 (index 1) goes to the world
  // The route is what the world server would do with that event.
  const auto& spec = *std::find_if(s.controls.begin(), s.controls.end(), [](const auto& c) { return c.id == "book_dinosaur"; });
  ASSERT_NE(controls::ActionOf(spec, r->kind, r->index), nullptr);
  EXPECT_EQ(controls::ActionOf(spec, r->kind, r->index)->goto_scene, "dinosaur");
}

TEST(WorldRoutes, TheSolarSystemLinksBackAndOnThroughItsArrows) {
  const auto routes = WorldRoutes(Load("solar_system"));
  ASSERT_EQ(routes.size(), 2u);  // its lever changes the gravity, not the world
  EXPECT_EQ(FindRoute(routes, "start_menu")->control_id, "arrow_start");
  EXPECT_EQ(FindRoute(routes, "dinosaur")->control_id, "arrow_next");
}

}  // namespace
}  // namespace handshare::web_console
