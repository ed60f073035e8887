// graphics_node: a spectator's view of a session, headless (PNG frames) or in a window.

#include <sys/resource.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "handshare/node/node_main.hpp"
#include "handshare/graphics/spectator.hpp"
#include "handshare/render/window_renderer.hpp"

int main(int argc, char** argv) {
  using handshare::common::OptionError;
  handshare::common::Options options(
      "graphics_node", "Spectates a handshare session: the scene and every user's hand and five fingertips "
                       "(red, green, blue, yellow, cyan), headless into PNG frames or in a window.");
  handshare::node::DeclareSessionOptions(options);
  options.Value("name", "NAME", "member name (default graphics-<pid>)", "")
      .Flag("headless", "render offscreen (software GL) into PNG files, no display needed")
      .Value("frames", "N", "headless: number of frames to write", "0")
      .Value("out", "DIR", "headless: output folder for frame_NNNNN.png, camera.json, frames.csv", "")
      .Value("width", "PX", "image or window width", "640")
      .Value("height", "PX", "image or window height", "480")
      .Value("fps", "HZ", "frames per second", "30")
      .Value("rejoin-after", "SEC",
             "join again with a new participant when no scene came from the world server this long after "
             "joining (a secured join whose handshake never finished; 0: never)", "15")
      .Value("stereo", "MODE", "mono, side-by-side or anaglyph", "mono")
      .Value("language", "en|ja", "the message board's language shown", "en")
      .Value("frame-pacing", "states|clock",
             "window: draw a hand's new state as it arrives (states: up to twice --fps) or only at --fps (clock)",
             "states")
      .Value("view", "spectator|user:NAME",
             "whose view: the spectator's, or a user's own (from their eye, following their hand)", "spectator")
      .Value("eye", "X,Y,Z", "user view: the eye in the hand base's frame [m] (fingers along +y, up +z)",
             "0,-0.30,0.25")
      .Value("input", "none|desk|gamepad",
             "desk: with --view user:NAME in a window, the mouse and keyboard drive NAME's hand "
             "(haptic_node --device desk --user NAME; mapping in docs/devices.md); gamepad: the first game "
             "controller does, and rumbles with what the hand feels", "none")
      .Flag("fullscreen", "window: full screen on the primary monitor (large screen)")
      .Value("assets", "DIR", "folder that the scene's mesh paths are relative to",
             handshare::graphics::DefaultAssetsDir().string())
      .Value("deformation-out", "FILE",
             "at exit, write the deformations received as JSON: {object_id: {revision, "
             "vertex_count, u_W_m: {vertex: [x, y, z]}}} (non-zero vertices only)", "")
      .Value("state-out", "FILE",
             "at exit, write what the spectator shows as JSON: scene, revision, board {message_id, text}, "
             "objects {id: {p_WO_m, q_WO_wxyz, from}}", "")
      .Value("nice", "N",
             "CPU priority (Linux nice, -20..19; below 0 needs the right to raise it). 10 makes a spectator's screen "
             "give way on a machine without room, so that the haptic nodes' bridges and the world server keep their "
             "rates (docs/network.md, \"A busy machine\": a screen starved so may be aborted by Fast DDS 2.9.1, "
             "hence not the default: without it the screen keeps the priority it was started with)", "")
      .Value("frame-log", "FILE",
             "window: a CSV row per frame shown (frame, t_ns, the view user's hand base, where the world's "
             "origin lands in pixels): what motion-to-photon is measured from", "");
  return handshare::node::RunNodeMain(argc, argv, options, [](const auto& o) {
    handshare::graphics::SpectatorConfig c;
    c.where = handshare::node::ReadSessionOptions(o);
    c.name = o.GetString("name");
    c.headless = o.FlagSet("headless");
    c.width_px = static_cast<int>(o.GetInt("width", 16, 8192));
    c.height_px = static_cast<int>(o.GetInt("height", 16, 8192));
    c.fps = o.GetDouble("fps", 0.1, 240.0);
    c.rejoin_after = std::chrono::duration<double>(o.GetDouble("rejoin-after", 0.0, 3600.0));
    c.fullscreen = o.FlagSet("fullscreen");
    c.assets_dir = o.GetString("assets");
    c.deformation_out = o.GetString("deformation-out");
    c.state_out = o.GetString("state-out");
    c.frame_log = o.GetString("frame-log");
    c.language = o.GetChoice("language", {"en", "ja"});
    c.frames_follow_states = o.GetChoice("frame-pacing", {"states", "clock"}) == "states";
    const std::string view = o.GetString("view");
    if (view.rfind("user:", 0) == 0 && view.size() > 5) {
      c.view_user = view.substr(5);
    } else if (view != "spectator") {
      throw OptionError("option --view: '" + view + "' is not spectator or user:NAME");
    }
    const std::string input = o.GetChoice("input", {"none", "desk", "gamepad"});
    c.desk_input = input != "none";
    c.gamepad_input = input == "gamepad";
    if (c.desk_input && c.view_user.empty()) {
      throw OptionError("option --input " + input + " needs --view user:NAME (the hand it drives)");
    }
    if (c.desk_input && c.headless) throw OptionError("option --input " + input + " needs a window (not --headless)");
    const auto eye = o.GetVector3("eye", 10.0);  // metres, each within 10 m
    c.eye.eye_H = Eigen::Vector3d(eye[0], eye[1], eye[2]);
    const std::string stereo = o.GetString("stereo");
    if (stereo == "mono") c.stereo = handshare::graphics::StereoOutput::kMono;
    else if (stereo == "side-by-side") c.stereo = handshare::graphics::StereoOutput::kSideBySide;
    else if (stereo == "anaglyph") c.stereo = handshare::graphics::StereoOutput::kAnaglyph;
    else throw OptionError("option --stereo: '" + stereo + "' is not mono, side-by-side or anaglyph");
    if (c.headless) {
      if (!o.Has("frames")) throw OptionError("option --frames N is required with --headless");
      c.frames = static_cast<int>(o.GetInt("frames", 1, 1000000));
      c.out_dir = o.GetString("out");
      if (c.out_dir.empty()) throw OptionError("option --out DIR is required with --headless");
    } else if (!handshare::render::WindowRenderer::DisplayAvailable()) {
      throw OptionError("no display is reachable for a window: use --headless --frames N --out DIR");
    }
    // Before any thread starts (DDS, the software rasterizer's): Linux keeps a nice value per
    // thread, and new threads take their creator's.
    if (!o.GetString("nice").empty()) {
      const int nice = static_cast<int>(o.GetInt("nice", -20, 19));
      if (setpriority(PRIO_PROCESS, 0, nice) != 0) {
        throw OptionError("option --nice " + std::to_string(nice) + ": " + std::strerror(errno));
      }
    }
    return handshare::graphics::Spectator(c).Run();
  });
}
