#pragma once
/// What the haptic loop asks of the world each step: the force each fingertip should feel.
/// Implemented by the node's scene (rigid and deformable contact, controls); the loop owns
/// safety (clamp, rate bound, passivity, fault ramp) after it.
#include <array>
#include <cstdint>

#include "handshare/haptic/device.hpp"

namespace handshare::haptic {

class ForceRenderer {
 public:
  virtual ~ForceRenderer() = default;
  /// Desired fingertip forces f_E_W [N] for a valid reading at time t_s, step dt_s [s];
  /// now_ns is the step's time on the steady clock (common::SteadyNowNs, the loop's stamp),
  /// against which the age of data received from other threads is taken.
  /// Real-time: noexcept, no allocation, no locks, no I/O.
  virtual void Render(double t_s, double dt_s, std::uint64_t now_ns, const DeviceReading& reading,
                      std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept = 0;
  /// The device is faulted this step (no trustworthy fingertips): release every contact.
  virtual void ReleaseAll() noexcept {}
};

}  // namespace handshare::haptic
