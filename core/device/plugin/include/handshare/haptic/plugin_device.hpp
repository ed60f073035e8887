#pragma once
/// A lab's haptic device through a plug-in of the C ABI in handshare/device_plugin.h
/// (`haptic_node --device plugin:PATH.so[:ARGS]`, docs/devices.md). Layer 2 (device).
///
/// Open() loads the library, checks its ABI version and its stated capabilities and opens the
/// device; every failure is a std::runtime_error that names the plug-in and what is wrong.
/// Read() and Command() run on the haptic thread: they call the plug-in's read() and command()
/// once each, time them against the deadline, map D to W and check the data. A call that
/// fails, a non-finite position, a jump or an overrun makes the reading invalid (the haptic
/// loop then ramps every force to zero) and is counted by kind (faults()).
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "handshare/device_plugin.h"
#include "handshare/haptic/device.hpp"

namespace handshare::haptic {

struct PluginDeviceOptions {
  std::string path;  ///< the shared library
  std::string args;  ///< handed to the plug-in's open()
  Eigen::Vector3d origin_W = Eigen::Vector3d(0.0, -0.05, 0.12);  ///< where D's origin is in W [m]
  double scale = 1.0;  ///< p_W = origin_W + scale p_D (forces are not scaled)
  /// A read() or command() that takes longer is an overrun (a fault) [s].
  double deadline_s = 0.0005;
  /// A contact point that moves further than this between two reads has jumped (a fault) [m]:
  /// 1 cm in 1 ms is 10 m/s, far beyond a hand.
  double max_jump_m = 0.01;
  /// Parses "plugin:PATH.so[:ARGS]" (ARGS may hold further colons). Throws
  /// std::invalid_argument naming the option for anything else.
  static PluginDeviceOptions FromSpec(const std::string& spec);
};

/// Faults counted by kind since Open() (any thread may read them).
struct PluginFaults {
  std::uint64_t read_errors = 0;     ///< read() or command() returned non-zero
  std::uint64_t not_finite = 0;      ///< a position or orientation NaN or infinite
  std::uint64_t jumps = 0;           ///< a contact point moved more than max_jump_m in one read
  std::uint64_t overruns = 0;        ///< a call took longer than the deadline
  std::uint64_t total() const noexcept { return read_errors + not_finite + jumps + overruns; }
};

class PluginDevice final : public Device {
 public:
  /// Loads, checks and opens the plug-in. Throws std::runtime_error on any failure.
  static std::unique_ptr<PluginDevice> Open(const PluginDeviceOptions& options);
  ~PluginDevice() override;
  PluginDevice(const PluginDevice&) = delete;
  PluginDevice& operator=(const PluginDevice&) = delete;

  DeviceCapabilities capabilities() const noexcept override { return caps_; }
  void Read(double t_s, DeviceReading& out) noexcept override;
  void Command(const std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept override;
  const char* name() const noexcept override { return name_.c_str(); }

  /// What the plug-in stated at open (its model name, points, fingers, limits).
  const hs_device_caps& plugin_capabilities() const noexcept { return plugin_caps_; }
  PluginFaults faults() const noexcept;
  /// One line for logs: model, points and their fingers, force, workspace, rate.
  std::string Describe() const;

 private:
  PluginDevice() = default;

  PluginDeviceOptions options_;
  void* library_ = nullptr;                 // dlopen handle
  const hs_device_plugin* plugin_ = nullptr;
  hs_device* device_ = nullptr;
  hs_device_caps plugin_caps_{};
  DeviceCapabilities caps_{};
  std::string name_;
  std::int64_t deadline_ns_ = 0;
  // Haptic thread only.
  hs_device_sample sample_{};
  std::array<Eigen::Vector3d, kFingers> last_p_WE_{};
  bool have_last_ = false;
  bool command_fault_ = false;  // the last command() failed or overran: the next reading is a fault
  double f_D_N_[HS_DEVICE_MAX_POINTS][3] = {};
  // Written by the haptic thread, read by any.
  std::atomic<std::uint64_t> read_errors_{0}, not_finite_{0}, jumps_{0}, overruns_{0};
};

}  // namespace handshare::haptic
