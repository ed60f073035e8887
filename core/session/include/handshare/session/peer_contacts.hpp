#pragma once
/// The other hands' contacts, as every process that shares a world reads them: the newest
/// ContactSet of each user, turned into contacts on this process's models of the scene
/// (world::SceneModels), so a haptic node and the world server put the same peers' fingertips
/// into the same FEM solves. Not real-time (the bridge thread or the server's tick).
///
/// A vanished peer does not stop pressing at once: its last contact set fades out. From
/// fade_after on, its imposed displacements and forces are scaled down linearly to zero at
/// lifespan, then the set is dropped, so the others feel a ramp, not a step (issue: "a member
/// that vanishes loses its contacts within 2 s, smoothly, without a force jump for the others").
/// A peer that lifts its hand sends one last set with no active finger: that ends at once (its
/// own fingertips already came off smoothly).
///
/// The contacts come out as received, each with its set's arrival time; whoever steps a solve
/// fades them at its own step time (contact::FadedContact with fade()): the world server at
/// its tick, the haptic node on its haptic thread, so a stalled bridge thread cannot hold the
/// weight still and then step it.
#include <chrono>
#include <cstdint>
#include <map>
#include <string>

#include "handshare/contact/peer_contact.hpp"
#include "handshare/dds/contact_codec.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/world/scene_models.hpp"

namespace handshare::session {

struct PeerContactsConfig {
  std::chrono::nanoseconds fade_after = std::chrono::milliseconds(300);  // contact::PeerFade's defaults
  std::chrono::nanoseconds lifespan = std::chrono::milliseconds(600);
};

using contact::PeerContact;  // handshare/contact/finger_contact.hpp: the plain, middleware-free type

class PeerContacts {
 public:
  using Clock = std::chrono::steady_clock;
  explicit PeerContacts(PeerContactsConfig config = {});

  /// A contact set arrived at `now`. Sets of `self` (this process's own user) are ignored.
  void Receive(const msg::ContactSet& set, Clock::time_point now, const std::string& self = "");
  /// Drops sets older than the lifespan.
  void Expire(Clock::time_point now);
  /// Forgets everything (a new scene: object indices change).
  void Clear() { sets_.clear(); }

  /// Calls fn(const PeerContact&, const msg::ContactSet&) for every active finger of every
  /// peer on an object of `models` (unknown objects are skipped) whose set has not faded out
  /// at `now`, decoded by the contact codec (dds::DecodeFingerContact). The contacts are not
  /// faded: fade them at the step that uses them (contact::FadedContact(c, fade(), now_ns)).
  template <typename Fn>
  void ForEach(const world::SceneModels& models, Clock::time_point now, Fn&& fn) const {
    std::int32_t hand = 0;
    for (const auto& [user, entry] : sets_) {
      ++hand;
      if (Weight(now - entry.received) <= 0.0) continue;
      const std::uint64_t user_key = contact::UserKey(user);
      const std::uint64_t received_ns = SteadyNs(entry.received);
      for (int i = 0; i < static_cast<int>(entry.set.fingers().size()); ++i) {
        const auto& f = entry.set.fingers()[i];
        if (!f.active()) continue;
        PeerContact c;
        if (!dds::DecodeFingerContact(f, i, models.Find(f.object_id().to_string()), c.contact)) continue;
        c.hand = hand;
        c.user_key = user_key;
        c.received_ns = received_ns;
        fn(c, entry.set);
      }
    }
  }

  /// The newest set of every peer (user -> set), for ownership claims and poses.
  struct Entry {
    msg::ContactSet set;
    Clock::time_point received;
  };
  const std::map<std::string, Entry>& sets() const { return sets_; }
  /// 1 while fresh, falling linearly to 0 between fade_after and lifespan (fade().Weight).
  double Weight(Clock::duration age) const;
  /// The fade law as plain data, for the step that fades the contacts (the haptic thread).
  const contact::PeerFade& fade() const noexcept { return fade_; }
  /// A time point of Clock as the steady nanoseconds PeerContact::received_ns counts
  /// (common::SteadyNowNs() reads the same clock).
  static std::uint64_t SteadyNs(Clock::time_point t) noexcept {
    return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count());
  }

 private:
  PeerContactsConfig config_;
  contact::PeerFade fade_;
  std::map<std::string, Entry> sets_;
};

}  // namespace handshare::session
