#include "handshare/graphics/scene_replica.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "handshare/render/offscreen_renderer.hpp"
#include "handshare/scene/scene.hpp"
#include "test_oracle.hpp"
#include "world_messages.hpp"

namespace handshare::graphics {
namespace {

using render::test::OracleProject;
using render::test::PixelPoint;

const std::filesystem::path kAssets = HANDSHARE_SOURCE_ASSETS;
constexpr const char* kTailUri = "meshes/triceratops_tail.obj";

/// The pose the tests put objects in: turned about a tilted axis, so that a frame mix-up
/// (O for W, or a transposed rotation) moves what is drawn.
Eigen::Isometry3d TestPose() {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = (Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  X.translation() = Eigen::Vector3d(0.05, 0.02, 0.1);
  return X;
}

/// The test's own copy of the mesh, read independently of the cache.
scene::Mesh Tail() { return scene::LoadMesh(kAssets / kTailUri); }

// ---------------------------------------------------------------------------------------------
// What the world holds and hands to the renderer.

TEST(SceneReplica, MeshObjectIsTheFilesMeshAtItsPose) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  const Eigen::Isometry3d X_WO = TestPose();
  world.OnSceneState(Scene("dinosaur", 1, {Object("tail", "mesh", kTailUri, X_WO, {0.5F, 0.45F, 0.3F})}));
  render::SceneView view;
  world.AddObjects(view);
  ASSERT_EQ(view.meshes.size(), 1U);
  EXPECT_TRUE(view.boxes.empty());
  EXPECT_EQ(errors.str(), "");

  const scene::Mesh tail = Tail();
  const render::TriangleMesh& drawn = view.meshes[0];
  ASSERT_EQ(drawn.p_MV.size(), tail.vertices_m.size());
  ASSERT_EQ(drawn.triangles.size(), tail.triangles.size());
  for (std::size_t v = 0; v < tail.vertices_m.size(); ++v) {
    const Eigen::Vector3d expected = X_WO * tail.vertices_m[v];
    ASSERT_LT((drawn.X_WM * drawn.p_MV[v] - expected).norm(), 1e-12) << "vertex " << v;
  }
  for (std::size_t t = 0; t < tail.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) ASSERT_EQ(drawn.triangles[t][k], static_cast<std::uint32_t>(tail.triangles[t][k]));
  }
  EXPECT_FLOAT_EQ(drawn.rgb.g, 0.45F);
}

// The solar system's controls as boxes at their frames C, in a replica: where each is at rest,
// and where the replica draws it now.
struct SolarControls {
  explicit SolarControls(SceneReplica& replica) : world(replica) {
    for (const auto& c : solar.controls) {
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      X.linear() = c.q_WC.toRotationMatrix();
      X.translation() = c.p_WC_m;
      at_rest[c.id] = X;
      objects.push_back(Object(c.id, "box", "", X, {}));
    }
    world.OnSceneState(Scene("solar_system", 1, objects));
  }
  Eigen::Isometry3d drawn(const std::string& id) const {
    render::SceneView view;
    world.AddObjects(view);
    for (std::size_t i = 0; i < objects.size(); ++i) {
      if (objects[i].object_id().to_string() == id) {
        return Eigen::Isometry3d(Eigen::Translation3d(view.boxes[i].p_W) * view.boxes[i].q_WB);
      }
    }
    return Eigen::Isometry3d::Identity();
  }
  SceneReplica& world;
  const scene::Scene solar = scene::LoadSceneByName("solar_system", kAssets / "scenes");
  std::vector<msg::SceneObject> objects;
  std::map<std::string, Eigen::Isometry3d> at_rest;
};

// The world server's control states: the solar system's lever drawn in Mars' detent (turned
// 0.6 rad about its hinge axis x), a pressed arrow down by its travel; states of another world,
// or of a world left, are not drawn.
TEST(SceneReplica, ControlsAreDrawnWhereTheirStateLeftThem) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  SolarControls controls(world);
  const scene::Scene& solar = controls.solar;
  auto& at_rest = controls.at_rest;
  const auto drawn = [&](const std::string& id) { return controls.drawn(id); };
  EXPECT_TRUE(drawn("lever_planet").isApprox(at_rest["lever_planet"], 1e-12));  // no state yet
  msg::ControlState lever;
  lever.control_id("lever_planet");
  lever.scene("solar_system");
  lever.index(1);
  world.OnControlState(lever);
  const Eigen::Isometry3d expected = at_rest["lever_planet"] * Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitX());
  EXPECT_TRUE(drawn("lever_planet").isApprox(expected, 1e-9));
  msg::ControlState arrow;
  arrow.control_id("arrow_next");
  arrow.scene("solar_system");
  arrow.engaged(true);
  world.OnControlState(arrow);
  const double travel = solar.controls[2].push.travel_m;
  ASSERT_EQ(solar.controls[2].id, "arrow_next");
  EXPECT_TRUE(drawn("arrow_next").isApprox(at_rest["arrow_next"] * Eigen::Translation3d(0, 0, -travel), 1e-12));
  // A state of another world's control of the same id is not this world's.
  arrow.scene("dinosaur");
  arrow.engaged(false);
  world.OnControlState(arrow);
  EXPECT_TRUE(drawn("arrow_next").isApprox(at_rest["arrow_next"], 1e-12));
  EXPECT_EQ(errors.str(), "");
}

