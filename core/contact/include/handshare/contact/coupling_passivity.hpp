#pragma once
/// Time-domain passivity of the couplings that cross the network: another hand's fingertip on a
/// deformable this hand also touches. The peer's contact set arrives late (one-way delay plus the
/// bridge's tick) and is held until the next one; the local solve imposes its displacement on
/// the body. A delayed displacement can put more energy into the local body -- and so into this
/// hand -- than the peer put into the body at its own end: the coupling then generates energy,
/// and enough of it makes two stiffly coupled hands oscillate.
///
/// The network as a two-port, as in the time-domain passivity approach to delayed teleoperation
/// (Ryu, Artigas and Preusche 2010: the energy that enters the channel at one end bounds what may
/// leave it at the other), with Hannaford and Ryu's (2002) observer E = sum f v dT:
///   sent      E_tx = the work the peer's fingertip did on the body at its own end, computed from
///             the samples it sent (displacement u, force on the fingertip f: the body got -f),
///             trapezoidal between samples: E_tx += -(f_k + f_{k-1}) / 2 . (u_k - u_{k-1});
///   received  E_rx = the work the same displacement, as the local solve imposes it, did on the
///             local body: E_rx += (F_prev + F_now) / 2 . (u_now - u_prev), F the local solve's
///             force of that contact's patch on the body (exact for a linear body whose contact
///             set holds through the step);
///   observer  E_obs = E_tx + E_grant - E_rx >= 0: the channel has given the local body no more
///             than the peer put in, plus what was granted at rest (below).
/// Controller (admittance type: the coupling imposes a displacement): a sample's jump is taken
/// at no more than kMaxSpeed_m_per_s, and before each step the displacement's change is scaled by alpha in [0, 1] so that the predicted E_rx stays within
/// E_tx (prediction F_prev . du + k du^2 / 2, k the largest stiffness seen at that contact);
/// after a prediction fell short (E_obs < 0 by at most that step's error) nothing that puts
/// energy in passes until the peer's samples bring more. A release always passes. What is held
/// back is taken up at later steps as the peer's samples bring energy, at the fade's rate (the
/// speed at which a peer's contact of that size fades in or out: the other hand feels a ramp,
/// not the step a fingertip's speed made), so the local displacement lags the peer's (position
/// drift) while the peer moves. Once the peer is still (its samples within 20 um of one another
/// for most of a keepalive: slower than about 0.2 mm/s), a lag left closes at the fade's rate
/// even beyond the budget, so that both copies of the body come to one shape; that energy is
/// granted (E_grant: at most the work of closing the lag, (F + k lag / 2) lag, once per stop;
/// counted into the budget) and reported. A sustained oscillation never stops, so it never gets
/// a grant (one slower than about 0.7 Hz at 0.5 mm could, at its turns). (Giving a deficit back by
/// moving the displacement out along the force was tried: with a small force the move is large,
/// and the peer's contact flickered in the local solve -- 0.1 N of force noise at the other hand.)
///
/// Plain state in fixed arrays: Admit and Observe are noexcept and allocation-free.
#include <array>
#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "handshare/contact/haptic_world.hpp"
#include "handshare/contact/peer_contact.hpp"

namespace handshare::contact {

/// What the controller has done since it was made (summed over its channels). Plain data.
struct CouplingPassivityStats {
  std::uint64_t steps = 0;           ///< steps with at least one coupling
  std::uint64_t held_back = 0;       ///< coupling-steps whose displacement change was scaled down
  double energy_sent_J = 0.0;        ///< sum of E_tx over channels that ended, plus the open ones
  double energy_received_J = 0.0;    ///< the same for E_rx
  double observer_min_J = 0.0;       ///< the lowest E_obs after any step (0 if never negative)
  double drift_max_m = 0.0;          ///< the largest |u_sent - u_imposed| where the controller acted
  double energy_granted_J = 0.0;     ///< what closing lags at rest put in beyond the peers' energy
  std::uint64_t granted_still = 0;   ///< coupling-steps that got such a grant
  std::uint64_t channels_total = 0;
};

class CouplingPassivity {
 public:
  static constexpr int kMaxChannels = 48;  ///< at least haptic::kMaxRemoteContacts

  /// enabled = false: observe only (E_tx, E_rx, E_obs are still kept), the displacements pass.
  explicit CouplingPassivity(bool enabled = true) noexcept : enabled_(enabled) {}

  bool enabled() const noexcept { return enabled_; }
  void set_enabled(bool on) noexcept { enabled_ = on; }

