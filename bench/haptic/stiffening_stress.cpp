// stiffening_stress: the large-deformation correction under a long random press, with the
// fingertip port's passivity observer watching (issue 47, point 3; docs/fem.md, "A correction
// beyond the paper").
//
//   stiffening_stress [--steps N] [--parts tail,belly] [--nu NU] [--seed S] [--cache-dir DIR]
//     one CSV row per part and table (off, on): part,nu,table,steps,contact_share,solver_faults,
//     non_finite,mean_force_N,max_force_N,max_speed_m_per_s,observer_min_J,observer_bound_J,damped_share
//
// Each part is built as every node builds it (world::BuildSceneModels on the scene reduced to
// the part; --nu overrides its Poisson ratio, the table staying the one sampled at the scene's),
// without and with its committed stiffening table. Five fingertips, each around the point where
// fem_accuracy presses the part (bench/fem/press_parts.hpp), follow random targets (a new one
// every 0.1-0.6 s: up to 8 mm along the surface, 0-8 mm deep, one in five lifted 3 mm off it),
// each through a first-order lag of 40 ms (speeds up to about 0.2 m/s); the same targets for
// both tables (same seed). Every step's forces go through haptic::ForceSafety as the haptic
// loop runs it (clamp at 3.5 N, passivity observer and controller, rate bound) at the scripted
// fingertips. The observer W(n) (energy into the rendered world's port, per finger) may dip below
// zero only by what one step's prediction can miss, 3.5 N x the fastest fingertip speed x 1 ms
// (the bound HiroWall's 10^6-step run holds its wall to); observer_min_J is the lowest W of any
// finger over the run, observer_bound_J minus that bound.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "handshare/haptic/force_safety.hpp"
#include "handshare/world/scene_models.hpp"

#include "press_parts.hpp"

