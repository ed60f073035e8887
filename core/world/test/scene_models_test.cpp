#include "handshare/world/scene_models.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

namespace handshare::world {
namespace {

std::filesystem::path TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("handshare_world_test_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "scenes");
  return dir;
}

scene::Scene WriteAndLoad(const std::filesystem::path& dir, const std::string& name, const std::string& objects) {
  const auto file = dir / "scenes" / (name + ".json");
  std::ofstream(file) << R"({"name": ")" << name << R"(", "gravity_m_per_s2": [0, 0, -1.62], "objects": [)"
                      << objects << R"(], "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  return scene::LoadScene(file);
}

const char* kGroundAndBall =
    R"({"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]},
       {"id": "ball", "kind": "rigid", "shape": "sphere", "position_m": [0, 0, 0.06], "radius_m": 0.04, "mass_kg": 0.2})";

// The ball falls onto the ground's top face under the scene's (Moon) gravity and rests there.
TEST(SceneModels, DynamicBallRestsOnTheGroundUnderTheSceneGravity) {
  const auto dir = TempDir("ball");
  const scene::Scene s = WriteAndLoad(dir, "moon", kGroundAndBall);
  SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  SceneModels sw = BuildSceneModels(s, options);
  ASSERT_EQ(sw.dynamic_bodies.size(), 1u);
  const auto ball = sw.Find("ball");
  ASSERT_GE(ball, 0);
  EXPECT_EQ(sw.ids[ball], "ball");
  EXPECT_EQ(sw.Find("nothing"), -1);
  std::array<Eigen::Vector3d, 5> far;
  for (auto& p : far) p = Eigen::Vector3d(5, 5, 5);  // fingertips nowhere near
  for (int k = 0; k < 4000; ++k) sw.world->Step(1e-3, far);
  // Resting on the support: the centre a radius above the top face, within the support's
  // penalty sag m g / k = 0.2 * 1.62 / 5000 = 65 um (and a little more while settling).
  EXPECT_NEAR(sw.world->pose(ball).translation().z(), 0.04, 2e-4);
  EXPECT_LT(sw.world->body_velocity_W(ball).norm(), 1e-3);
}

TEST(SceneModels, DeformableBoxIsPreparedOnceThenLoadedFromTheCache) {
  const auto dir = TempDir("box");
  const std::string block =
      R"({"id": "block", "kind": "deformable", "shape": "box", "position_m": [0, 0, 0.02],
          "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.4},
          "fixed": {"below_m": -0.0099}})";
  const scene::Scene s = WriteAndLoad(dir, "soft", block);
  const auto& o = s.objects.front();
  const PreparedDeformable first = PrepareDeformable(s, o, dir / "cache");
  EXPECT_GT(first.compliance->num_nodes(), 50);
  EXPECT_FALSE(first.fixed_nodes.empty());
  for (std::int32_t n : first.fixed_nodes) EXPECT_NEAR(first.mesh->positions_m()[n].z(), -0.01, 1e-12);
  const PreparedDeformable second = PrepareDeformable(s, o, dir / "cache");
  EXPECT_EQ(second.compliance->input_hash(), first.compliance->input_hash());
  EXPECT_NE(second.cache_note, first.cache_note);  // precomputed, then loaded
  SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  SceneModels sw = BuildSceneModels(s, options);
  ASSERT_EQ(sw.deformables.size(), 1u);
  // A fingertip pressed 2 mm into the top face feels an upward force.
  std::array<Eigen::Vector3d, 5> tips;
  for (auto& p : tips) p = Eigen::Vector3d(5, 5, 5);
  for (int k = 0; k <= 100; ++k) {
    tips[1] = Eigen::Vector3d(0, 0, 0.03 + 0.008 - 0.002 * k / 100.0);
    sw.world->Step(1e-3, tips);
  }
  EXPECT_GT(sw.world->fingers()[1].f_E_W_N.z(), 0.01);
  EXPECT_EQ(sw.world->fingers()[1].object, sw.Find("block"));
}