// The start menu's books: shut, each is covers, a spine and a block of pages, and no page is
// printed; the solar-system book open at its second page shows that page's picture on the left
// and its text in the replica's language on the right, on top of the pages (z = 0 of C).
TEST(SceneReplica, ABookIsDrawnShutOrOpenAtItsPage) {
  const scene::Scene menu = scene::LoadSceneByName("start_menu", kAssets / "scenes");
  std::vector<msg::SceneObject> objects;
  for (const auto& c : menu.controls) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = c.p_WC_m;
    objects.push_back(Object(c.id, "mesh", c.mesh_uri, X, {}));
  }
  const scene::ControlSpec& solar = menu.controls[0];
  ASSERT_EQ(solar.id, "book_solar_system");
  for (const char* language : {"en", "ja"}) {
    std::ostringstream errors;
    SceneReplica world(kAssets, errors, "", language);
    world.OnSceneState(Scene("start_menu", 1, objects));
    render::SceneView shut;
    world.AddObjects(shut);
    EXPECT_TRUE(shut.pages.empty());
    EXPECT_EQ(shut.boxes.size(), 3U * 4U) << "three books of four parts";
    EXPECT_EQ(shut.meshes.size(), 3U) << "the three buttons";

    msg::ControlState state;
    state.control_id("book_solar_system");
    state.scene("start_menu");
    state.index(1);
    state.engaged(true);
    world.OnControlState(state);
    render::SceneView open;
    world.AddObjects(open);
    ASSERT_EQ(open.pages.size(), 2U) << language;
    const render::Page& left = open.pages[0];
    const render::Page& right = open.pages[1];
    ASSERT_NE(left.image, nullptr);
    EXPECT_EQ(left.image->width_px, 240);
    EXPECT_EQ(left.image->height_px, 320);
    EXPECT_TRUE(left.text.empty());
    EXPECT_EQ(right.text, solar.page_content[1].TextIn(language));
    EXPECT_EQ(right.image, nullptr);
    const double top = solar.p_WC_m.z() + 0.0004;
    for (const render::Page* page : {&left, &right}) {
      for (const Eigen::Vector3d& corner : page->corners_W) EXPECT_NEAR(corner.z(), top, 1e-12);
    }
    const double w = solar.size_m.x();
    EXPECT_LT(left.corners_W[1].x(), solar.p_WC_m.x() - 0.5 * w + 1e-9) << "left of the spine";
    EXPECT_GT(right.corners_W[0].x(), solar.p_WC_m.x() - 0.5 * w - 1e-9) << "right of the spine";
    EXPECT_GT(left.corners_W[3].y(), left.corners_W[0].y()) << "read from the visitor's side (-y)";
    EXPECT_EQ(open.boxes.size(), 3U * 4U + 1U) << "open: two covers, a spine, two blocks of pages";
    EXPECT_EQ(errors.str(), "");
  }
  EXPECT_NE(solar.page_content[1].TextIn("en"), solar.page_content[1].TextIn("ja"));
}

// A page picture that cannot be read: said once, the page drawn without it.
TEST(SceneReplica, ABookPagePictureThatCannotBeReadIsReportedOnce) {
  const auto assets = std::filesystem::temp_directory_path() / "hs_replica_book_assets";
  std::filesystem::remove_all(assets);
  std::filesystem::create_directories(assets / "scenes");
  std::filesystem::create_directories(assets / "images");
  std::ofstream(assets / "images" / "broken.png") << "not a png";
  std::ofstream(assets / "scenes" / "shelf.json") << R"({"name": "shelf", "messages": [{"language": "en", "text": "t"}],
    "controls": [{"id": "book", "type": "book", "position_m": [0, 0, 0],
                  "pages": [{"image": "images/broken.png", "text": [{"language": "en", "text": "Hello"}]}]}]})";
  std::ostringstream errors;
  SceneReplica world(assets, errors);
  world.OnSceneState(Scene("shelf", 1, {Object("book", "box", "", Eigen::Isometry3d::Identity(), {})}));
  msg::ControlState state;
  state.control_id("book");
  state.scene("shelf");
  state.index(0);
  state.engaged(true);
  world.OnControlState(state);
  for (int frame = 0; frame < 3; ++frame) {
    render::SceneView view;
    world.AddObjects(view);
    ASSERT_EQ(view.pages.size(), 1U);
    EXPECT_EQ(view.pages[0].text, "Hello");
  }
  const std::string said = errors.str();
  EXPECT_NE(said.find("cannot read the book page picture"), std::string::npos) << said;
  EXPECT_NE(said.find("broken.png"), std::string::npos) << said;
  const std::string line = "cannot read the book page picture";
  EXPECT_EQ(said.find(line, said.find(line) + 1), std::string::npos) << "once: " << said;
  std::filesystem::remove_all(assets);
}

