#pragma once
/// Another hand's fingertip on an object of this process's models, as the haptic thread takes
/// it: plain, trivially copyable data with no middleware type, so the haptic renderer's
/// headers never reach the DDS layer. handshare::session turns received contact sets into
/// these (the DDS boundary); the haptic renderer and the world server turn them into
/// RemoteContacts for the solves.
#include <cstdint>

#include "handshare/contact/haptic_world.hpp"

namespace handshare::contact {

/// One peer fingertip on an object of the local models. Plain data.
struct PeerContact {
  std::int32_t hand = 0;        ///< 1, 2, ... in user-name order
  std::int32_t finger = 0;
  std::int32_t object = -1;     ///< object index of the local models (world::SceneModels)
  double p_WC_m[3] = {};        ///< contact point on the undeformed surface [m], in W
  double u_W_m[3] = {};         ///< imposed displacement (deformables), faded [m], in W
  double f_E_W_N[3] = {};       ///< force on the peer's fingertip, faded [N], in W
  double weight = 1.0;          ///< the fade factor applied (1: fresh)
};

/// The contact as the haptic world takes it. Real-time safe.
inline RemoteContact ToRemoteContact(const PeerContact& c) noexcept {
  RemoteContact r;
  r.hand = c.hand;
  r.finger = c.finger;
  r.object = c.object;
  r.p_WC_m = Eigen::Vector3d(c.p_WC_m[0], c.p_WC_m[1], c.p_WC_m[2]);
  r.u_W_m = Eigen::Vector3d(c.u_W_m[0], c.u_W_m[1], c.u_W_m[2]);
  r.f_E_W_N = Eigen::Vector3d(c.f_E_W_N[0], c.f_E_W_N[1], c.f_E_W_N[2]);
  return r;
}

}  // namespace handshare::contact