namespace {

using namespace handshare;
namespace fs = std::filesystem;
namespace hb = handshare::bench;
constexpr int kFingers = 5;

struct Result {
  long steps = 0, contact_finger_steps = 0, solver_faults = 0, non_finite = 0, damped_finger_steps = 0;
  double max_force_N = 0.0, max_speed = 0.0, observer_min_J = 0.0;
  double mean_force_N = 0.0;  // over finger-steps in contact (as rendered, before ForceSafety)
};

Result Run(const hb::Part& part, const scene::Scene& scene, const fs::path& cache, long steps, unsigned seed) {
  world::SceneModelsOptions opt;
  opt.cache_dir = cache;
  world::SceneModels models = world::BuildSceneModels(scene, opt);
  contact::HapticWorld& w = *models.world;
  const std::vector<hb::Finger> fingers = hb::FindFingers(part, kFingers);
  const double R = w.config().fingertip_radius_m;
  haptic::ForceSafety safety(haptic::ForceSafetyConfig{});
  haptic::ForceSafetyInput in;
  haptic::ForceSafetyOutput out;

  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  struct Tip {
    Eigen::Vector3d target_O, p_O;
    long next_change = 0;
  };
  std::array<Tip, kFingers> tip;
  auto above = [&](int i, double along_t1, double along_t2, double depth) {
    const hb::Finger& f = fingers[static_cast<std::size_t>(i)];
    const Eigen::Vector3d t1 = f.n_out_O.unitOrthogonal(), t2 = f.n_out_O.cross(t1);
    return Eigen::Vector3d(f.p_O + along_t1 * t1 + along_t2 * t2 + (R - depth) * f.n_out_O);
  };
  for (int i = 0; i < kFingers; ++i) tip[static_cast<std::size_t>(i)].p_O = above(i, 0, 0, -0.003);
  const double lag = 1.0 - std::exp(-1e-3 / 0.040);
  std::array<Eigen::Vector3d, kFingers> p_W;
  Result r;
  for (long k = 0; k < steps; ++k) {
    for (int i = 0; i < kFingers; ++i) {
      Tip& t = tip[static_cast<std::size_t>(i)];
      if (k >= t.next_change) {
        const double rho = 0.008 * std::sqrt(uni(rng)), phi = 2 * M_PI * uni(rng);
        const double depth = uni(rng) < 0.2 ? -0.003 : 0.008 * uni(rng);
        t.target_O = above(i, rho * std::cos(phi), rho * std::sin(phi), depth);
        t.next_change = k + 100 + static_cast<long>(500 * uni(rng));
      }
      t.p_O += lag * (t.target_O - t.p_O);
      p_W[static_cast<std::size_t>(i)] = part.X_WO * t.p_O;
    }
    const contact::StepReport rep = w.Step(1e-3, p_W);
    r.solver_faults += rep.solver_faults;
    for (int i = 0; i < kFingers; ++i) {
      const contact::FingerResult& f = w.fingers()[static_cast<std::size_t>(i)];
      if (!f.f_E_W_N.allFinite()) ++r.non_finite;
      r.contact_finger_steps += f.in_contact ? 1 : 0;
      if (f.in_contact) r.mean_force_N += f.f_E_W_N.norm();
      in.finger[static_cast<std::size_t>(i)].f_desired_E_W = f.f_E_W_N;
      in.finger[static_cast<std::size_t>(i)].p_WE = p_W[static_cast<std::size_t>(i)];
    }
    safety.Step(in, out);
    for (int i = 0; i < kFingers; ++i) {
      const haptic::FingerSafetyStatus& s = out.finger[static_cast<std::size_t>(i)];
      r.observer_min_J = std::min(r.observer_min_J, s.observed_energy_J);
      r.max_speed = std::max(r.max_speed, s.v_WE.norm());
      r.damped_finger_steps += s.damping_N_s_per_m > 0.0 ? 1 : 0;
      r.max_force_N = std::max(r.max_force_N, out.f_E_W[static_cast<std::size_t>(i)].norm());
    }
    ++r.steps;
  }
  if (r.contact_finger_steps > 0) r.mean_force_N /= static_cast<double>(r.contact_finger_steps);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  long steps = 1000000;
  std::string parts = "tail,belly";
  double nu = 0.0;
  unsigned seed = 47;
  fs::path cache = fs::temp_directory_path() / "handshare_stiffening_stress_cache";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--steps" && i + 1 < argc) {
      steps = std::atol(argv[++i]);
    } else if (a == "--parts" && i + 1 < argc) {
      parts = argv[++i];
    } else if (a == "--nu" && i + 1 < argc) {
      nu = std::atof(argv[++i]);
    } else if (a == "--seed" && i + 1 < argc) {
      seed = static_cast<unsigned>(std::atol(argv[++i]));
    } else if (a == "--cache-dir" && i + 1 < argc) {
      cache = argv[++i];
    } else {
      std::fprintf(stderr, "usage: stiffening_stress [--steps N] [--parts tail,belly] [--nu NU] [--seed S] [--cache-dir DIR]\n");
      return 2;
    }
  }
  try {
    std::printf("part,nu,table,steps,contact_share,solver_faults,non_finite,mean_force_N,max_force_N,max_speed_m_per_s,"
                "observer_min_J,observer_bound_J,damped_share\n");
    std::stringstream list(parts);
    std::string name;
    while (std::getline(list, name, ',')) {
      const hb::PartSpec* spec = nullptr;
      for (const auto& p : hb::Parts()) {
        if (p.name == name) spec = &p;
      }
      if (spec == nullptr) throw std::runtime_error("no part " + name);
      const hb::Part part = hb::PreparePart(*spec, HANDSHARE_SOURCE_ASSETS, cache, {});
      const fs::path table = hb::CommittedTable(part, spec->object_id);
      if (table.empty()) throw std::runtime_error(name + ": no committed stiffening table");
      for (bool on : {false, true}) {
        scene::Scene sc = part.scene;
        std::erase_if(sc.objects, [&](const scene::SceneObject& o) { return o.id != spec->object_id; });
        auto& d = sc.objects[0].deformable;
        if (nu > 0.0) d.nu = nu;
        d.stiffening_table_uri.clear();
        d.stiffening_table_path = on ? table : fs::path();
        const auto t0 = std::chrono::steady_clock::now();
        const Result r = Run(part, sc, cache, steps, seed);
        const double bound = -3.5 * r.max_speed * 1e-3;
        std::printf("%s,%.3f,%s,%ld,%.3f,%ld,%ld,%.4f,%.3f,%.3f,%.3e,%.3e,%.4f\n", name.c_str(), d.nu, on ? "on" : "off", r.steps,
                    static_cast<double>(r.contact_finger_steps) / (kFingers * static_cast<double>(r.steps)), r.solver_faults,
                    r.non_finite, r.mean_force_N, r.max_force_N, r.max_speed, r.observer_min_J, bound,
                    static_cast<double>(r.damped_finger_steps) / (kFingers * static_cast<double>(r.steps)));
        std::fflush(stdout);
        std::fprintf(stderr, "# %s nu %.3f table %s: %.1f s\n", name.c_str(), d.nu, on ? "on" : "off",
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stiffening_stress: %s\n", e.what());
    return 1;
  }
  return 0;
}