// While a hand moves a control (the world server's state says moving, with its position), it
// is drawn where the hand has it: the lever at its angle between detents, the arrow part way
// down, a book's cover lifted about its spine; at rest, where it settled.
TEST(SceneReplica, AControlAHandMovesIsDrawnWhereTheHandHasIt) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  SolarControls controls(world);
  const scene::Scene& solar = controls.solar;
  auto& at_rest = controls.at_rest;
  const auto drawn = [&](const std::string& id) { return controls.drawn(id); };
  msg::ControlState lever;
  lever.control_id("lever_planet");
  lever.scene("solar_system");
  lever.index(0);
  lever.moving(true);
  lever.position(0.25);
  world.OnControlState(lever);
  EXPECT_TRUE(drawn("lever_planet").isApprox(at_rest["lever_planet"] * Eigen::AngleAxisd(0.25, Eigen::Vector3d::UnitX()), 1e-9));
  lever.moving(false);
  lever.position(0.0);
  world.OnControlState(lever);
  EXPECT_TRUE(drawn("lever_planet").isApprox(at_rest["lever_planet"], 1e-12)) << "let go: back in detent 0";
  msg::ControlState arrow;
  arrow.control_id("arrow_next");
  arrow.scene("solar_system");
  arrow.moving(true);
  arrow.position(0.0007);
  world.OnControlState(arrow);
  EXPECT_TRUE(drawn("arrow_next").isApprox(at_rest["arrow_next"] * Eigen::Translation3d(0, 0, -0.0007), 1e-12));
  arrow.position(1.0);  // beyond its travel: drawn at the bottom of it
  world.OnControlState(arrow);
  const double travel = solar.controls[2].push.travel_m;
  EXPECT_TRUE(drawn("arrow_next").isApprox(at_rest["arrow_next"] * Eigen::Translation3d(0, 0, -travel), 1e-12));

  // The start menu's solar-system book with its cover lifted upright (pi / 2): the front cover
  // stands on the spine's top edge.
  const scene::Scene menu = scene::LoadSceneByName("start_menu", kAssets / "scenes");
  std::vector<msg::SceneObject> menu_objects;
  for (const auto& c : menu.controls) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = c.p_WC_m;
    menu_objects.push_back(Object(c.id, "box", "", X, {}));
  }
  world.OnSceneState(Scene("start_menu", 1, menu_objects));
  msg::ControlState book;
  book.control_id("book_solar_system");
  book.scene("start_menu");
  book.index(-1);
  book.moving(true);
  book.position(std::numbers::pi / 2);
  world.OnControlState(book);
  render::SceneView view;
  world.AddObjects(view);
  const scene::ControlSpec& spec = menu.controls[0];
  const Eigen::Vector3d hinge = spec.p_WC_m + Eigen::Vector3d(-0.5 * spec.size_m.x(), 0.0, 0.0);
  int standing = 0;
  for (const render::Box& b : view.boxes) {
    // Upright: its long side (x of the box) along z, its centre half a book's width above the hinge.
    const Eigen::Vector3d along = b.q_WB * Eigen::Vector3d::UnitX();
    if (std::abs(std::abs(along.z()) - 1.0) < 1e-9 && std::abs(b.p_W.z() - (hinge.z() + 0.5 * spec.size_m.x())) < 1e-9 &&
        std::abs(b.p_W.x() - hinge.x()) < 0.005) {
      ++standing;
    }
  }
  EXPECT_EQ(standing, 1) << "the solar-system book's front cover stands on its spine";
  EXPECT_TRUE(view.pages.empty()) << "not open yet";
  EXPECT_EQ(errors.str(), "");
}

// Labels from the scene file, in the replica's language: the solar system's ball is named 1 cm
// above its top, the lever above its handle; the ground has none.
TEST(SceneReplica, ObjectsAndControlsAreLabelledInTheReplicasLanguage) {
  const scene::Scene solar = scene::LoadSceneByName("solar_system", kAssets / "scenes");
  std::vector<msg::SceneObject> objects;
  for (const auto& o : solar.objects) {
    const std::string shape = o.shape == scene::Shape::kSphere ? "sphere" : o.shape == scene::Shape::kBox ? "box" : "mesh";
    objects.push_back(Object(o.id, shape, o.mesh_uri, o.X_WO(), {}, o.half_extent_m));
  }
  for (const char* language : {"en", "ja"}) {
    std::ostringstream errors;
    SceneReplica world(kAssets, errors, "", language);
    world.OnSceneState(Scene("solar_system", 1, objects));
    render::SceneView view;
    world.AddObjects(view);
    std::map<std::string, Eigen::Vector3d> at;
    for (const render::Label& l : view.labels) at[l.text] = l.p_W;
    const std::string ball = std::string(language) == "ja" ? "ボール" : "Ball";
    ASSERT_EQ(at.count(ball), 1U) << language;
    const scene::SceneObject& spec = solar.objects[1];
    ASSERT_EQ(spec.id, "ball");
    EXPECT_TRUE(at[ball].isApprox(spec.p_WO_m + Eigen::Vector3d(0.0, 0.0, spec.half_extent_m.x() + 0.01), 1e-12));
    const std::string lever = std::string(language) == "ja" ? "月 | 火星" : "Moon | Mars";
    ASSERT_EQ(at.count(lever), 1U) << language;
    EXPECT_GT(at[lever].z(), solar.controls[0].p_WC_m.z() + 0.08) << "above the handle's top";
    EXPECT_EQ(view.labels.size(), 5U) << "ball, weight, lever and two arrows; not the ground";
    EXPECT_EQ(errors.str(), "");
  }
}

