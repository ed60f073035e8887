// graphics_bench: how long a spectator takes to draw one frame of each world at a museum
// screen's size (1920 x 1080 by default), in a window (GLFW, Mesa's software GL through GLX
// under a real or virtual X display) and headless (OSMesa).
//
// Each frame is what the spectator draws: the scene replica's objects built from the scene's
// own scene state (meshes, the start menu's open book with its pages, the labels), two users'
// hands with their fingertips, and the board's caption; the view is rebuilt every frame as the
// spectator rebuilds it. In the worlds with the triceratops' tail, the tail is pressed and its
// surface field changes every frame (a new Deformation sample), so its normals are recomputed
// as while two users press it.
//
// usage: graphics_bench [--frames N] [--warmup N] [--width W] [--height H]
//                       [--mode window|offscreen|both] [--scenes a,b,...]
// CSV on stdout: mode,scene,width_px,height_px,frames,p50_ms,p99_ms,max_ms,fps_p50
// (build: the view's rebuild; the rest is drawing and presenting it). Exit 1 with a reason on
// stderr for bad options, an unknown scene or a window that cannot be opened.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "handshare/graphics/hand_figure.hpp"
#include "handshare/graphics/scene_replica.hpp"
#include "handshare/graphics/spectator.hpp"
#include "handshare/render/offscreen_renderer.hpp"
#include "handshare/render/window_renderer.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/session/scene_state.hpp"

namespace {

using namespace handshare;
using Clock = std::chrono::steady_clock;

struct Options {
  int frames = 300;
  int warmup = 20;
  int width = 1920;
  int height = 1080;
  std::string mode = "both";
  std::vector<std::string> scenes = {"start_menu", "solar_system", "dinosaur", "microscopic", "microscopic_belly",
                                     "microscopic_horn"};
};

int PositiveInt(const std::string& option, const char* text, int max) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v < 1 || v > max) {
    throw std::invalid_argument(option + " wants a whole number from 1 to " + std::to_string(max) + ", got '" +
                                text + "'");
  }
  return static_cast<int>(v);
}

Options Parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> const char* {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--frames") o.frames = PositiveInt(a, value(), 100000);
    else if (a == "--warmup") o.warmup = PositiveInt(a, value(), 10000);
    else if (a == "--width") o.width = PositiveInt(a, value(), 8192);
    else if (a == "--height") o.height = PositiveInt(a, value(), 8192);
    else if (a == "--mode") {
      o.mode = value();
      if (o.mode != "window" && o.mode != "offscreen" && o.mode != "both") {
        throw std::invalid_argument("--mode is window, offscreen or both, not '" + o.mode + "'");
      }
    } else if (a == "--scenes") {
      o.scenes.clear();
      std::stringstream list(value());
      for (std::string name; std::getline(list, name, ',');) {
        if (!name.empty()) o.scenes.push_back(name);
      }
      if (o.scenes.empty()) throw std::invalid_argument("--scenes names no scene");
    } else {
      throw std::invalid_argument("unknown option '" + a + "' (--frames, --warmup, --width, --height, --mode, --scenes)");
    }
  }
  return o;
}

// Two users' hands over the middle of the table, fingers slightly bent, as a spectator sees them
// while two users touch something: the palms, their links and joints, and the fingertips.
void AddTwoHands(render::SceneView& view) {
  constexpr std::array<render::Rgb, 5> kFingerRgb = {render::Rgb{1.0F, 0.0F, 0.0F}, render::Rgb{0.0F, 1.0F, 0.0F},
                                                     render::Rgb{0.0F, 0.0F, 1.0F}, render::Rgb{1.0F, 1.0F, 0.0F},
                                                     render::Rgb{0.0F, 1.0F, 1.0F}};
  for (const double x : {-0.10, 0.12}) {
    Eigen::Isometry3d X_WH = Eigen::Isometry3d::Identity();
    X_WH.translation() = Eigen::Vector3d(x, -0.06, 0.13);
    std::array<Eigen::Vector3d, graphics::kFingers> p_WE;
    for (int f = 0; f < graphics::kFingers; ++f) {
      p_WE[static_cast<std::size_t>(f)] = X_WH * Eigen::Vector3d(-0.04 + 0.02 * f, f == 0 ? 0.05 : 0.10, -0.06);
    }
    figure::HandParts hand;
    hand.rgb = {0.93F, 0.78F, 0.66F};
    figure::AddHandFigure(figure::FitHandToFingertips(X_WH, p_WE), 0.008, hand);
    graphics::AddHandParts(hand, view);
    for (int f = 0; f < graphics::kFingers; ++f) {
      view.markers.push_back(render::Sphere{p_WE[static_cast<std::size_t>(f)], 0.008, kFingerRgb[static_cast<std::size_t>(f)]});
    }
  }
}

