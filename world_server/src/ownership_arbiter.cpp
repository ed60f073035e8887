#include "handshare/world_server/ownership_arbiter.hpp"

#include <cmath>

namespace handshare::server {

const char* ToString(OwnershipReason reason) {
  switch (reason) {
    case OwnershipReason::kGranted: return "granted";
    case OwnershipReason::kReleased: return "released";
    case OwnershipReason::kHandedOver: return "handed_over";
    case OwnershipReason::kOwnerVanished: return "owner_vanished";
    case OwnershipReason::kOwnerStale: return "owner_stale";
  }
  return "?";
}

OwnershipArbiter::OwnershipArbiter(OwnershipConfig config) : config_(config) {}

void OwnershipArbiter::Report(const std::string& user, const std::string& object_id, bool grasping, Time t) {
  // A sample sent before the user was reported gone (taken late from another topic) does not
  // bring it back; a newer one does.
  if (const auto gone = gone_at_.find(user); gone != gone_at_.end()) {
    if (t <= gone->second) return;
    gone_at_.erase(gone);
  }
  Grasp& g = objects_[object_id].grasps[user];
  if (grasping && !g.grasping) g.since = t;
  if (!grasping && g.grasping) g.released_at = t;
  g.grasping = grasping;
  g.last_report = t;
}

void OwnershipArbiter::OnUserGone(const std::string& user, Time t) {
  for (auto& [id, object] : objects_) object.grasps.erase(user);
  gone_at_[user] = t;
}

bool OwnershipArbiter::Stale(const Grasp& g, Time now) const {
  return config_.stale_after.count() > 0 && now - g.last_report > config_.stale_after;
}

bool OwnershipArbiter::Holds(const Grasp& g, Time now) const { return g.grasping && !Stale(g, now); }

std::vector<OwnershipChange> OwnershipArbiter::Update(Time now) {
  std::vector<OwnershipChange> changes;
  for (auto it = objects_.begin(); it != objects_.end();) {
    const std::string& id = it->first;
    Object& object = it->second;

    // Does the current owner lose it, and why?
    std::optional<OwnershipReason> lost;
    if (!object.owner.empty()) {
      const auto g = object.grasps.find(object.owner);
      if (g == object.grasps.end()) {  // OnUserGone removed it
        lost = OwnershipReason::kOwnerVanished;
      } else if (g->second.grasping && Stale(g->second, now)) {
        lost = OwnershipReason::kOwnerStale;
      } else if (!g->second.grasping && now - g->second.released_at >= config_.release_grace) {
        lost = OwnershipReason::kReleased;
      }
    }

    if (object.owner.empty() || lost) {
      // The longest-held grasp among the others (ties: the smaller name, the map's order).
      const std::string* best = nullptr;
      Time best_since{};
      for (const auto& [user, g] : object.grasps) {
        if (user == object.owner || !Holds(g, now)) continue;
        if (!best || g.since < best_since) {
          best = &user;
          best_since = g.since;
        }
      }
      if (object.owner.empty()) {
        if (best) changes.push_back({id, "", *best, OwnershipReason::kGranted});
      } else {
        const std::string next = best ? *best : std::string();
        OwnershipReason reason = *lost;
        if (reason == OwnershipReason::kReleased && best) reason = OwnershipReason::kHandedOver;
        changes.push_back({id, object.owner, next, reason});
      }
      if (!changes.empty() && changes.back().object_id == id) object.owner = changes.back().owner;
    }

    // Forget grasps that ended or went stale (not the owner's, which the rules above still need),
    // and objects nobody owns or touches.
    for (auto g = object.grasps.begin(); g != object.grasps.end();) {
      const bool owner = g->first == object.owner;
      g = (!owner && !Holds(g->second, now)) ? object.grasps.erase(g) : std::next(g);
    }
    it = (object.owner.empty() && object.grasps.empty()) ? objects_.erase(it) : std::next(it);
  }
  return changes;
}

void OwnershipArbiter::Clear() {
  objects_.clear();
  gone_at_.clear();
}

std::string OwnershipArbiter::owner(const std::string& object_id) const {
  const auto it = objects_.find(object_id);
  return it == objects_.end() ? std::string() : it->second.owner;
}

std::size_t OwnershipArbiter::owned_count() const {
  std::size_t n = 0;
  for (const auto& [id, o] : objects_) n += o.owner.empty() ? 0 : 1;
  return n;
}

}  // namespace handshare::server
