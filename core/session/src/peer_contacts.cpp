#include "handshare/session/peer_contacts.hpp"

#include <algorithm>
#include <stdexcept>

namespace handshare::session {

PeerContacts::PeerContacts(PeerContactsConfig config) : config_(config) {
  if (config_.fade_after.count() < 0 || config_.lifespan <= config_.fade_after) {
    throw std::invalid_argument("PeerContacts: need 0 <= fade_after < lifespan");
  }
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
  if (age <= config_.fade_after) return 1.0;
  if (age >= config_.lifespan) return 0.0;
  const double span = std::chrono::duration<double>(config_.lifespan - config_.fade_after).count();
  return std::clamp(1.0 - std::chrono::duration<double>(age - config_.fade_after).count() / span, 0.0, 1.0);
}

}  // namespace handshare::session