TEST(SceneReplica, EachMeshFileIsLoadedOnce) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  const Eigen::Isometry3d X = TestPose();
  world.OnSceneState(Scene("a", 1, {Object("left", "mesh", kTailUri, X, {}), Object("right", "mesh", kTailUri, X, {})}));
  world.OnSceneState(Scene("b", 1, {Object("again", "mesh", kTailUri, X, {})}));
  EXPECT_EQ(world.meshes().loads(), 1U);
  render::SceneView view;
  world.AddObjects(view);
  EXPECT_EQ(view.meshes.size(), 1U);
}

TEST(SceneReplica, DrawnVertexIsPoseTimesVertexPlusWorldDisplacement) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  const Eigen::Isometry3d X_WO = TestPose();
  world.OnSceneState(Scene("dinosaur", 1, {Object("tail", "mesh", kTailUri, X_WO, {})}));
  const std::vector<std::uint32_t> ids = {0, 17, 500};
  const std::vector<float> u = {0.001F, 0.0F, 0.0F, 0.0F, -0.002F, 0.0F, 0.0F, 0.0F, 0.003F};
  world.OnDeformation(Deformation("tail", 1, true, ids, u));
  render::SceneView view;
  world.AddObjects(view);
  ASSERT_EQ(view.meshes.size(), 1U);
  const scene::Mesh tail = Tail();
  const render::TriangleMesh& drawn = view.meshes[0];
  for (std::size_t v = 0; v < tail.vertices_m.size(); ++v) {
    Eigen::Vector3d u_W = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < ids.size(); ++i) {
      if (ids[i] == v) u_W = Eigen::Vector3d(u[3 * i], u[3 * i + 1], u[3 * i + 2]);
    }
    const Eigen::Vector3d expected = X_WO * tail.vertices_m[v] + u_W;
    ASSERT_LT((drawn.X_WM * drawn.p_MV[v] - expected).norm(), 1e-12) << "vertex " << v;
  }
  // Normals were recomputed for the displaced mesh. (A vertex's own area-weighted normal does
  // not change when it alone moves: the area vector of its closed 1-ring depends only on the
  // ring. Its neighbours' normals do.)
  render::SceneView rest;
  world.OnDeformation(Deformation("tail", 2, true, {}, {}));
  world.AddObjects(rest);
  std::int32_t neighbour = -1;
  for (const auto& t : tail.triangles) {
    if (t[0] == 500) neighbour = t[1];
  }
  ASSERT_GE(neighbour, 0);
  EXPECT_GT((drawn.n_MV[neighbour] - rest.meshes[0].n_MV[neighbour]).norm(), 1e-3);
  // A vertex in no triangle with a displaced vertex keeps its normal, bit for bit.
  std::set<std::uint32_t> near(ids.begin(), ids.end());
  for (const auto& t : tail.triangles) {
    for (const auto id : ids) {
      if (t[0] == static_cast<std::int32_t>(id) || t[1] == static_cast<std::int32_t>(id) || t[2] == static_cast<std::int32_t>(id)) {
        for (const auto v : t) near.insert(static_cast<std::uint32_t>(v));
      }
    }
  }
  int compared = 0;
  for (std::uint32_t v = 0; v < tail.vertices_m.size(); ++v) {
    if (near.count(v) != 0) continue;
    ASSERT_EQ(drawn.n_MV[v], rest.meshes[0].n_MV[v]) << "vertex " << v;
    ++compared;
  }
  EXPECT_GT(compared, 900);
}

TEST(SceneReplica, DeformationsFollowTheReceiverRuleAndResetWithTheScene) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  const Eigen::Isometry3d X = TestPose();
  const auto dinosaur = [&](std::uint32_t revision) {
    return Scene("dinosaur", revision, {Object("tail", "mesh", kTailUri, X, {}),
                                        Object("ground", "box", "", Eigen::Isometry3d::Identity(), {})});
  };
  world.OnSceneState(dinosaur(1));
  const DeformationField* field = world.deformation("tail");
  ASSERT_NE(field, nullptr);
  EXPECT_EQ(field->vertex_count(), Tail().vertices_m.size());
  EXPECT_EQ(world.field_revisions(), "") << "no sample yet";
  EXPECT_EQ(world.deformation("ground"), nullptr) << "a box has no vertices to displace";

  msg::Deformation first = Deformation("tail", 1, true, {3, 961, 962, 5000}, std::vector<float>(12, 0.001F));
  first.surface_node_count(962);
  world.OnDeformation(first);
  EXPECT_EQ(world.stats().deformation_count_mismatch, 0U);
  EXPECT_TRUE(field->displaced());
  EXPECT_EQ(field->stats().ids_out_of_range, 2U) << "962 vertices: ids 962 and 5000 are beyond";
  EXPECT_EQ(field->u_W_m()[961], Eigen::Vector3d::Constant(double(0.001F)));
  EXPECT_EQ(world.field_revisions(), "tail@1") << "what frame_times.csv says a frame shows";

  // Samples for objects that are not in the scene, or have no mesh, are counted and dropped.
  world.OnDeformation(Deformation("daphnia_belly", 1, true, {0}, {1, 1, 1}));
  world.OnDeformation(Deformation("ground", 1, true, {0}, {1, 1, 1}));
  EXPECT_EQ(world.stats().deformation_unknown_object, 1U);
  EXPECT_EQ(world.stats().deformation_without_mesh, 1U);
  // A publisher that numbers another mesh is counted (and still applied).
  msg::Deformation other = Deformation("tail", 1, false, {3}, {0.001F, 0.001F, 0.001F});
  other.surface_node_count(1000);
  world.OnDeformation(other);
  EXPECT_EQ(world.stats().deformation_count_mismatch, 1U);

  // Another revision of the same scene (gravity changed, say): the field stays.
  world.OnSceneState(dinosaur(2));
  field = world.deformation("tail");
  ASSERT_NE(field, nullptr);
  EXPECT_TRUE(field->displaced());
  EXPECT_EQ(field->revision(), 1U);

  // Another scene and back: the field starts again from zero, no revision seen, so the
  // restarted publisher's revision 1 keyframe is a keyframe again.
  world.OnSceneState(Scene("microscopic", 3, {}));
  EXPECT_EQ(world.deformation("tail"), nullptr);
  world.OnSceneState(dinosaur(4));
  field = world.deformation("tail");
  ASSERT_NE(field, nullptr);
  EXPECT_FALSE(field->displaced());
  EXPECT_FALSE(field->revision().has_value());
  EXPECT_EQ(world.stats().scene_changes, 2U);
  // The statistics of the fields of earlier scenes are kept.
  EXPECT_EQ(world.deformation_stats().ids_out_of_range, 2U);
}

