#pragma once
/// The desk: a person's hand from the mouse and keyboard of their own view (graphics_node
/// --input desk), as a haptic::Device (haptic_node --device desk). The view sends a target (hand
/// base pose, how closed each finger is) a few tens of times a second, in steps; this device
/// turns it into the smooth motion a haptic loop needs (docs/devices.md, "The desk: mouse and
/// keyboard"):
///
///   Every channel (hand base position, its rotation vector, each finger's closure) follows its
///   target through a critically damped second-order filter with time constant tau:
///     a = (r - x) / tau^2 - 2 v / tau,
///   its acceleration and speed clamped (per group, on the vector's norm), integrated by
///   semi-implicit Euler at the loop's step. A step of the target gives a motion whose speed
///   and acceleration are bounded and continuous in position: no step reaches the contact
///   forces, and a fingertip moves at most kMaxFingertipSpeed_m_per_s (the sum of the three
///   groups' bounds times their lever arms), so a 1000 N/m contact changes its force by at most
///   0.6 N per 1 ms step, well under the force safety's rate bound (2 N per step).
///
/// Fingertips from the filtered pose (DeskFingertip_H): a hand that closes around what is under
/// it, as the scripted hand's `grasp` places its fingertips (sim_hand.hpp): each fingertip on a
/// ring around a grasp centre in front of and below the palm, 72 degrees apart about the
/// vertical (the thumb towards the person), 15 degrees below the ring's centre; a finger's
/// closure c shrinks its radius from 75 mm (open) to 10 mm (closed, fingertips touching), so
/// a ball of radius r is held at c = (0.075 - r - fingertip radius) / 0.065 (the Moon's ball,
/// 40 mm: c = 0.42), and the pose is turned with the hand base.
///
/// Release: no target for input_timeout_s, or a target saying the window lost focus, makes the
/// reading invalid (valid = false): the haptic loop ramps the force to zero as for a lost device.
/// The filter keeps its state meanwhile; when input comes back the hand moves on from where it
/// was.
///
/// Threads: Post() is the bridge thread's (one producer), Read() and Command() the haptic
/// thread's; the target travels through a lock-free triple buffer. Read() never allocates,
/// locks or does I/O.
#include <array>
#include <atomic>
#include <cstdint>

#include "handshare/common/triple_buffer.hpp"
#include "handshare/haptic/device.hpp"

namespace handshare::haptic {

/// What the person at the desk asks for, as the bridge received it.
struct DeskTarget {
  std::array<double, 3> p_WH_m{0.0, 0.0, 0.0};       ///< hand base target in W [m]
  std::array<double, 4> q_WH_wxyz{1.0, 0.0, 0.0, 0.0};  ///< its orientation (unit quaternion)
  std::array<double, kFingers> closure{};             ///< 0 open .. 1 closed, thumb first
  bool focused = true;                                ///< false: release the hand
  std::uint64_t received_ns = 0;                      ///< steady clock when the bridge took it
};

struct DeskFilterConfig {
  /// Time constant of the critically damped filter [s]: a step is 90 % done after about 4 tau
  /// when no bound is reached.
  double tau_s = 0.04;
  double max_speed_m_per_s = 0.25;             ///< hand base
  double max_acceleration_m_per_s2 = 12.0;      ///< a pointer's jump: a pixel of the view in 11 ms
  double max_turn_rate_rad_per_s = 1.2;        ///< hand base rotation
  double max_turn_acceleration_rad_per_s2 = 20.0;
  double max_closure_rate_per_s = 1.5;         ///< each finger, full closure per second
  double max_closure_acceleration_per_s2 = 20.0;
  /// No target this long: the hand is released [s]. A view draws 30 frames a second, but one
  /// stalls for a few hundred ms while it loads a new world's meshes (software GL, a loaded
  /// 2-core machine): 1 s rides that out and still lets go of a hand whose view died.
  double input_timeout_s = 1.0;
};

/// The bound on any fingertip's speed the filter's bounds give: base speed + turn rate x the
/// farthest fingertip from the base (0.13 m) + closure rate x the closing path (0.065 m).
double MaxFingertipSpeed(const DeskFilterConfig& c) noexcept;

/// Where the desk puts fingertip `finger` (0 thumb .. 4 little) at closure c in [0, 1], in the
/// hand base's frame H (x right, y forward, z up) [m].
Eigen::Vector3d DeskFingertip_H(int finger, double closure) noexcept;
/// The grasp ring: its centre in H, its radius open and closed [m].
inline constexpr double kDeskGraspCentreY_m = 0.07, kDeskGraspCentreZ_m = -0.03;
inline constexpr double kDeskRingOpen_m = 0.075, kDeskRingClosed_m = 0.010;

class DeskDevice final : public Device {
 public:
  explicit DeskDevice(DeskFilterConfig config = {});

  DeviceCapabilities capabilities() const noexcept override { return {}; }
  /// The filtered hand at loop time t_s; valid only while targets arrive and the window has
  /// focus. Real-time safe.
  void Read(double t_s, DeviceReading& out) noexcept override;
  /// A desk has no force display: the forces are remembered (the view draws them from the
  /// device state). Real-time safe.
  void Command(const std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept override { last_command_ = f_E_W; }
  const char* name() const noexcept override { return "desk"; }

  /// Bridge thread: the newest target (received_ns set by the caller). Real-time safe.
  void Post(const DeskTarget& target) noexcept { targets_.Write(target); }
  /// Tests: the clock Read() compares received_ns with (default: the steady clock).
  void SetClockForTest(std::uint64_t (*now_ns)()) noexcept { now_ns_ = now_ns; }
  const std::array<Eigen::Vector3d, kFingers>& last_command() const noexcept { return last_command_; }
  const DeskFilterConfig& config() const noexcept { return config_; }

 private:
  // One filtered group: x follows r, speed and acceleration bounded on the vector's norm.
  template <int N>
  struct Channel {
    Eigen::Matrix<double, N, 1> x = Eigen::Matrix<double, N, 1>::Zero();
    Eigen::Matrix<double, N, 1> v = Eigen::Matrix<double, N, 1>::Zero();
    void Step(const Eigen::Matrix<double, N, 1>& r, double tau_s, double max_v, double max_a, double dt_s) noexcept;
  };

  DeskFilterConfig config_;
  common::TripleBuffer<DeskTarget> targets_;
  std::uint64_t (*now_ns_)() = nullptr;
  // The haptic thread's.
  DeskTarget target_{};
  bool have_target_ = false;
  double last_t_s_ = -1.0;
  Channel<3> base_;      // p_WH [m]
  Channel<3> turn_;      // rotation vector of q_WH [rad]
  Channel<kFingers> closure_;
  std::array<Eigen::Vector3d, kFingers> last_command_{};
};

}  // namespace handshare::haptic
