#include "handshare/session/peer_contacts.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace handshare::session {

PeerContacts::PeerContacts(PeerContactsConfig config) : config_(config) {
  if (config_.fade_after.count() < 0 || config_.lifespan <= config_.fade_after) {
    throw std::invalid_argument("PeerContacts: need 0 <= fade_after < lifespan");
  }
  fade_.fade_after_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(config_.fade_after).count();
  fade_.lifespan_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(config_.lifespan).count();
}

void PeerContacts::Receive(const msg::ContactSet& set, Clock::time_point now, const std::string& self) {
  const std::string user = set.user().to_string();
  if (user.empty() || user == self) return;
  sets_[user] = Entry{set, now};
}

void PeerContacts::Expire(Clock::time_point now) {
  std::erase_if(sets_, [&](const auto& e) { return now - e.second.received >= config_.lifespan; });
}

double PeerContacts::Weight(Clock::duration age) const {
  return fade_.Weight(std::chrono::duration_cast<std::chrono::nanoseconds>(age).count());
}

}  // namespace handshare::session