TEST(SceneReplica, ObjectStatesMoveObjectsOfTheSceneOnly) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  const Eigen::Isometry3d X_scene = TestPose();
  world.OnSceneState(Scene("microscopic", 1, {Object("daphnia", "mesh", kTailUri, X_scene, {}),
                                              Object("ball", "sphere", "", X_scene, {}, Eigen::Vector3d(0.03, 0, 0))}));
  ASSERT_TRUE(world.X_WO("daphnia").has_value());
  EXPECT_TRUE(world.X_WO("daphnia")->isApprox(X_scene, 1e-12));

  // The state's pose replaces the scene's; the quaternion is normalized.
  world.OnObjectState(State("daphnia", {0.1, 0.2, 0.3}, {2.0, 0.0, 0.0, 0.0}));
  world.OnObjectState(State("ball", {-0.1, 0.0, 0.05}, {1.0, 0.0, 0.0, 0.0}));
  Eigen::Isometry3d expected = Eigen::Isometry3d::Identity();
  expected.translation() = Eigen::Vector3d(0.1, 0.2, 0.3);
  EXPECT_TRUE(world.X_WO("daphnia")->isApprox(expected, 1e-12));
  render::SceneView view;
  world.AddObjects(view);
  ASSERT_EQ(view.meshes.size(), 1U);
  ASSERT_EQ(view.spheres.size(), 1U);
  EXPECT_TRUE(view.meshes[0].X_WM.isApprox(expected, 1e-12));
  EXPECT_TRUE(view.spheres[0].p_W.isApprox(Eigen::Vector3d(-0.1, 0.0, 0.05), 1e-12));

  // Non-finite positions, quaternions and a zero quaternion are rejected; the last good pose stays.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  world.OnObjectState(State("daphnia", {nan, 0.0, 0.0}, {1.0, 0.0, 0.0, 0.0}));
  world.OnObjectState(State("daphnia", {0.0, 0.0, 0.0}, {1.0, std::numeric_limits<double>::infinity(), 0.0, 0.0}));
  world.OnObjectState(State("daphnia", {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0}));
  EXPECT_EQ(world.stats().object_states_nonfinite, 3U);
  EXPECT_TRUE(world.X_WO("daphnia")->isApprox(expected, 1e-12));

  // An object of no current scene is ignored.
  world.OnObjectState(State("moon", {0.0, 0.0, 0.0}, {1.0, 0.0, 0.0, 0.0}));
  EXPECT_EQ(world.stats().object_states_unknown, 1U);
  EXPECT_FALSE(world.X_WO("moon").has_value());

  // A new revision of the scene keeps the pose; another scene forgets it.
  world.OnSceneState(Scene("microscopic", 2, {Object("daphnia", "mesh", kTailUri, X_scene, {})}));
  EXPECT_TRUE(world.X_WO("daphnia")->isApprox(expected, 1e-12));
  world.OnSceneState(Scene("dinosaur", 3, {Object("daphnia", "mesh", kTailUri, X_scene, {})}));
  EXPECT_TRUE(world.X_WO("daphnia")->isApprox(X_scene, 1e-12));
}

