#pragma once
/// The graphics node: a spectator's view of a session. Reads the scene state (objects drawn
/// with their meshes), object states (poses of moving and grasped objects), deformations, every
/// user's device state and the message board over DDS and draws them: headless into PNG files,
/// or in a window where a display exists (large screen, mono or stereo). See SceneReplica.
#include <chrono>
#include <filesystem>
#include <string>

#include "handshare/common/session_options.hpp"
#include "handshare/graphics/hand_figure.hpp"

namespace handshare::graphics {

enum class StereoOutput { kMono, kSideBySide, kAnaglyph };

struct SpectatorConfig {
  common::SessionOptions where;  // domain, session, duration, QoS file
  std::string name;                  // member name; "" = graphics-<pid>
  bool headless = false;
  int frames = 0;                    // headless: frames to write (required > 0)
  std::string out_dir;               // headless: where frame_NNNNN.png go
  int width_px = 640, height_px = 480;
  double fps = 30.0;
  StereoOutput stereo = StereoOutput::kMono;
  bool fullscreen = false;
  std::string language = "en";       // the board's language shown: en or ja
  std::string view_user;             // "" = the spectator's camera; else that user's own view (eye)
  UserEye eye;                       // the user's eye relative to their hand base
  /// A user's view in a window only: the person's mouse and keyboard drive that user's hand
  /// (DeskControl, sent as DeskInput to haptic_node --device desk), and the view shows what the
  /// hand feels (each fingertip's force as colour and arrow, the held weight, the key mapping).
  bool desk_input = false;
  bool gamepad_input = false;  // with desk_input: the hand follows the gamepad, not the window's mouse and keys
  std::chrono::duration<double> wait_for_scene{5.0};  // headless: wait this long for the scene
  /// No scene from the world server this long after joining: join again with a new participant
  /// (a secured handshake that never finished; docs/security.md); 0: never.
  std::chrono::duration<double> rejoin_after{15.0};
  std::filesystem::path assets_dir;  // mesh uris are relative to it; "" = DefaultAssetsDir()
  std::filesystem::path deformation_out;  // "" = none; else at exit: SceneReplica::WriteDeformationJson
  /// "" = none; else at exit, JSON: {"scene", "revision",
  /// "board": {"message_id", "language", "text", "next_action"},
  /// "objects": {id: {"p_WO_m", "q_WO_wxyz", "from": "object_state" | "scene_state"}}}: the
  /// scene, board and poses the spectator shows (a late joiner's check).
  std::filesystem::path state_out;
  /// "" = none; else, in a window, a CSV row per frame shown: frame, t_ns (steady clock,
  /// CLOCK_MONOTONIC, once the frame is swapped to the screen), the view user's hand base
  /// hand_x_m, hand_y_m, hand_z_m as drawn (blank without a hand), and where the world's origin
  /// lands in the frame, anchor_x_px, anchor_y_px (a user's view follows the hand: the scene
  /// moves on the screen when the hand does), and the stamp of the hand's device state drawn,
  /// hand_stamp_ns (the haptic loop's steady clock: the same clock on one machine), and how
  /// long the frame took from its start to the swap, draw_ms.
  /// bench/graphics/motion_to_photon.py reads it. A spectator logs the hand whose state is the
  /// newest (bench/graphics/spectator_to_photon.py).
  std::filesystem::path frame_log;
  /// A window draws a new state of a hand (a user's view: their own; a spectator: anyone's) as
  /// it arrives, from half a period after the last frame began (up to twice fps); false: only
  /// at the frame clock (fps), for a machine that cannot spare the frames.
  bool frames_follow_states = true;
};

/// $HANDSHARE_ASSETS if set, else the installed or source tree's assets (common::AssetsDir, as
/// core/scene finds scenes).
std::filesystem::path DefaultAssetsDir();

/// The spectator's camera over the table (from the visitors' side, above it), width x height px.
render::Camera SpectatorCamera(int width, int height);

class Spectator {
 public:
  explicit Spectator(SpectatorConfig config);
  int Run();

 private:
  SpectatorConfig config_;
};

/// Fingertip colours, thumb first: red, green, blue, yellow, cyan (as in the paper's figures).
inline constexpr float kFingertipRgb[5][3] = {
    {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, {1.0f, 1.0f, 0.0f}, {0.0f, 1.0f, 1.0f}};

}  // namespace handshare::graphics
