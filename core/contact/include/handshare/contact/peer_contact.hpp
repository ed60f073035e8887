#pragma once
/// How the other hands' contacts (PeerContact, finger_contact.hpp: a FingerContact with who
/// sent it and when it came) enter a solve: faded by their age at the solver's own step
/// (PeerFade, FadedContact), and rising again at the fade's rate (PeerWeights); PeerFadeStage is
/// that stage of a solve, which the haptic renderer and the world server both run. Plain data,
/// no middleware.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "handshare/contact/finger_contact.hpp"

namespace handshare::contact {

/// How a silent peer's contact fades out, so the others feel a ramp, not a step, when it
/// vanishes: weight 1 while its set is at most fade_after old, falling linearly to 0 at
/// lifespan (then the set is dropped). Plain data; Weight() is real-time safe.
/// fade_after is three keepalives of the sender's deadband (session/contact_deadband.hpp: a
/// still hand sends every 100 ms), so one lost keepalive plus network jitter never dims a hand
/// that is still there.
struct PeerFade {
  std::int64_t fade_after_ns = 300'000'000;
  std::int64_t lifespan_ns = 600'000'000;

  /// The weight of a contact whose set arrived `age_ns` ago (negative: fresh, 1).
  double Weight(std::int64_t age_ns) const noexcept {
    if (age_ns <= fade_after_ns) return 1.0;
    if (age_ns >= lifespan_ns) return 0.0;
    const double w = 1.0 - static_cast<double>(age_ns - fade_after_ns) / static_cast<double>(lifespan_ns - fade_after_ns);
    return w < 0.0 ? 0.0 : (w > 1.0 ? 1.0 : w);
  }
  /// The weight at `now_ns` of a set received at `received_ns` (one steady clock) [ns].
  double WeightAt(std::uint64_t now_ns, std::uint64_t received_ns) const noexcept {
    return Weight(static_cast<std::int64_t>(now_ns - received_ns));  // two's complement: earlier is negative
  }
  /// The largest change of the weight per second (the fade's slope) [1/s].
  double rate_per_s() const noexcept { return 1e9 / static_cast<double>(lifespan_ns - fade_after_ns); }
};

/// A user name's key for PeerContact::user_key: FNV-1a of its bytes, never 0.
inline std::uint64_t UserKey(std::string_view user) noexcept {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (const char ch : user) h = (h ^ static_cast<unsigned char>(ch)) * 0x100000001b3ull;
  return h == 0 ? 1 : h;
}

/// The contact as a solve takes it: u and f scaled by the fade's weight w. Whoever steps the
/// solve calls this with the weight at its own step time (PeerFade::WeightAt, PeerWeights), so
/// the fade moves with every step however late the contact was handed over. Real-time safe.
inline FingerContact FadedContact(const PeerContact& c, double w) noexcept {
  FingerContact r = c.contact;
  AsVector(r.u_O_m) *= w;
  AsVector(r.f_O_N) *= w;
  return r;
}

/// FadedContact at the fade law's weight for its age at now_ns.
inline FingerContact FadedContact(const PeerContact& c, const PeerFade& fade, std::uint64_t now_ns) noexcept {
  return FadedContact(c, fade.WeightAt(now_ns, c.received_ns));
}

/// The weights a haptic step gives the peers' contacts: the fade law's, except that a contact
/// whose weight rises again -- a newer set after its bridge stalled past fade_after (the stalls
/// seen under load are 10-570 ms), or back within kMemory_ns after it had faded out -- rises at
/// the fade's rate instead of stepping back to full weight in one step: the other hand feels
/// the same ramp coming back as going. A contact the step has not seen within kMemory_ns starts
/// at its law's weight, as a new touch does (its displacement grows from zero anyway).
/// Channels by (user_key, finger, object), in fixed arrays: real-time safe.
class PeerWeights {
 public:
  static constexpr int kMaxChannels = 48;  ///< at least haptic::kMaxRemoteContacts
  static constexpr std::uint64_t kMemory_ns = 2'000'000'000;

  /// The weight for c this step (law: the fade's weight at its age), dt_s after the last step.
  double Weight(const PeerContact& c, double law, double dt_s, double rate_per_s, std::uint64_t now_ns) noexcept {
    Channel* ch = nullptr;
    for (int i = 0; i < count_ && ch == nullptr; ++i) {
      Channel& x = channels_[static_cast<std::size_t>(i)];
      if (x.user_key == c.user_key && x.finger == c.contact.finger && x.object == c.contact.object) ch = &x;
    }
    if (ch == nullptr) {
      if (count_ == kMaxChannels) return law;
      ch = &channels_[static_cast<std::size_t>(count_++)];
      *ch = {c.user_key, c.contact.finger, c.contact.object, law, now_ns, true};
      return law;
    }
    const double w = law > ch->w ? std::min(law, ch->w + rate_per_s * dt_s) : law;
    ch->w = w;
    ch->seen_ns = now_ns;
    ch->seen = true;
    return w;
  }
  /// After the step's contacts: a channel not seen this step has weight 0 from now on, and is
  /// forgotten kMemory_ns after it was last seen.
  void EndStep(std::uint64_t now_ns) noexcept {
    for (int i = 0; i < count_;) {
      Channel& x = channels_[static_cast<std::size_t>(i)];
      if (!x.seen) x.w = 0.0;
      x.seen = false;
      if (now_ns - x.seen_ns > kMemory_ns) {
        x = channels_[static_cast<std::size_t>(--count_)];
      } else {
        ++i;
      }
    }
  }

 private:
  struct Channel {
    std::uint64_t user_key = 0;
    std::int32_t finger = 0, object = -1;
    double w = 0.0;
    std::uint64_t seen_ns = 0;
    bool seen = false;
  };
  std::array<Channel, kMaxChannels> channels_{};
  int count_ = 0;
};

/// The peer-fade stage of a solve, the one loop every process that solves the peers' contacts
/// runs (the haptic renderer at each haptic step, the world server at each tick): each contact
/// weighted by the fade law at its age at this step (PeerFade::WeightAt), rising again at the
/// fade's rate (PeerWeights), and faded (FadedContact); a contact of weight 0 leaves the solve.
/// Fixed arrays: real-time safe.
class PeerFadeStage {
 public:
  /// One step: writes the faded contacts of `peers` into `out`, in order, and, where `from` is
  /// long enough, the index in `peers` each came from. Once `out` is full, the contacts left
  /// are not weighed (their weights start afresh when they next fit).
  /// @param now_ns  this step's time, on the clock of PeerContact::received_ns [ns]
  /// @param dt_s    since the last step [s]
  /// @returns how many contacts were written.
  std::size_t Step(std::span<const PeerContact> peers, const PeerFade& fade, double dt_s, std::uint64_t now_ns,
                   std::span<FingerContact> out, std::span<std::int32_t> from = {}) noexcept {
    std::size_t n = 0;
    for (std::size_t i = 0; i < peers.size() && n < out.size(); ++i) {
      const PeerContact& c = peers[i];
      const double law = fade.WeightAt(now_ns, c.received_ns);
      if (law <= 0.0) continue;
      // A contact coming back after its set had aged into the fade (its bridge stalled) rises
      // at the fade's rate, not in one step.
      const double w = weights_.Weight(c, law, dt_s, fade.rate_per_s(), now_ns);
      if (w <= 0.0) continue;
      if (n < from.size()) from[n] = static_cast<std::int32_t>(i);
      out[n++] = FadedContact(c, w);
    }
    weights_.EndStep(now_ns);
    return n;
  }

 private:
  PeerWeights weights_;
};

}  // namespace handshare::contact
