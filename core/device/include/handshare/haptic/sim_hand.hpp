#pragma once
/// A simulated hand driven by a script file, for everyone without the robot (and for every
/// test). Every change follows a minimum-jerk profile (human reaching motion, Flash and Hogan
/// 1985). The hand is a base position plus five fingertip offsets; the offsets either come
/// from a grip value in [0, 1] (flat open hand .. closed fist) or from a task shape (poke,
/// pinch, grasp) that places fingertips at world points.
///
/// Script format, one command per line, '#' starts a comment, positions in world W [m]
/// (x right, y away from the user, z up), durations [s]:
///   start X Y Z [grip G]          initial hand-base position and grip (default 0: open)
///   await_world                   (only right after start) hold the start pose until the
///                                 session's first world is here: the script's clock starts
///                                 then (Device::OnWorldReady), not when the device starts, so a
///                                 slow discovery cannot put the hand on a control before the
///                                 control exists
///   await_world NAME              (anywhere after start) hold the current pose until the world
///                                 NAME (a scene name: solar_system, dinosaur, ...) is the one
///                                 the node has; no hold if it already is. The rest of the
///                                 script runs on from when it arrived, so a hand that pressed
///                                 a control waits for the world the control opens instead of
///                                 holding for a guessed time
///   move DUR X Y Z [grip G]       move the hand base (and grip); a shaped hand keeps its shape
///   reach DUR X Y Z               move the hand base to X Y Z with a relaxed open hand
///   grip DUR G                    close (G -> 1) or open (G -> 0) the hand
///   hold DUR                      stay still
///   poke DUR X Y Z                index fingertip centre to X Y Z, other fingers curled
///   press DUR X Y Z DEPTH         index fingertip centre to X Y Z, down by DEPTH, back up
///                                 (a third of DUR each; a push button from above)
///   pinch DUR X Y Z [WIDTH]       thumb and index fingertip centres WIDTH apart (default
///                                 0.016, touching) on either side of X Y Z along x
///   grasp DUR X Y Z RADIUS [SQ]   five fingertips on a sphere of RADIUS around X Y Z, thumb
///                                 opposite the fingers, slightly below the equator, each
///                                 fingertip centre SQ (default 0.002) inside its contact
///                                 distance RADIUS + fingertip radius (squeeze); the hand
///                                 shapes above the object, comes down beside it, closes in
///   lift DUR DZ                   the whole hand up by DZ (keeps its shape)
///   pull DUR DX DY DZ             the whole hand by DX DY DZ (a hooked finger on a lever)
///   release DUR                   fingertips move 0.03 m away from their centroid, then the
///                                 hand rises 0.05 m
/// After the last command the hand holds its final pose. Errors name the file and line.
#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "handshare/haptic/device.hpp"

namespace handshare::haptic {

class ScriptError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Fingertip radius the scripts plan with [m]: DeviceCapabilities' default.
inline constexpr double kSimFingertipRadius_m = 0.008;

struct HandPose {
  Eigen::Vector3d p_WH = Eigen::Vector3d::Zero();
  double grip = 0.0;  // 0: open, 1: closed
  /// Task shape: fingertip offsets from the hand base [m], blended in with shape_weight
  /// (0: fingertips from grip only, 1: from the shape only).
  std::array<Eigen::Vector3d, kFingers> p_HE_shape = {
      Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
      Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  double shape_weight = 0.0;
};

struct ScriptSegment {
  double t0_s = 0.0, t1_s = 0.0;
  HandPose from, to;
};

/// An await_world in a script: the script time it holds at and the world it waits for.
struct WorldWait {
  double t_s = 0.0;
  std::string world;  // empty: the session's first world (plain await_world)
  int line = 0;       // in the script, for messages
};

class HandScript {
 public:
  /// Parses script text; `origin` names it in error messages (file path).
  static HandScript Parse(const std::string& text, const std::string& origin);
  static HandScript Load(const std::filesystem::path& file);
  /// A gentle default motion around p_center when no script is given.
  static HandScript Default(const Eigen::Vector3d& p_center);

