#include "handshare/session/stream_rates.hpp"

#include <algorithm>
#include <cmath>

namespace handshare::session {

double DeviceStateRate(int matched_readers, int viewers, double fastest_view_Hz, double full_Hz) {
  if (matched_readers <= 0) return 0.0;
  if (matched_readers > viewers || !(fastest_view_Hz > 0.0)) return full_Hz;
  return std::clamp(fastest_view_Hz, std::min(kMinDeviceStateHz, full_Hz), full_Hz);
}

double ContactSetRate(bool shared, double server_tick_Hz, double full_Hz) {
  if (shared || !(server_tick_Hz > 0.0)) return full_Hz;
  return std::min(server_tick_Hz, full_Hz);
}

namespace {
/// Calls fn(object id) for every object `set` touches with an active finger or claims (grasps,
/// simulates) until fn returns true; returns whether it did.
template <class Fn>
bool AnyObjectOf(const msg::ContactSet& set, Fn&& fn) {
  for (const auto& f : set.fingers()) {
    if (f.active() && f.object_id().size() > 0 && fn(f.object_id())) return true;
  }
  if (set.grasped_object_id().size() > 0 && fn(set.grasped_object_id())) return true;
  return set.simulating() && set.simulated_object_id().size() > 0 && fn(set.simulated_object_id());
}
}  // namespace

bool SharesObjectWithPeer(const msg::ContactSet& own, const PeerContacts& peers, PeerContacts::Clock::time_point now) {
  for (const auto& [user, entry] : peers.sets()) {
    if (own.user() == user || peers.Weight(now - entry.received) <= 0.0) continue;
    const bool shared = AnyObjectOf(entry.set, [&](const auto& theirs) {
      return AnyObjectOf(own, [&](const auto& mine) { return mine == theirs; });
    });
    if (shared) return true;
  }
  return false;
}

StreamPacer::StreamPacer(double tick_Hz)
    : tick_Hz_(tick_Hz), half_tick_ns_(static_cast<std::uint64_t>(std::llround(0.5e9 / tick_Hz))) {}

bool StreamPacer::Due(std::uint64_t now_ns, double rate_Hz) {
  if (!(rate_Hz > 0.0)) return false;
  if (rate_Hz >= tick_Hz_) {
    next_ns_ = 0;
    return true;
  }
  if (now_ns + half_tick_ns_ < next_ns_) return false;
  const auto period_ns = static_cast<std::uint64_t>(std::llround(1e9 / rate_Hz));
  // From the slot this tick was due at, not from now: the ticks' jitter averages out. A tick
  // more than a period late starts afresh from now (no burst of catch-up sends).
  next_ns_ = (next_ns_ == 0 || now_ns >= next_ns_ + period_ns) ? now_ns + period_ns : next_ns_ + period_ns;
  return true;
}

}  // namespace handshare::session
