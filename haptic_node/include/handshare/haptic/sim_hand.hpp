#pragma once
/// A simulated hand driven by a script file, for everyone without the robot (and for every
/// test). The hand base follows minimum-jerk segments between script poses (human reaching
/// motion, Flash and Hogan 1985); the fingers open and close with a grip value in [0, 1].
///
/// Script format, one command per line, '#' starts a comment:
///   start X Y Z [grip G]        initial hand-base position [m] and grip (default 0: open)
///   move DURATION X Y Z [grip G] minimum-jerk move of the hand base (and grip) over DURATION s
///   grip DURATION G              close (G -> 1) or open (G -> 0) the hand over DURATION s
///   hold DURATION                stay still for DURATION s
/// After the last command the hand holds its final pose. Errors name the file and line.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "handshare/haptic/device.hpp"

namespace handshare::haptic {

class ScriptError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct HandPose {
  Eigen::Vector3d p_WH = Eigen::Vector3d::Zero();
  double grip = 0.0;  // 0: open, 1: closed
};

struct ScriptSegment {
  double t0_s = 0.0, t1_s = 0.0;
  HandPose from, to;
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

 private:
  HandPose start_;
  std::vector<ScriptSegment> segments_;
};

/// Fingertip positions of the simulated hand for a hand-base position and grip.
/// Hand frame: x right, y forward (fingers point +y), z up; identity orientation.
std::array<Eigen::Vector3d, kFingers> SimFingertips(const HandPose& pose) noexcept;

/// The simulated device: a scripted hand. Commands are accepted and remembered (a human hand
/// is not moved by them; issue-level plants live in their own drivers).
class SimDevice final : public Device {
 public:
  explicit SimDevice(HandScript script) : script_(std::move(script)) {}
  DeviceCapabilities capabilities() const noexcept override { return {}; }
  void Read(double t_s, DeviceReading& out) noexcept override;
  void Command(const std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept override {
    last_command_ = f_E_W;
  }
  const char* name() const noexcept override { return "sim"; }
  const std::array<Eigen::Vector3d, kFingers>& last_command() const noexcept { return last_command_; }

 private:
  HandScript script_;
  std::array<Eigen::Vector3d, kFingers> last_command_{};
};

}  // namespace handshare::haptic
