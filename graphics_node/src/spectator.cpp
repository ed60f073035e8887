#include "handshare/graphics/spectator.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "handshare/common/shutdown.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/render/image.hpp"
#include "handshare/render/offscreen_renderer.hpp"
#include "handshare/render/window_renderer.hpp"

namespace handshare::graphics {

namespace {

using Clock = std::chrono::steady_clock;

/// A user's hand is drawn while its device state is fresher than this.
constexpr auto kHandTimeout = std::chrono::seconds(2);

struct UserHand {
  msg::DeviceState state;
  Clock::time_point received;
};

/// Everything the view needs, updated from DDS on the render thread.
class WorldView {
 public:
  explicit WorldView(dds::Participant& p)
      : scene_reader_(dds::MakeReader<msg::SceneState>(p, dds::topics::kSceneState)),
        device_reader_(dds::MakeReader<msg::DeviceState>(p, dds::topics::kDeviceState)),
        board_reader_(dds::MakeReader<msg::MessageBoard>(p, dds::topics::kMessageBoard)) {}

  void Update() {
    dds::SampleMeta meta;
    msg::SceneState scene;
    while (scene_reader_.TakeNext(scene, meta)) {
      if (meta.valid_data) scene_ = scene;
    }
    msg::DeviceState state;
    while (device_reader_.TakeNext(state, meta)) {
      if (meta.valid_data) hands_[state.user().to_string()] = UserHand{state, Clock::now()};
    }
    msg::MessageBoard board;
    while (board_reader_.TakeNext(board, meta)) {
      if (meta.valid_data) caption_ = board.text().to_string();
    }
    for (auto it = hands_.begin(); it != hands_.end();) {
      it = (Clock::now() - it->second.received > kHandTimeout) ? hands_.erase(it) : std::next(it);
    }
  }

  bool has_scene() const { return scene_.has_value(); }
  const std::map<std::string, UserHand>& hands() const { return hands_; }

  render::SceneView Build() const {
    render::SceneView view;
    view.caption = caption_;
    if (scene_) {
      for (const auto& o : scene_->objects()) {
        const auto& p = o.p_WO_m();
        const auto& q = o.q_WO_wxyz();
        const render::Rgb rgb{o.rgb()[0], o.rgb()[1], o.rgb()[2]};
        if (o.shape() == "sphere") {
          view.spheres.push_back(render::Sphere{Eigen::Vector3d(p[0], p[1], p[2]), o.half_extent_m()[0], rgb});
        } else {
          // Boxes, and meshes until their assets are loaded here: their bounding box.
          render::Box box;
          box.p_W = Eigen::Vector3d(p[0], p[1], p[2]);
          box.half_extents_m = Eigen::Vector3d(o.half_extent_m()[0], o.half_extent_m()[1], o.half_extent_m()[2]);
          box.q_WB = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
          box.rgb = rgb;
          view.boxes.push_back(box);
        }
      }
    }
    for (const auto& [user, hand] : hands_) {
      if (hand.state.fault()) continue;  // a faulted device has no trustworthy pose
      for (int i = 0; i < 5; ++i) {
        const auto& p = hand.state.p_WE_m()[i];
        view.spheres.push_back(render::Sphere{
            Eigen::Vector3d(p[0], p[1], p[2]), hand.state.fingertip_radius_m(),
            render::Rgb{kFingertipRgb[i][0], kFingertipRgb[i][1], kFingertipRgb[i][2]}});
      }
    }
    view.grid.half_size_m = 0.4;
    view.grid.spacing_m = 0.05;
    return view;
  }

