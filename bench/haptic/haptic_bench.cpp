// haptic_bench: time of one HapticWorld::Step (5 fingers: collision, proxy, contact solve,
// forces) while the fingers move along trajectories that touch the object.
//
//   haptic_bench --csv [--cache-dir DIR] [--steps N] [--only NAME] [--stiffening]
//                                                                    scenario,p50_us,p99_us,lost_share rows
//     lost_share: share of the measured finger-steps whose proxy is more than 15 mm from its
//     fingertip (a proxy that stopped following); it must be 0.
//   haptic_bench [google benchmark flags]                            the same as Google Benchmarks
//
// Scenarios:
//   rigid_mesh_20k         static bumpy sphere, 20,480 triangles, radius 5 cm, friction on
//   dynamic_ball_grasp     a 5,120-triangle ball held by five fingers under Moon gravity
//   deformable_2k          cube 0.1 m, 21^3 nodes (1,961 compliance nodes), bottom fixed
//   deformable_10k         plate 0.2 x 0.2 x 0.01 m, 71 x 71 x 3 nodes (10,149 compliance nodes),
//                          clamped along one edge; float32 compliance (1.85 GB)
//   deformable_10k_patch6  the same with at most 6 patch nodes per fingertip
//   deformable_10k_2hands  the same plus a remote hand's 5 contacts in the same solve
//   deformable_2k_friction deformable_2k with fingertip friction (mu 0.8 static, 0.6 kinetic):
//                          every patch held in 3-D (docs/fem.md, "Friction")
//   deformable_tail        the dinosaur scene's triceratops tail as every node builds it
//                          (world::BuildSceneModels: its mesh through tetgen, its material and
//                          friction), five fingertips in a row where the tour presses it
//   deformable_belly       the same on the water flea's belly (microscopic_belly), where
//                          session.beating_belly presses it
// --stiffening: the large-deformation correction on (docs/fem.md, "A correction beyond the
// paper"): the tail and the belly with their committed tables (assets/meshes/*.stiffening.csv);
// the cube and the plate, which have no table of their own, with a table of samples 10 mm apart
// over their top faces whose gains are the tail table's, cycled (the same work per patch node
// as a part's own table: the gains are read per node, whatever their values).
// Fingertips: radius 8 mm; each follows its own circle over the object and presses 0..3 mm in and
// out (a few percent of the steps are free), at up to about 0.1 m/s; on the tail and the belly
// each circles 3 mm around its press point and presses 0..4.2 mm (the scripted users' depths).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "handshare/contact/haptic_world.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/mesh.hpp"
#include "handshare/fem/stiffening.hpp"
#include "handshare/world/scene_models.hpp"

#include "press_parts.hpp"

