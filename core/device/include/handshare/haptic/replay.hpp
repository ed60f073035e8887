#pragma once
/// The replay device: plays back a recorded device-state log (the CSV that `haptic_node
/// --trace` writes), so a session can be reproduced with the same hand motion. Layer 2 (device,
/// docs/ARCHITECTURE.md): no middleware.
///
/// Log format: a header line naming the columns, then one row per sample. Required columns:
/// t_s (seconds since the recording's loop start, non-decreasing), fault (0/1), and the
/// fingertips x0,y0,z0 .. x4,y4,z4 [m]. Optional: hand base hx,hy,hz [m] and qw,qx,qy,qz;
/// any other column (seq, forces) is ignored. Rows recorded during a fault replay as a fault.
#include <bit>
#include <filesystem>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "handshare/haptic/device.hpp"
#include "handshare/haptic/haptic_snapshot.hpp"

namespace handshare::haptic {

/// Writes the log format's header / one row for a haptic snapshot (what `--trace` records).
/// The last column, stamp_ns, is the host's steady clock at the sample; each row is flushed.
void WriteTraceHeader(std::ostream& out);
void WriteTraceRow(std::ostream& out, const HapticSnapshot& s);

class ReplayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ReplaySample {
  double t_s = 0.0;
  bool fault = false;
  Eigen::Vector3d p_WH = Eigen::Vector3d::Zero();
  Eigen::Vector4d q_WH_wxyz = Eigen::Vector4d(1, 0, 0, 0);
  std::array<Eigen::Vector3d, kFingers> p_WE{};
};

class ReplayLog {
 public:
  /// Parses log text; `origin` names it in errors ("FILE:LINE: what").
  static ReplayLog Parse(const std::string& text, const std::string& origin);
  static ReplayLog Load(const std::filesystem::path& file);

  const std::vector<ReplaySample>& samples() const noexcept { return samples_; }
  /// The fingers of the recorded device (the log's `fingers` column; a whole hand without one).
  FingerMask finger_mask() const noexcept { return finger_mask_; }
  double duration_s() const noexcept { return samples_.back().t_s - samples_.front().t_s; }

 private:
  std::vector<ReplaySample> samples_;  // never empty after Parse
  FingerMask finger_mask_ = kEveryFinger;
};

/// Plays a log from its first sample, interpolating linearly between samples (the log is
/// usually recorded at viewer rate, the loop runs at 1 kHz or more). A fault on either side of
/// the interval replays as a fault. After the end it holds the last sample, or starts over
/// with `loop`.
class ReplayDevice final : public Device {
 public:
  explicit ReplayDevice(ReplayLog log, bool loop = false) : log_(std::move(log)), loop_(loop) {}
  DeviceCapabilities capabilities() const noexcept override {
    DeviceCapabilities c;
    c.finger_mask = log_.finger_mask();
    c.fingers = std::popcount(static_cast<unsigned>(c.finger_mask));
    return c;
  }
  void Read(double t_s, DeviceReading& out) noexcept override;
  void Command(const std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept override {
    last_command_ = f_E_W;
  }
  const char* name() const noexcept override { return "replay"; }
  const std::array<Eigen::Vector3d, kFingers>& last_command() const noexcept { return last_command_; }

 private:
  ReplayLog log_;
  bool loop_;
  std::size_t cursor_ = 0;  // index of the sample at or before the last time read
  std::array<Eigen::Vector3d, kFingers> last_command_{};
};

}  // namespace handshare::haptic