 private:
  dds::Reader<msg::SceneState> scene_reader_;
  dds::Reader<msg::DeviceState> device_reader_;
  dds::Reader<msg::MessageBoard> board_reader_;
  std::optional<msg::SceneState> scene_;
  std::map<std::string, UserHand> hands_;
  std::string caption_;
};

render::Camera DefaultCamera(int width, int height) {
  render::Camera c;
  c.eye_W = Eigen::Vector3d(0.0, -0.55, 0.45);
  c.target_W = Eigen::Vector3d(0.0, 0.05, 0.05);
  c.up_W = Eigen::Vector3d(0.0, 0.0, 1.0);
  c.fov_y_rad = 0.8;
  c.width_px = width;
  c.height_px = height;
  return c;
}

render::StereoMode ToRender(StereoOutput s) {
  switch (s) {
    case StereoOutput::kSideBySide: return render::StereoMode::kSideBySide;
    case StereoOutput::kAnaglyph: return render::StereoMode::kAnaglyph;
    case StereoOutput::kMono: break;
  }
  return render::StereoMode::kMono;
}

// The camera of a headless run, so anyone can project world points onto the frames.
void WriteCameraJson(const std::filesystem::path& file, const render::Camera& c, StereoOutput stereo) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error("cannot write " + file.string());
  out << std::setprecision(17) << "{\n"
      << "  \"convention\": \"OpenGL gluLookAt + gluPerspective, row 0 at the top\",\n"
      << "  \"eye_W_m\": [" << c.eye_W.x() << ", " << c.eye_W.y() << ", " << c.eye_W.z() << "],\n"
      << "  \"target_W_m\": [" << c.target_W.x() << ", " << c.target_W.y() << ", " << c.target_W.z() << "],\n"
      << "  \"up_W\": [" << c.up_W.x() << ", " << c.up_W.y() << ", " << c.up_W.z() << "],\n"
      << "  \"fov_y_rad\": " << c.fov_y_rad << ",\n"
      << "  \"width_px\": " << c.width_px << ",\n  \"height_px\": " << c.height_px << ",\n"
      << "  \"stereo\": \"" << (stereo == StereoOutput::kMono ? "mono" : stereo == StereoOutput::kSideBySide ? "side_by_side" : "anaglyph")
      << "\"\n}\n";
}

}  // namespace

Spectator::Spectator(SpectatorConfig config) : config_(std::move(config)) {}

int Spectator::Run() {
  const std::string name = config_.name.empty() ? "graphics-" + std::to_string(getpid()) : config_.name;
  const render::Camera camera = DefaultCamera(config_.width_px, config_.height_px);
  render::ValidateCamera(camera);

  std::filesystem::path out_dir;
  std::ofstream index;
  if (config_.headless) {
    out_dir = config_.out_dir;
    std::filesystem::create_directories(out_dir);
    WriteCameraJson(out_dir / "camera.json", camera, config_.stereo);
    // frames.csv: which hands each frame shows and where their fingertips were drawn.
    index.open(out_dir / "frames.csv");
    if (!index) throw std::runtime_error("cannot write " + (out_dir / "frames.csv").string());
    index << "frame,file,user,finger,x_m,y_m,z_m,radius_m\n" << std::setprecision(9);
  }

  dds::Participant participant(config_.where.domain_id, config_.where.session, name, config_.where.qos_file);
  dds::MemberAnnouncement member(participant, name, msg::NODE_GRAPHICS);
  WorldView world(participant);

  const auto start = Clock::now();
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / config_.fps));

  if (config_.headless) {
    render::OffscreenRenderer renderer;
    // Late joiner: the scene arrives transient-local within discovery time; do not draw an
    // empty world unless it never comes.
    while (!world.has_scene() && Clock::now() - start < config_.wait_for_scene && !common::ShutdownRequested()) {
      world.Update();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (!world.has_scene()) std::fprintf(stderr, "[graphics_node %s] no scene state received; drawing hands only\n", name.c_str());
    auto next = Clock::now();
    int written = 0;
    for (; written < config_.frames && !common::ShutdownRequested(); ++written) {
      world.Update();
      const render::ImageRgb8 image = renderer.Render(world.Build(), camera, ToRender(config_.stereo));
      char file[32];
      std::snprintf(file, sizeof(file), "frame_%05d.png", written);
      render::WritePng(out_dir / file, image);
      for (const auto& [user, hand] : world.hands()) {
        if (hand.state.fault()) continue;
        for (int i = 0; i < 5; ++i) {
          const auto& p = hand.state.p_WE_m()[i];
          index << written << "," << file << "," << user << "," << i << "," << p[0] << "," << p[1]
                << "," << p[2] << "," << hand.state.fingertip_radius_m() << "\n";
        }
      }
      next += period;
      std::this_thread::sleep_until(next);
    }
    std::printf("[graphics_node %s] wrote %d frames to %s\n", name.c_str(), written, out_dir.c_str());
    std::fflush(stdout);
    return 0;
  }

  render::WindowRenderer::Options options;
  options.title = "handshare - " + config_.where.session;
  options.width_px = config_.width_px;
  options.height_px = config_.height_px;
  options.stereo = ToRender(config_.stereo);
  options.fullscreen = config_.fullscreen;
  render::WindowRenderer window(options);
  auto next = Clock::now();
  while (!window.ShouldClose() && !common::ShutdownRequested()) {
    if (config_.where.duration.count() > 0 && Clock::now() - start >= config_.where.duration) break;
    world.Update();
    window.Render(world.Build(), camera);
    next += period;
    std::this_thread::sleep_until(next);
  }
  return 0;
}

}  // namespace handshare::graphics