TEST(SceneReplica, DeformationJsonHoldsTheNonZeroDisplacements) {
  TempDir dir;
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  world.OnSceneState(Scene("dinosaur", 1, {Object("tail", "mesh", kTailUri, TestPose(), {}),
                                           Object("leg", "mesh", kTailUri, TestPose(), {})}));
  world.OnDeformation(Deformation("tail", 7, true, {4, 9, 11}, {0.25F, -0.5F, 0.125F, 0, 0, 0, 0, 0, -0.001F}));
  const auto file = dir.path() / "deformation.json";
  world.WriteDeformationJson(file);
  std::ifstream in(file);
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_TRUE(j.contains("tail"));
  EXPECT_FALSE(j.contains("leg")) << "no sample received for it";
  EXPECT_EQ(j["tail"]["revision"], 7);
  EXPECT_EQ(j["tail"]["vertex_count"], 962);
  const auto& u = j["tail"]["u_W_m"];
  ASSERT_EQ(u.size(), 2U) << "vertex 9 is at zero";
  EXPECT_EQ(u["4"][0].get<double>(), 0.25);
  EXPECT_EQ(u["4"][1].get<double>(), -0.5);
  EXPECT_EQ(u["4"][2].get<double>(), 0.125);
  EXPECT_EQ(u["11"][2].get<float>(), -0.001F) << "the received float, exactly";
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "deformation.json.tmp"));

  EXPECT_THROW(world.WriteDeformationJson(dir.path() / "no_such_folder" / "d.json"), std::runtime_error);
}

TEST(SceneReplica, MissingOrBadMeshIsReportedOnceAndDrawnAsItsBox) {
  TempDir dir;
  const auto junk = dir.path() / "junk.obj";
  std::ofstream(junk) << "this is not a mesh\n";
  std::ostringstream errors;
  SceneReplica world(kAssets, errors, "[spectator] ");
  const Eigen::Isometry3d X = TestPose();
  const auto state = Scene("dinosaur", 1, {Object("ghost", "mesh", "meshes/no_such_mesh.obj", X, {0, 1, 0}, {0.03, 0.02, 0.01}),
                                           Object("junk", "mesh", junk.string(), X, {0, 0, 1}),
                                           Object("empty", "mesh", "", X, {1, 0, 0})});
  world.OnSceneState(state);
  world.OnSceneState(state);  // the same scene again: no second report
  const std::string text = errors.str();
  EXPECT_NE(text.find("[spectator] object 'ghost' of scene 'dinosaur': cannot load mesh 'meshes/no_such_mesh.obj' (file " +
                      (kAssets / "meshes/no_such_mesh.obj").string() + "): "),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("no such file"), std::string::npos) << text;
  EXPECT_NE(text.find("object 'junk'"), std::string::npos) << text;
  EXPECT_NE(text.find("object 'empty'"), std::string::npos) << text;
  EXPECT_NE(text.find("empty mesh_uri"), std::string::npos) << text;
  EXPECT_EQ(world.stats().mesh_errors, 3U);

  render::SceneView view;
  world.AddObjects(view);
  EXPECT_TRUE(view.meshes.empty());
  ASSERT_EQ(view.boxes.size(), 3U);
  EXPECT_TRUE(view.boxes[0].p_W.isApprox(X.translation(), 1e-12));
  EXPECT_TRUE(view.boxes[0].q_WB.toRotationMatrix().isApprox(X.linear(), 1e-12));
  EXPECT_TRUE(view.boxes[0].half_extents_m.isApprox(Eigen::Vector3d(0.03, 0.02, 0.01), 1e-12));
  // Deformations of such an object are dropped, not applied to anything.
  world.OnDeformation(Deformation("ghost", 1, true, {0}, {1, 1, 1}));
  EXPECT_EQ(world.stats().deformation_without_mesh, 1U);
}

// ---------------------------------------------------------------------------------------------
// Pixels: the real mesh drawn offscreen against an independent projection.

constexpr render::Rgb kGreen{0.1F, 0.9F, 0.2F};

render::Camera TailCamera(const Eigen::Isometry3d& X_WO) {
  render::Camera camera;
  camera.target_W = X_WO * Eigen::Vector3d(-0.09, 0.0, 0.0);  // the middle of the tail
  camera.eye_W = camera.target_W + Eigen::Vector3d(0.12, -0.32, 0.2);
  camera.up_W = {0.0, 0.0, 1.0};
  camera.fov_y_rad = 0.7;
  camera.width_px = 400;
  camera.height_px = 300;
  camera.near_m = 0.05;
  camera.far_m = 5.0;
  return camera;
}

render::SceneView Bare() {
  render::SceneView view;
  view.grid.visible = false;
  view.background_rgb = {0.0F, 0.0F, 0.0F};
  return view;
}

bool Covered(const std::uint8_t* px) { return px[0] > 8 || px[1] > 8 || px[2] > 8; }

/// Which pixel centres the triangles cover, by the test's own rasterizer (edge functions on
/// OracleProject's image coordinates; no depth, either winding).
std::vector<bool> OracleCoverage(const render::Camera& camera, const std::vector<Eigen::Vector3d>& p_W,
                                 const std::vector<std::array<std::int32_t, 3>>& triangles,
                                 const std::vector<bool>* only = nullptr) {
  std::vector<bool> mask(static_cast<std::size_t>(camera.width_px * camera.height_px), false);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (only != nullptr && !(*only)[t]) continue;
    PixelPoint q[3];
    for (int k = 0; k < 3; ++k) q[k] = OracleProject(camera, p_W[triangles[t][k]]);
    const double area = (q[1].col - q[0].col) * (q[2].row - q[0].row) - (q[1].row - q[0].row) * (q[2].col - q[0].col);
    if (area == 0.0) continue;
    const int c0 = std::max(0, static_cast<int>(std::floor(std::min({q[0].col, q[1].col, q[2].col}))));
    const int c1 = std::min(camera.width_px - 1, static_cast<int>(std::ceil(std::max({q[0].col, q[1].col, q[2].col}))));
    const int r0 = std::max(0, static_cast<int>(std::floor(std::min({q[0].row, q[1].row, q[2].row}))));
    const int r1 = std::min(camera.height_px - 1, static_cast<int>(std::ceil(std::max({q[0].row, q[1].row, q[2].row}))));
    for (int row = r0; row <= r1; ++row) {
      for (int col = c0; col <= c1; ++col) {
        const double x = col + 0.5;
        const double y = row + 0.5;
        bool inside = true;
        for (int k = 0; k < 3; ++k) {
          const PixelPoint& a = q[k];
          const PixelPoint& b = q[(k + 1) % 3];
          const double e = (b.col - a.col) * (y - a.row) - (b.row - a.row) * (x - a.col);
          if (e * area < 0.0) inside = false;
        }
        if (inside) mask[static_cast<std::size_t>(row * camera.width_px + col)] = true;
      }
    }
  }
  return mask;
}

