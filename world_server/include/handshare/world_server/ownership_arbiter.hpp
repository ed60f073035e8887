#pragma once
/// Who owns each grasped rigid object. One owner at a time; the owner's haptic node simulates
/// the object and writes its ObjectState, everyone else follows it. Pure logic, no DDS, no
/// clock of its own: the world server feeds it grasp reports and the time, and publishes the
/// changes it returns. Deterministic: the same calls give the same changes.
///
/// Rules
/// 1. Grant: a free object goes to the user grasping it; if several grasp it, to the one whose
///    grasp began first (ties: the smaller user name).
/// 2. Keep: the owner keeps the object while grasping it, however many others grasp it too; a
///    taker never pulls an object out of a holding hand.
/// 3. Release: when the owner stops grasping for longer than release_grace (a grasp flickering
///    for a frame is not a release), the object goes to the longest-grasping other user (rule 1),
///    else it becomes free (the world server simulates it).
/// 4. Vanish: an owner whose member is reported gone (OnUserGone) loses everything at once; an
///    owner whose grasp reports stop arriving for stale_after counts as not grasping, so a
///    vanished owner loses the object within stale_after + release_grace (< 2 s by default)
///    even before the member registry notices.
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "handshare/world/grasp.hpp"  // IsGrasp: what a grasp report means

namespace handshare::server {

struct OwnershipConfig {
  std::chrono::nanoseconds release_grace = std::chrono::milliseconds(100);
  std::chrono::nanoseconds stale_after = std::chrono::seconds(1);  // 0: reports never go stale
};

enum class OwnershipReason {
  kGranted,        // a free object was grasped
  kReleased,       // the owner let go; nobody else holds it: free
  kHandedOver,     // the owner let go while another user held it
  kOwnerVanished,  // the owner's member is gone (OnUserGone)
  kOwnerStale,     // the owner's grasp reports stopped
};
const char* ToString(OwnershipReason reason);

struct OwnershipChange {
  std::string object_id;
  std::string previous_owner;  // "" : was free
  std::string owner;           // "" : now free
  OwnershipReason reason;
};

class OwnershipArbiter {
 public:
  using Time = std::chrono::steady_clock::time_point;

  explicit OwnershipArbiter(OwnershipConfig config = {});

  /// A grasp report of `user` on `object_id` at time t (from the user's contact set: IsGrasp).
  /// Reports must arrive at least every stale_after while a user grasps (contact sets come at
  /// haptic rate while touching); a report with grasping = false ends that user's grasp.
  void Report(const std::string& user, const std::string& object_id, bool grasping, Time t);
  /// The user's member left or was lost at time t: its grasps end and it owns nothing from the
  /// next Update. Reports stamped at or before t are ignored from then on (late samples).
  void OnUserGone(const std::string& user, Time t);
  /// Applies the rules at time now; returns the changes in object-id order.
  std::vector<OwnershipChange> Update(Time now);
  /// Forgets everything (a new scene).
  void Clear();

  /// "" when free or unknown.
  std::string owner(const std::string& object_id) const;
  std::size_t owned_count() const;

 private:
  struct Grasp {
    bool grasping = false;
    Time since{};      // when the current grasp began
    Time last_report{};
    Time released_at{};  // when grasping turned false
  };
  struct Object {
    std::string owner;
    std::map<std::string, Grasp> grasps;  // by user
  };
  bool Holds(const Grasp& g, Time now) const;
  bool Stale(const Grasp& g, Time now) const;

  OwnershipConfig config_;
  std::map<std::string, Object> objects_;
  std::map<std::string, Time> gone_at_;  // users reported gone, and when
};

}  // namespace handshare::server