namespace {

using namespace handshare;
using namespace handshare::contact;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

fs::path g_cache_dir = HANDSHARE_HAPTIC_BENCH_CACHE;
bool g_stiffening = false;  // --stiffening

double Since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::shared_ptr<const fem::Compliance> LoadCompliance(const std::string& name, const fem::TetMesh& mesh,
                                                      const std::vector<std::int32_t>& fixed,
                                                      fem::Precision precision) {
  fs::create_directories(g_cache_dir);
  const fs::path file = g_cache_dir / (name + (precision == fem::Precision::kFloat32 ? ".f32" : ".f64") + ".compliance");
  fem::ComplianceOptions opt;
  opt.precision = precision;
  std::string note;
  fem::PrecomputeStats st;
  const auto t0 = Clock::now();
  auto progress = [&](std::int64_t d, std::int64_t t) {
    if (d == t || d % 1024 == 0) std::fprintf(stderr, "\r  %s: %lld/%lld nodes, %.0f s ", name.c_str(), static_cast<long long>(d), static_cast<long long>(t), Since(t0));
  };
  auto C = std::make_shared<const fem::Compliance>(
      fem::Compliance::LoadOrPrecompute(file, mesh, fem::Material{1e4, 0.3}, fixed, opt, progress, &note, &st));
  std::fprintf(stderr, "\n# %s: %d compliance nodes, %s (%.1f s%s)\n", name.c_str(), C->num_nodes(), note.c_str(),
               Since(t0), st.total_s > 0 ? ", precomputed" : ", from cache");
  return C;
}

struct Scenario {
  std::string name;
  std::unique_ptr<HapticWorld> world;
  // Fingertip trajectory: circle centre, radius, surface point/normal model.
  std::function<std::array<Eigen::Vector3d, kFingers>(int)> tips;
  std::vector<FingerContact> remote;
  std::function<void(int)> before_step = [](int) {};
};

// Fingertip i at step k on a flat top face z = top over [x0, x0 + L] x [y0, y0 + L].
std::array<Eigen::Vector3d, kFingers> FlatTips(int k, double x0, double y0, double L, double top) {
  std::array<Eigen::Vector3d, kFingers> p;
  const double t = k * 1e-3;
  for (int i = 0; i < kFingers; ++i) {
    const double ang = 0.8 * t + 2.0 * M_PI * i / kFingers;
    const double rad = 0.18 * L + 0.03 * L * i;
    const double depth = 0.0015 + 0.0017 * std::sin(3.0 * t + i);  // -0.2 .. 3.2 mm
    p[static_cast<std::size_t>(i)] = Eigen::Vector3d(x0 + 0.5 * L + rad * std::cos(ang), y0 + 0.5 * L + rad * std::sin(ang),
                                                     top + 0.008 - depth);
  }
  return p;
}

std::unique_ptr<Scenario> MakeRigid() {
  auto s = std::make_unique<Scenario>();
  s->name = "rigid_mesh_20k";
  s->world = std::make_unique<HapticWorld>();
  auto mesh = std::make_shared<TriMesh>(MakeBumpySphere(0.05, 0.003, 5));
  s->world->AddStatic(Shape::Mesh(mesh), RigidMaterial{1000.0, 2.0, 0.6, 0.5}, Eigen::Isometry3d::Identity());
  s->world->Init();
  s->tips = [](int k) {
    std::array<Eigen::Vector3d, kFingers> p;
    const double t = k * 1e-3;
    for (int i = 0; i < kFingers; ++i) {
      // A point sliding over the sphere (about 0.1 m/s), pressing 0..3 mm beyond the bumps.
      const double th = 0.9 + 0.25 * i + 0.3 * std::sin(0.7 * t + i);
      const double ph = 2.0 * t + 1.2 * i;
      const Eigen::Vector3d u(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      const double depth = 0.0015 + 0.0017 * std::sin(3.0 * t + i);
      p[static_cast<std::size_t>(i)] = u * (0.05 + 0.008 - depth);
    }
    return p;
  };
  return s;
}

std::unique_ptr<Scenario> MakeBall() {
  auto s = std::make_unique<Scenario>();
  s->name = "dynamic_ball_grasp";
  WorldConfig cfg;
  cfg.gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -kMoonGravity_m_per_s2);
  s->world = std::make_unique<HapticWorld>(cfg);
  BodyProperties body;
  body.mass_kg = 0.2;
  body.linear_damping_N_s_per_m = 2.0;
  body.angular_damping_N_m_s = 0.002;
  const ObjectId ball = s->world->AddDynamic(Shape::Sphere(0.03, 4), RigidMaterial{1000.0, 2.0, 1.0, 0.8}, body,
                                             Eigen::Isometry3d::Identity());
  s->world->Init();
  // The scene holds the ball while the hand closes (0.2 s), then lets go.
  HapticWorld* w = s->world.get();
  s->before_step = [w, ball](int k) {
    if (k <= 200) w->SetPose(ball, Eigen::Isometry3d::Identity());
  };
  s->tips = [](int k) {
    const std::array<Eigen::Vector3d, kFingers> dir = {Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d(1, 0.3, 0.3),
                                                       Eigen::Vector3d(1, -0.3, 0.3), Eigen::Vector3d(1, 0.3, -0.3),
                                                       Eigen::Vector3d(1, -0.3, -0.3)};
    const std::array<double, kFingers> depth = {0.00184, 0.0005, 0.0005, 0.0005, 0.0005};
    std::array<Eigen::Vector3d, kFingers> p;
    const double close = std::min(1.0, k / 200.0);
    const Eigen::Vector3d hand(0.0, 0.0, 0.01 * std::sin(1e-3 * k));  // the hand lifts and lowers
    for (int i = 0; i < kFingers; ++i) {
      const double h = 0.005 - (0.005 + depth[static_cast<std::size_t>(i)]) * close;
      p[static_cast<std::size_t>(i)] = hand + dir[static_cast<std::size_t>(i)].normalized() * (0.03 + 0.008 + h);
    }
    return p;
  };
  return s;
}

// A table for a block with no table of its own (--stiffening): samples 10 mm apart over its top
// face z = top, normal +z, with the tail table's gains cycled over them.
std::shared_ptr<const fem::StiffeningTable> BlockTable(const fem::TetMesh& mesh, double L, double top) {
  const auto tail = fem::ReadStiffeningSamples(fs::path(HANDSHARE_SOURCE_ASSETS) / "meshes" / "triceratops_tail.stiffening.csv");
  std::vector<fem::StiffeningSample> samples;
  std::size_t k = 0;
  for (double x = 0.0; x <= L + 1e-9; x += 0.01) {
    for (double y = 0.0; y <= L + 1e-9; y += 0.01) {
      fem::StiffeningSample smp = tail[k++ % tail.size()];
      smp.p_m = Eigen::Vector3d(x, y, top);
      smp.n_out = Eigen::Vector3d::UnitZ();
      smp.axis = Eigen::Vector3d::UnitX();
      samples.push_back(smp);
    }
  }
  return std::make_shared<const fem::StiffeningTable>(mesh, fem::ExtractSurface(mesh), samples);
}

std::unique_ptr<Scenario> MakeDeformable(const std::string& name, bool plate, int max_patch, bool two_hands,
                                         double mu_static = 0.0, double mu_kinetic = 0.0) {
  auto s = std::make_unique<Scenario>();
  s->name = name;
  WorldConfig cfg;
  cfg.max_hands = 2;
  s->world = std::make_unique<HapticWorld>(cfg);
  std::shared_ptr<fem::TetMesh> mesh;
  std::vector<std::int32_t> fixed;
  double L = 0.1, top = 0.1;
  if (plate) {
    mesh = std::make_shared<fem::TetMesh>(fem::MakeBoxMesh({0.2, 0.2, 0.01}, {70, 70, 2}));
    fixed = fem::NodesOnPlane(*mesh, 0, 0.0);
    L = 0.2;
    top = 0.01;
  } else {
    mesh = std::make_shared<fem::TetMesh>(fem::MakeBoxMesh({0.1, 0.1, 0.1}, {20, 20, 20}));
    fixed = fem::NodesOnPlane(*mesh, 2, 0.0);
  }
  static std::shared_ptr<const fem::Compliance> plate_c, cube_c;
  auto& C = plate ? plate_c : cube_c;
  if (!C) {
    C = LoadCompliance(plate ? "plate71x71x3" : "cube21", *mesh, fixed,
                       plate ? fem::Precision::kFloat32 : fem::Precision::kFloat64);
  }
  DeformableDesc d;
  d.mesh = mesh;
  d.compliance = C;
  d.max_patch_nodes = max_patch;
  d.mu_static = mu_static;
  d.mu_kinetic = mu_kinetic;
  if (g_stiffening) d.stiffening = BlockTable(*mesh, L, top);
  s->world->AddDeformable(d);
  s->world->Init();
  s->tips = [L, top](int k) { return FlatTips(k, 0.0, 0.0, L, top); };
  if (two_hands) {
    // A remote hand's five fingertips pressing 1.5 mm at fixed points, as its ContactSet says.
    for (int i = 0; i < kFingers; ++i) {
      const Eigen::Vector3d p_C(0.15 * L + 0.17 * L * i, 0.9 * L, top);
      s->remote.push_back(ContactInObjectFrame(d.X_WO, i, 0, p_C, p_C + Eigen::Vector3d(0, 0, 0.008 - 0.0015),
                                               Eigen::Vector3d(0, 0, -0.0015), Eigen::Vector3d(0, 0, 0.2)));
    }
  }
  return s;
}

// A scene's part as every node builds it (world::BuildSceneModels), five fingertips in the row
// fem_accuracy presses it with (bench/fem/press_parts.hpp), each circling 3 mm around its press
// point and pressing -0.2..4.2 mm along the normal there.
std::unique_ptr<Scenario> MakePart(const std::string& name, const std::string& part_name) {
  namespace hb = handshare::bench;
  const hb::PartSpec* spec = nullptr;
  for (const auto& p : hb::Parts()) {
    if (p.name == part_name) spec = &p;
  }
  const hb::Part part = hb::PreparePart(*spec, HANDSHARE_SOURCE_ASSETS, g_cache_dir / "parts", {});
  scene::Scene sc = part.scene;
  std::erase_if(sc.objects, [&](const scene::SceneObject& o) { return o.id != spec->object_id; });
  sc.objects[0].deformable.stiffening_table_uri.clear();
  sc.objects[0].deformable.stiffening_table_path.clear();
  if (g_stiffening) {
    sc.objects[0].deformable.stiffening_table_path = hb::CommittedTable(part, spec->object_id);
    if (sc.objects[0].deformable.stiffening_table_path.empty()) throw std::runtime_error(part_name + ": no committed table");
  }
  world::SceneModelsOptions opt;
  opt.cache_dir = g_cache_dir / "parts";
  world::SceneModels models = world::BuildSceneModels(sc, opt);
  auto s = std::make_unique<Scenario>();
  s->name = name;
  s->world = std::move(models.world);
  const std::vector<hb::Finger> fingers = hb::FindFingers(part, kFingers);
  const Eigen::Isometry3d X_WO = part.X_WO;
  const double R = s->world->config().fingertip_radius_m;
  s->tips = [fingers, X_WO, R](int k) {
    std::array<Eigen::Vector3d, kFingers> p;
    const double t = k * 1e-3;
    for (int i = 0; i < kFingers; ++i) {
      const hb::Finger& f = fingers[static_cast<std::size_t>(i)];
      const Eigen::Vector3d t1 = f.n_out_O.unitOrthogonal(), t2 = f.n_out_O.cross(t1);
      const double ang = 0.8 * t + 2.0 * M_PI * i / kFingers;
      const double depth = 0.002 + 0.0022 * std::sin(3.0 * t + i);  // -0.2 .. 4.2 mm
      p[static_cast<std::size_t>(i)] =
          X_WO * (f.p_O + 0.003 * (std::cos(ang) * t1 + std::sin(ang) * t2) + (R - depth) * f.n_out_O);
    }
    return p;
  };
  return s;
}

std::unique_ptr<Scenario> Make(const std::string& name) {
  if (name == "rigid_mesh_20k") return MakeRigid();
  if (name == "dynamic_ball_grasp") return MakeBall();
  if (name == "deformable_2k") return MakeDeformable(name, false, 16, false);
  if (name == "deformable_10k") return MakeDeformable(name, true, 16, false);
  if (name == "deformable_10k_patch6") return MakeDeformable(name, true, 6, false);
  if (name == "deformable_10k_2hands") return MakeDeformable(name, true, 16, true);
  if (name == "deformable_2k_friction") return MakeDeformable(name, false, 16, false, 0.8, 0.6);
  if (name == "deformable_tail") return MakePart(name, "tail");
  if (name == "deformable_belly") return MakePart(name, "belly");
  return nullptr;
}

const char* kNames[] = {"rigid_mesh_20k", "dynamic_ball_grasp", "deformable_2k", "deformable_10k",
                        "deformable_10k_patch6", "deformable_10k_2hands", "deformable_2k_friction",
                        "deformable_tail", "deformable_belly"};

struct Stats {
  double p50_us, p99_us, max_us, mean_us, contact_fraction, mean_patch;
  double lost_share;                        // finger-steps with a proxy > kLostDistance_m from its fingertip
  std::array<long, kFingers> lost_steps{};  // per finger
  double max_gap_m = 0.0;                   // largest proxy-fingertip distance seen
};

// A proxy farther than this from its fingertip is lost: the fingertips press at most 3.2 mm
// (3.5 mm with the bumps' slope and friction's tangential offset), so a healthy proxy is never
// near 15 mm away.
constexpr double kLostDistance_m = 0.015;

Stats Run(Scenario& s, int steps) {
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(steps));
  long contacts = 0, patch = 0, lost = 0;
  std::array<long, kFingers> lost_steps{};
  double max_gap = 0.0;
  for (int k = 0; k < 500; ++k) {  // warm-up (and the ball grasp closes)
    s.before_step(k);
    s.world->Step(1e-3, s.tips(k), s.remote);
  }
  for (int k = 500; k < 500 + steps; ++k) {
    const auto tips = s.tips(k);
    s.before_step(k);
    const auto t0 = Clock::now();
    s.world->Step(1e-3, tips, s.remote);
    const auto t1 = Clock::now();
    benchmark::DoNotOptimize(s.world->fingers().data());
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    for (const FingerResult& r : s.world->fingers()) {
      contacts += r.in_contact ? 1 : 0;
      patch += r.patch_nodes;
    }
    for (int i = 0; i < kFingers; ++i) {  // every proxy of the finger, touching or not
      double gap = 0.0;
      for (ObjectId o = 0; o < s.world->num_objects(); ++o) {
        Eigen::Vector3d p;
        if (s.world->proxy_W(i, o, p)) gap = std::max(gap, (p - tips[static_cast<std::size_t>(i)]).norm());
      }
      max_gap = std::max(max_gap, gap);
      if (gap > kLostDistance_m) {
        ++lost;
        ++lost_steps[static_cast<std::size_t>(i)];
      }
    }
  }
  double sum_us = 0.0;
  for (double u : us) sum_us += u;
  std::sort(us.begin(), us.end());
  auto q = [&](double f) { return us[static_cast<std::size_t>(f * static_cast<double>(us.size() - 1))]; };
  return {q(0.5), q(0.99), us.back(), sum_us / static_cast<double>(us.size()), static_cast<double>(contacts) / (kFingers * steps),
          contacts ? static_cast<double>(patch) / static_cast<double>(contacts) : 0.0,
          static_cast<double>(lost) / (kFingers * steps), lost_steps, max_gap};
}