/// mask grown by `radius` pixels (square neighbourhood).
std::vector<bool> Dilate(const std::vector<bool>& mask, int width, int height, int radius) {
  std::vector<bool> out(mask.size(), false);
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      if (!mask[static_cast<std::size_t>(row * width + col)]) continue;
      for (int dr = -radius; dr <= radius; ++dr) {
        for (int dc = -radius; dc <= radius; ++dc) {
          const int r = row + dr;
          const int c = col + dc;
          if (r >= 0 && r < height && c >= 0 && c < width) out[static_cast<std::size_t>(r * width + c)] = true;
        }
      }
    }
  }
  return out;
}

TEST(SceneReplicaOffscreen, TailMeshCoversExactlyItsIndependentlyProjectedTriangles) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  const Eigen::Isometry3d X_WO = TestPose();
  world.OnSceneState(Scene("dinosaur", 1, {Object("tail", "mesh", kTailUri, X_WO, kGreen)}));
  render::SceneView view = Bare();
  world.AddObjects(view);
  const render::Camera camera = TailCamera(X_WO);
  render::OffscreenRenderer renderer;
  const render::ImageRgb8 image = renderer.Render(view, camera);

  const scene::Mesh tail = Tail();
  std::vector<Eigen::Vector3d> p_W;
  for (const auto& v : tail.vertices_m) p_W.push_back(X_WO * v);
  const std::vector<bool> oracle = OracleCoverage(camera, p_W, tail.triangles);
  // Rasterization differs from the oracle only where a pixel centre lies within about a pixel
  // of a projected edge: a mismatch counts only where the oracle's 3x3 neighbourhood is uniform.
  const std::vector<bool> grown = Dilate(oracle, camera.width_px, camera.height_px, 1);
  std::vector<bool> inverted(oracle.size());
  for (std::size_t i = 0; i < oracle.size(); ++i) inverted[i] = !oracle[i];
  const std::vector<bool> grown_out = Dilate(inverted, camera.width_px, camera.height_px, 1);
  int covered = 0;
  int interior = 0;
  int wrong = 0;
  int not_green = 0;
  for (int row = 0; row < camera.height_px; ++row) {
    for (int col = 0; col < camera.width_px; ++col) {
      const std::size_t i = static_cast<std::size_t>(row * camera.width_px + col);
      const std::uint8_t* px = image.At(col, row);
      const bool drawn = Covered(px);
      covered += drawn ? 1 : 0;
      const bool surely_in = oracle[i] && !grown_out[i];
      const bool surely_out = !grown[i];
      if ((surely_in && !drawn) || (surely_out && drawn)) {
        if (++wrong <= 5) ADD_FAILURE() << "pixel (" << col << ", " << row << ") drawn " << drawn << ", oracle " << oracle[i];
      }
      if (surely_in) {
        ++interior;
        // The object's colour, shaded: green dominates.
        if (!(px[1] > px[0] && px[1] > px[2] && px[1] > 40)) ++not_green;
      }
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(not_green, 0);
  EXPECT_GT(interior, 3000) << "the tail should fill a good part of the image";
  EXPECT_GT(covered, interior);
}

TEST(SceneReplicaOffscreen, DentChangesThePixelsOfTheDisplacedPatchAndNothingElse) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  const Eigen::Isometry3d X_WO = TestPose();
  world.OnSceneState(Scene("dinosaur", 1, {Object("tail", "mesh", kTailUri, X_WO, kGreen)}));
  const render::Camera camera = TailCamera(X_WO);
  render::OffscreenRenderer renderer;
  render::SceneView rest_view = Bare();
  world.AddObjects(rest_view);
  const render::ImageRgb8 rest = renderer.Render(rest_view, camera);

  // The dent's centre: the vertex nearest the eye (it faces the camera, so it is visible).
  const scene::Mesh tail = Tail();
  std::vector<Eigen::Vector3d> p_W;
  for (const auto& v : tail.vertices_m) p_W.push_back(X_WO * v);
  std::size_t centre = 0;
  for (std::size_t v = 0; v < p_W.size(); ++v) {
    if ((p_W[v] - camera.eye_W).norm() < (p_W[centre] - camera.eye_W).norm()) centre = v;
  }
  // A known field: a paraboloid dent of 4 mm depth and 10 mm radius, pushed away from the eye.
  const Eigen::Vector3d into_W = (p_W[centre] - camera.eye_W).normalized();
  constexpr double kDepth_m = 0.004;
  constexpr double kRadius_m = 0.010;
  std::vector<std::uint32_t> ids;
  std::vector<float> u;
  std::vector<bool> displaced(p_W.size(), false);
  std::vector<Eigen::Vector3d> dented = p_W;
  for (std::size_t v = 0; v < p_W.size(); ++v) {
    const double r = (p_W[v] - p_W[centre]).norm();
    if (r >= kRadius_m) continue;
    const Eigen::Vector3f u_W = (kDepth_m * (1.0 - r * r / (kRadius_m * kRadius_m)) * into_W).cast<float>();
    ids.push_back(static_cast<std::uint32_t>(v));
    u.insert(u.end(), {u_W.x(), u_W.y(), u_W.z()});
    displaced[v] = true;
    dented[v] += u_W.cast<double>();
  }
  ASSERT_GT(ids.size(), 3U) << "the dent should move several vertices";
  world.OnDeformation(Deformation("tail", 1, true, ids, u));
  render::SceneView dent_view = Bare();
  world.AddObjects(dent_view);
  const render::ImageRgb8 dent = renderer.Render(dent_view, camera);

  // Where a change may show: triangles with a vertex that moved or whose normal changed (a
  // vertex of a triangle touching a moved vertex), before and after the dent, plus 2 px.
  std::vector<bool> normal_changed = displaced;
  for (const auto& t : tail.triangles) {
    if (displaced[t[0]] || displaced[t[1]] || displaced[t[2]]) {
      for (const auto v : t) normal_changed[v] = true;
    }
  }
  std::vector<bool> affected(tail.triangles.size(), false);
  for (std::size_t t = 0; t < tail.triangles.size(); ++t) {
    for (const auto v : tail.triangles[t]) affected[t] = affected[t] || normal_changed[v];
  }
  std::vector<bool> region = OracleCoverage(camera, p_W, tail.triangles, &affected);
  const std::vector<bool> after = OracleCoverage(camera, dented, tail.triangles, &affected);
  for (std::size_t i = 0; i < region.size(); ++i) region[i] = region[i] || after[i];
  region = Dilate(region, camera.width_px, camera.height_px, 2);

  const PixelPoint c = OracleProject(camera, dented[centre]);
  int changed_inside = 0;
  int changed_outside = 0;
  int changed_near_centre = 0;
  for (int row = 0; row < camera.height_px; ++row) {
    for (int col = 0; col < camera.width_px; ++col) {
      const std::uint8_t* a = rest.At(col, row);
      const std::uint8_t* b = dent.At(col, row);
      const bool changed = a[0] != b[0] || a[1] != b[1] || a[2] != b[2];
      if (!changed) continue;
      if (region[static_cast<std::size_t>(row * camera.width_px + col)]) {
        ++changed_inside;
      } else if (++changed_outside <= 5) {
        ADD_FAILURE() << "pixel (" << col << ", " << row << ") changed outside the dent";
      }
      if (std::hypot(col + 0.5 - c.col, row + 0.5 - c.row) < 6.0) ++changed_near_centre;
    }
  }
  EXPECT_EQ(changed_outside, 0);
  EXPECT_GT(changed_inside, 30) << "a 4 mm dent should reshade the patch";
  EXPECT_GT(changed_near_centre, 10) << "the shading changes around the projected dent centre";

  // Back to rest by an empty keyframe: the image is the undeformed one again, exactly.
  world.OnDeformation(Deformation("tail", 2, true, {}, {}));
  render::SceneView again = Bare();
  world.AddObjects(again);
  EXPECT_EQ(renderer.Render(again, camera).rgb, rest.rgb);
}