  /// The fastest an imposed displacement moves (the controller's rate limit on a sample's jump) [m/s].
  static constexpr double kMaxSpeed_m_per_s = 0.25;

  /// Starts a haptic step of dt_s: every channel is unseen until Admit names it again.
  /// catch_up_rate_per_s: the peer fade's slope (PeerFade::rate_per_s); a held-back displacement
  /// catches up at this rate times its size.
  void BeginStep(double dt_s, double catch_up_rate_per_s = PeerFade{}.rate_per_s()) noexcept;
  /// A peer contact on a deformable entering this step's solve (the haptic node hands in no
  /// other: ToRemoteContacts keeps the deformables' only). `sent` is the sample as it arrived
  /// (not faded: it feeds E_tx when its received_ns is new); `input` the solve's contact
  /// (faded), whose u_O_m the controller may hold back. Admitted contacts are numbered in call
  /// order for Observe.
  void Admit(const PeerContact& sent, FingerContact& input) noexcept;
  /// After the step: the local solve's force of each admitted contact's patch on its body, in
  /// admission order, in the body's frame O as the contacts' displacements
  /// (HapticWorld::remote_forces_O). Ends the step: unseen channels close.
  void Observe(std::span<const Eigen::Vector3d> force_on_body_O) noexcept;

  const CouplingPassivityStats& stats() const noexcept { return stats_; }
  /// E_obs of the channel of (user_key, finger, object), or 0 if none is open (tests).
  double observer_J(std::uint64_t user_key, std::int32_t finger, std::int32_t object) const noexcept;

 private:
  struct Channel {
    bool open = false;
    bool seen = false;
    bool deformable = false;
    std::uint64_t user_key = 0;  // the user's (PeerContact::user_key), not the hand index: that
                                 // changes as users come and go
    std::int32_t finger = 0, object = -1;
    std::uint64_t sample_ns = 0;                                 // received_ns of the last sample
    Eigen::Vector3d u_sent = Eigen::Vector3d::Zero();            // last sample (sender's)
    Eigen::Vector3d f_sent = Eigen::Vector3d::Zero();
    Eigen::Vector3d u_imposed = Eigen::Vector3d::Zero();         // what the local solve got last step
    Eigen::Vector3d du = Eigen::Vector3d::Zero();                // ... and its change in that step
    Eigen::Vector3d force = Eigen::Vector3d::Zero();             // local patch force on the body
    double e_tx = 0.0, e_rx = 0.0;
    double k = 0.0;                                              // stiffness seen [N/m]
    double e_granted = 0.0;                                      // granted at rest
    bool held = false;                                           // lagging since a hold
    Eigen::Vector3d target_prev = Eigen::Vector3d::Zero();       // the displacement asked for last step
    Eigen::Vector3d u_still = Eigen::Vector3d::Zero();           // the sample the peer is still at
    std::uint64_t still_since_ns = 0;                            // ... received then (0: none yet)
  };
  /// The open channel of (user_key, finger, object): its index, -1 if none.
  int Find(std::uint64_t user_key, std::int32_t finger, std::int32_t object) const noexcept;
  // Admit's stages.
  /// The contact's open channel, opened if it has none; nullptr if every channel is open.
  Channel* ChannelOf(const PeerContact& sent) noexcept;
  /// The peer's end: the work its samples did on its body (e_tx), once per sample, and since
  /// when it has been still.
  void ObserveSample(Channel& ch, const PeerContact& sent) noexcept;
  /// This end: target taken at a fingertip's speed (a held lag closing at the fade's rate),
  /// within the energy the channel has brought, or granted beyond it once the peer is still.
  Eigen::Vector3d Limit(Channel& ch, const Eigen::Vector3d& target, bool still) noexcept;
  /// The channel's last displacement plus the part of du whose predicted work fits the budget.
  Eigen::Vector3d ScaledToBudget(const Channel& ch, const Eigen::Vector3d& du, double budget) const noexcept;

  bool enabled_;
  double max_step_m_ = 0.0;
  double dt_s_ = 0.0;
  double catch_up_rate_per_s_ = 0.0;
  std::array<Channel, kMaxChannels> channels_{};
  std::array<std::int16_t, kMaxChannels> admitted_{};  // channel index per admitted contact, -1: none
  std::int32_t num_admitted_ = 0;
  CouplingPassivityStats stats_{};
  double closed_tx_ = 0.0, closed_rx_ = 0.0;
};

}  // namespace handshare::contact
