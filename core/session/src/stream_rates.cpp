#include "handshare/session/stream_rates.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

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
/// Every object a set touches with an active finger or claims.
std::vector<std::string> ObjectsOf(const msg::ContactSet& set) {
  std::vector<std::string> out;
  for (const auto& f : set.fingers()) {
    if (f.active() && !f.object_id().to_string().empty()) out.push_back(f.object_id().to_string());
  }
  if (!set.grasped_object_id().to_string().empty()) out.push_back(set.grasped_object_id().to_string());
  if (set.simulating() && !set.simulated_object_id().to_string().empty()) {
    out.push_back(set.simulated_object_id().to_string());
  }
  return out;
}
}  // namespace

bool SharesObjectWithPeer(const msg::ContactSet& own, const PeerContacts& peers, PeerContacts::Clock::time_point now) {
  const std::vector<std::string> mine = ObjectsOf(own);
  if (mine.empty()) return false;
  for (const auto& [user, entry] : peers.sets()) {
    if (user == own.user().to_string() || peers.Weight(now - entry.received) <= 0.0) continue;
    for (const std::string& object : ObjectsOf(entry.set)) {
      if (std::find(mine.begin(), mine.end(), object) != mine.end()) return true;
    }
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