TEST(SceneReplicaOffscreen, MissingMeshIsDrawnAsItsBox) {
  std::ostringstream errors;
  SceneReplica world(kAssets, errors);
  const Eigen::Isometry3d X_WO = TestPose();
  world.OnSceneState(Scene("dinosaur", 1, {Object("ghost", "mesh", "meshes/no_such_mesh.obj", X_WO, kGreen,
                                                  {0.03, 0.03, 0.03})}));
  EXPECT_NE(errors.str().find("object 'ghost'"), std::string::npos);
  render::SceneView view = Bare();
  world.AddObjects(view);
  render::Camera camera = TailCamera(X_WO);
  camera.target_W = X_WO.translation();
  render::OffscreenRenderer renderer;
  const render::ImageRgb8 image = renderer.Render(view, camera);
  // The box's centre and points well inside its faces are green; a point 2 half sizes away is not.
  const PixelPoint centre = OracleProject(camera, X_WO.translation());
  const std::uint8_t* px = image.At(static_cast<int>(centre.col), static_cast<int>(centre.row));
  EXPECT_GT(px[1], 60);
  EXPECT_GT(px[1], px[0]);
  const Eigen::Vector3d right_W = (camera.target_W - camera.eye_W).cross(camera.up_W).normalized();
  const PixelPoint beside = OracleProject(camera, X_WO.translation() + 0.1 * right_W);
  EXPECT_FALSE(Covered(image.At(static_cast<int>(beside.col), static_cast<int>(beside.row))));
}

}  // namespace
}  // namespace handshare::graphics