  /// Pose at time t_s (minimum-jerk within a segment, held after the end). Real-time safe.
  HandPose PoseAt(double t_s) const noexcept;
  double duration_s() const noexcept { return segments_.empty() ? 0.0 : segments_.back().t1_s; }
  /// True if the script has an await_world (ScriptClock maps device time to script time).
  bool awaits_world() const noexcept { return !waits_.empty(); }
  /// The script's await_world lines in script order (non-decreasing t_s).
  const std::vector<WorldWait>& waits() const noexcept { return waits_; }

 private:
  HandPose start_;
  std::vector<WorldWait> waits_;
  std::vector<ScriptSegment> segments_;
};

/// Script time for device time, for a script with await_world lines: the script holds at each
/// wait until its world is the node's (or, plain, until any world is here), then runs on from
/// when that world arrived. OnWorldReady is told every world the node gets (bridge thread);
/// ScriptTime is asked by one thread (the haptic thread) with non-decreasing times. Both are
/// real-time safe: world names become indices into the script's own list, and what the bridge
/// tells the haptic thread travels in lock-free atomics.
class ScriptClock {
 public:
  /// Allocates; setup only.
  explicit ScriptClock(const HandScript& script);
  ScriptClock(const ScriptClock&) = delete;
  ScriptClock& operator=(const ScriptClock&) = delete;

  /// The world `world` is the node's from device time t_s (a new revision of the same world
  /// keeps its first arrival time). Returns true the one time a call lets a script that
  /// holds at its very start begin (its first await_world, at script time 0, is satisfied).
  /// Any thread (one at a time); no allocation.
  bool OnWorldReady(double t_s, std::string_view world) noexcept;
  /// Script time at device time t_s (the script's time at a hold while it waits).
  double ScriptTime(double t_s) noexcept;

 private:
  static constexpr std::uint64_t kNoWorld = 0;
  static constexpr std::uint64_t kOtherWorld = 0xFFFF;  // a world no await_world names
  // The current world packed in one lock-free word: (arrival time in us << 16) | code, where
  // code is 1 + the index of the world's name in names_, kOtherWorld, or kNoWorld (none yet).
  std::uint64_t CodeOf(std::string_view world) const noexcept;

  std::vector<std::string> names_;      // distinct named worlds the script awaits
  std::vector<double> wait_t_s_;        // per wait: its script time
  std::vector<std::uint64_t> wait_code_;  // per wait: its world's code, kNoWorld for plain
  std::atomic<std::uint64_t> world_{0};
  std::atomic<double> first_world_s_{std::numeric_limits<double>::quiet_NaN()};
  std::atomic<bool> start_released_{false};
  // The ScriptTime thread's: the next wait and device time at script time 0.
  std::size_t next_ = 0;
  double origin_s_ = 0.0;
};

/// Fingertip positions of the simulated hand for a hand pose (grip blended with task shape).
/// Hand frame: x right, y forward (fingers point +y), z up; identity orientation.
std::array<Eigen::Vector3d, kFingers> SimFingertips(const HandPose& pose) noexcept;

/// The simulated device: a scripted hand. Commands are accepted and remembered (a human hand
/// is not moved by them; issue-level plants live in their own drivers).
class SimDevice final : public Device {
 public:
  explicit SimDevice(HandScript script) : script_(std::move(script)), clock_(script_) {}
  DeviceCapabilities capabilities() const noexcept override { return {}; }
  void Read(double t_s, DeviceReading& out) noexcept override;
  void Command(const std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept override {
    last_command_ = f_E_W;
  }
  const char* name() const noexcept override { return "sim"; }
  /// Tells the script's clock (ScriptClock) that `world` is here from t_s; true the one time
  /// this starts a script that holds at its start. Any thread.
  bool OnWorldReady(double t_s, std::string_view world) noexcept override;
  const std::array<Eigen::Vector3d, kFingers>& last_command() const noexcept { return last_command_; }

 private:
  HandScript script_;
  ScriptClock clock_;  // after script_: built from it
  std::array<Eigen::Vector3d, kFingers> last_command_{};
};

}  // namespace handshare::haptic