// A dent under two fingertips on the tail, deepening and easing with the frame number: every
// vertex within 3 cm of the dent's centre moves down.
msg::Deformation PressedTail(graphics::SceneReplica& world, int frame) {
  msg::Deformation d;
  d.object_id("triceratops_tail");
  d.session("bench");
  d.revision(static_cast<std::uint32_t>(frame + 1));
  d.keyframe(true);
  const graphics::DeformationField* field = world.deformation("triceratops_tail");
  const auto X_WO = world.X_WO("triceratops_tail");
  const auto* mesh = world.meshes().Get("meshes/triceratops_tail.obj").mesh.get();
  if (field == nullptr || !X_WO || mesh == nullptr) return d;
  d.surface_node_count(static_cast<std::uint32_t>(field->vertex_count()));
  const Eigen::Vector3d centre = *X_WO * Eigen::Vector3d(0.08, 0.0, 0.0);
  const double depth = 0.004 * (0.5 + 0.5 * std::sin(0.2 * frame));
  for (std::size_t v = 0; v < mesh->p_MV.size(); ++v) {
    const double r = (*X_WO * mesh->p_MV[v] - centre).norm();
    if (r > 0.03) continue;
    d.node_ids().push_back(static_cast<std::uint32_t>(v));
    const double u = -depth * (1.0 - r / 0.03);
    for (const double c : {0.0, 0.0, u}) d.u_W_m().push_back(static_cast<float>(c));
  }
  return d;
}

struct Result {
  std::vector<double> frame_ms;
  int width_px = 0;
  int height_px = 0;
};

double Percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, k == 0 ? 0 : k - 1)];
}

template <typename Draw>
Result Run(const Options& o, const scene::Scene& scene, const std::filesystem::path& assets, Draw&& draw) {
  graphics::SceneReplica world(assets, std::cerr, "[graphics_bench] ", "en");
  world.OnSceneState(session::ToSceneState(scene, "bench", 1, 0));
  for (const auto& c : scene.controls) {
    if (c.type != scene::ControlType::kBook || c.page_content.empty()) continue;
    msg::ControlState open;  // the first book open at its first page: its pictures and text drawn
    open.control_id(c.id);
    open.session("bench");
    open.scene(scene.name);
    open.index(0);
    open.engaged(true);
    world.OnControlState(open);
    break;
  }
  const bool tail = world.deformation("triceratops_tail") != nullptr;
  std::string caption;
  for (const auto& m : scene.messages) {
    if (m.language == "en") caption = m.next_action.empty() ? m.text : m.text + "\n" + m.next_action;
  }
  Result r;
  for (int frame = 0; frame < o.warmup + o.frames; ++frame) {
    const auto start = Clock::now();
    if (tail) world.OnDeformation(PressedTail(world, frame));
    render::SceneView view;
    view.caption = caption;
    world.AddObjects(view);
    AddTwoHands(view);
    draw(view, r);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (frame >= o.warmup) r.frame_ms.push_back(ms);
  }
  return r;
}

void Report(const std::string& mode, const std::string& scene, const Result& r) {
  const double p50 = Percentile(r.frame_ms, 0.50);
  const double p99 = Percentile(r.frame_ms, 0.99);
  const double max = *std::max_element(r.frame_ms.begin(), r.frame_ms.end());
  std::printf("%s,%s,%d,%d,%zu,%.2f,%.2f,%.2f,%.1f\n", mode.c_str(), scene.c_str(), r.width_px, r.height_px,
              r.frame_ms.size(), p50, p99, max, 1000.0 / p50);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = Parse(argc, argv);
    const std::filesystem::path assets = graphics::DefaultAssetsDir();
    std::printf("mode,scene,width_px,height_px,frames,p50_ms,p99_ms,max_ms,fps_p50\n");
    // One window for every scene (GLFW is set up with the first window and torn down with the
    // last: a second one after that found no display under Xvfb).
    std::optional<render::WindowRenderer> window;
    if (o.mode != "offscreen") {
      if (!render::WindowRenderer::DisplayAvailable()) {
        throw std::runtime_error("no display for the window mode (run it under xvfb-run -s '-screen 0 " +
                                 std::to_string(o.width) + "x" + std::to_string(o.height) + "x24', or --mode offscreen)");
      }
      render::WindowRenderer::Options w;
      w.title = "graphics_bench";
      w.width_px = o.width;
      w.height_px = o.height;
      w.vsync = false;  // the drawing's own time, not the display's refresh
      window.emplace(w);
    }
    std::optional<render::OffscreenRenderer> offscreen;
    if (o.mode != "window") offscreen.emplace();
    for (const std::string& name : o.scenes) {
      const scene::Scene scene = scene::LoadSceneByName(name, assets / "scenes", scene::LoadOptions{.load_meshes = false});
      const render::Camera camera = graphics::SpectatorCamera(o.width, o.height);
      if (offscreen) {
        const Result r = Run(o, scene, assets, [&](const render::SceneView& view, Result& out) {
          const render::ImageRgb8 image = offscreen->Render(view, camera);
          out.width_px = image.width_px;
          out.height_px = image.height_px;
        });
        Report("offscreen", name, r);
      }
      if (window) {
        const Result r = Run(o, scene, assets, [&](const render::SceneView& view, Result& out) {
          window->Render(view, camera);
          out.width_px = window->framebuffer_width_px();
          out.height_px = window->framebuffer_height_px();
        });
        Report("window", name, r);
      }
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "graphics_bench: %s\n", e.what());
    return 1;
  }
}