void BM_HapticStep(benchmark::State& state, const char* name) {
  static std::map<std::string, std::unique_ptr<Scenario>> cache;
  auto& s = cache[name];
  if (!s) s = Make(name);
  static std::map<std::string, int> step;
  int& k = step[name];
  for (auto _ : state) {
    s->before_step(k);
    s->world->Step(1e-3, s->tips(k++), s->remote);
    benchmark::DoNotOptimize(s->world->fingers().data());
  }
}

}  // namespace

int main(int argc, char** argv) {
  bool csv = false;
  int steps = 20000;
  std::string only;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--csv") {
      csv = true;
    } else if (a == "--cache-dir" && i + 1 < argc) {
      g_cache_dir = argv[++i];
    } else if (a == "--steps" && i + 1 < argc) {
      steps = std::max(100, std::atoi(argv[++i]));
    } else if (a == "--only" && i + 1 < argc) {
      only = argv[++i];
    } else if (a == "--stiffening") {
      g_stiffening = true;
    } else {
      rest.push_back(argv[i]);
    }
  }
  try {
    if (csv) {
      std::printf("scenario,p50_us,p99_us,lost_share\n");
      for (const char* name : kNames) {
        if (!only.empty() && only != name) continue;
        auto s = Make(name);
        const Stats st = Run(*s, steps);
        std::printf("%s,%.2f,%.2f,%.4f\n", name, st.p50_us, st.p99_us, st.lost_share);
        std::fflush(stdout);
        std::fprintf(stderr, "# %s: mean %.1f us, max %.1f us, fingers in contact %.0f%% of finger-steps, mean patch %.1f nodes, %d steps\n",
                     name, st.mean_us, st.max_us, 100.0 * st.contact_fraction, st.mean_patch, steps);
        std::fprintf(stderr, "# %s: proxy > %.0f mm from its fingertip in %.2f%% of finger-steps (per finger %ld %ld %ld %ld %ld), largest gap %.2f mm\n",
                     name, 1e3 * kLostDistance_m, 100.0 * st.lost_share, st.lost_steps[0], st.lost_steps[1], st.lost_steps[2],
                     st.lost_steps[3], st.lost_steps[4], 1e3 * st.max_gap_m);
      }
      return 0;
    }
    for (const char* name : kNames) {
      benchmark::RegisterBenchmark((std::string("HapticStep/") + name).c_str(), BM_HapticStep, name)
          ->Unit(benchmark::kMicrosecond);
    }
    int n = static_cast<int>(rest.size());
    benchmark::Initialize(&n, rest.data());
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptic_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