TEST(SceneModels, ADeformableWithoutFixedNodesIsAnErrorNamingFileAndObject) {
  const auto dir = TempDir("free");
  const std::string block =
      R"({"id": "floater", "kind": "deformable", "shape": "box", "position_m": [0, 0, 0.02],
          "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.4},
          "fixed": {"below_m": -1.0}})";
  const scene::Scene s = WriteAndLoad(dir, "free", block);
  try {
    PrepareDeformable(s, s.objects.front(), dir / "cache");
    FAIL() << "no error";
  } catch (const scene::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("free.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("floater"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("holds no node"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace handshare::world

namespace handshare::world {
namespace {

// A block whose top is driven up and down (a beat) while its bottom is held. With nu = 0 the
// exact solution is uniaxial: u_z = d (z + h) / 2h and no lateral motion, which linear
// tetrahedra reproduce exactly: the mode must be that field at every node.
TEST(SceneModels, ABeatsModeIsTheBodysStaticResponseToItsDrivenNodes) {
  const auto dir = TempDir("beat");
  const std::string block =
      R"({"id": "block", "kind": "deformable", "shape": "box", "position_m": [0, 0, 0.02],
          "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.0},
          "fixed": {"below_m": -0.0099},
          "beat": {"driven": {"plane_point_m": [0, 0, 0.0099], "plane_normal": [0, 0, -1]},
                   "displacement_m": [0, 0, 0.002], "period_s": 1.0}})";
  const scene::Scene s = WriteAndLoad(dir, "beat", block);
  const PreparedDeformable p = PrepareDeformable(s, s.objects.front(), dir / "cache");
  ASSERT_NE(p.mode_O_m, nullptr);
  ASSERT_FALSE(p.driven_nodes.empty());
  const auto& x = p.mesh->positions_m();
  for (const auto n : p.driven_nodes) EXPECT_NEAR(x[static_cast<std::size_t>(n)].z(), 0.01, 1e-12);
  double worst = 0.0;
  for (std::size_t n = 0; n < x.size(); ++n) {
    const Eigen::Vector3d exact(0.0, 0.0, 0.002 * (x[n].z() + 0.01) / 0.02);
    worst = std::max(worst, ((*p.mode_O_m)[n] - exact).norm());
  }
  EXPECT_LT(worst, 1e-12) << "largest difference from the uniaxial field [m]";
  // The compliance holds the driven nodes too: a fingertip's field adds to s M.
  for (const auto node : p.compliance->nodes()) {
    EXPECT_FALSE(std::binary_search(p.driven_nodes.begin(), p.driven_nodes.end(), node)) << node;
  }
  const std::string still = std::string(block).replace(block.find(",\n          \"beat\""), std::string::npos, "}");
  const scene::Scene s2 = WriteAndLoad(dir, "still", still);
  const PreparedDeformable q = PrepareDeformable(s2, s2.objects.front(), dir / "cache");
  EXPECT_EQ(q.mode_O_m, nullptr);
  EXPECT_EQ(q.compliance->num_nodes(), p.compliance->num_nodes() + static_cast<std::int32_t>(p.driven_nodes.size()));
  // The models beat: the world takes the scale.
  SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  SceneModels models = BuildSceneModels(s, options);
  const auto id = models.Find("block");
  models.world->SetModeScale(id, 0.5);
  EXPECT_EQ(models.world->mode_scale(id), 0.5);
}

TEST(SceneModels, ABeatThatDrivesOnlyFixedNodesNamesTheObject) {
  const auto dir = TempDir("beat_fixed");
  const scene::Scene s = WriteAndLoad(dir, "beat_fixed",
      R"({"id": "block", "kind": "deformable", "shape": "box", "position_m": [0, 0, 0.02],
          "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.3},
          "fixed": {"below_m": -0.0099},
          "beat": {"driven": {"plane_point_m": [0, 0, -0.0099], "plane_normal": [0, 0, 1]},
                   "displacement_m": [0, 0, 0.002], "period_s": 1.0}})");
  try {
    PrepareDeformable(s, s.objects.front(), dir / "cache");
    FAIL() << "a beat of fixed nodes only was accepted";
  } catch (const scene::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("object 'block': its beat drives no node that is not fixed"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace handshare::world

#include "test_models.hpp"

namespace handshare::world {
namespace {

// The tail pressed where the tour presses it (a fingertip 5 mm into the top, 95 mm from the
// root, then drawn 2 mm along the tail so that its stick leans the press), with and without the
// scene naming its stiffening table (docs/fem.md, "A correction beyond the paper"). Off, the
// table changes nothing; on, the felt force differs, by a gain inside the table's range. Fails
// if the haptic world does not apply the table (or applies it when told not to).
TEST(SceneModels, AStiffeningTableScalesTheFeltForceOnlyWhenOn) {
  auto press = [](bool table, bool on) {
    scene::Scene s = test::OneDeformable("dinosaur.json", "triceratops_tail");
    if (table) {
      s.objects[0].deformable.stiffening_table_path =
          std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "meshes" / "triceratops_tail.stiffening.csv";
    }
    SceneModelsOptions options;
    const char* cache = std::getenv("HANDSHARE_CACHE");
    options.cache_dir = cache != nullptr ? std::filesystem::path(cache)
                                         : std::filesystem::temp_directory_path() / "handshare_stiffening_cache";
    options.stiffening = on;
    SceneModels w = BuildSceneModels(s, options);
    const Eigen::Isometry3d X_WO = s.objects[0].X_WO();
    const PreparedDeformable& body = w.deformables[0];
    std::size_t top = 0;
    double best = 1e9;
    for (std::size_t i = 0; i < body.surface->nodes.size(); ++i) {
      const Eigen::Vector3d& p = body.mesh->positions_m()[static_cast<std::size_t>(body.surface->nodes[i])];
      const double d = std::abs(p.x() + 0.095) + std::abs(p.y()) - 0.01 * (X_WO.linear() * body.surface->normals[i]).z();
      if (d < best) best = d, top = i;
    }
    const Eigen::Vector3d n_W = X_WO.linear() * body.surface->normals[top];
    const Eigen::Vector3d p_W = X_WO * body.mesh->positions_m()[static_cast<std::size_t>(body.surface->nodes[top])];
    const Eigen::Vector3d along = (X_WO.linear() * Eigen::Vector3d::UnitX() -
                                   (X_WO.linear() * Eigen::Vector3d::UnitX()).dot(n_W) * n_W).normalized();
    const double R = w.world->config().fingertip_radius_m;
    std::array<Eigen::Vector3d, 5> tips;
    tips.fill(Eigen::Vector3d(5, 5, 5));
    for (int k = 0; k < 400; ++k) {
      const double sink = 0.005 * std::min(1.0, k / 200.0), slide = 0.002 * std::clamp((k - 200) / 100.0, 0.0, 1.0);
      tips[1] = p_W + (R - sink) * n_W + slide * along;
      w.world->Step(1e-3, tips);
    }
    return Eigen::Vector3d(w.world->fingers()[1].f_E_W_N);
  };
  const Eigen::Vector3d linear = press(false, true), off = press(true, false), on = press(true, true);
  ASSERT_GT(linear.norm(), 0.2);
  EXPECT_EQ(off, linear) << "a table turned off changes nothing";
  const auto samples = fem::ReadStiffeningSamples(std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "meshes" /
                                                  "triceratops_tail.stiffening.csv");
  double g_min = 1.0, g_max = 1.0;
  for (const auto& s : samples) {
    for (const auto& g : {s.g_normal, s.g_t1, s.g_t2}) {
      g_min = std::min({g_min, g[0], g[1]});
      g_max = std::max({g_max, g[0], g[1]});
    }
  }
  const double gain = on.norm() / linear.norm();
  RecordProperty("gain", std::to_string(gain));
  EXPECT_GT(std::abs(gain - 1.0), 1e-3) << "the table on changes the felt force";
  EXPECT_GE(gain, g_min - 1e-9);
  EXPECT_LE(gain, g_max + 1e-9);
  EXPECT_LT((on / on.norm() - linear / linear.norm()).norm(), 1e-9) << "a patch's force is scaled, not turned";
}

}  // namespace
}  // namespace handshare::world
