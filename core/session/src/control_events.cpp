#include "handshare/session/control_events.hpp"

namespace handshare::session {

msg::ControlEventKind ToMessage(controls::EventKind kind) noexcept {
  switch (kind) {
    case controls::EventKind::kPressed: return msg::CONTROL_PRESSED;
    case controls::EventKind::kReleased: return msg::CONTROL_RELEASED;
    case controls::EventKind::kMoved: return msg::CONTROL_MOVED;
    case controls::EventKind::kPageTurned: return msg::CONTROL_PAGE_TURNED;
    case controls::EventKind::kMissed: return msg::CONTROL_MISSED;
    case controls::EventKind::kOpened: return msg::CONTROL_OPENED;
    case controls::EventKind::kMoving: return msg::CONTROL_MOVING;
  }
  return msg::CONTROL_MISSED;
}

std::optional<controls::EventKind> FromMessage(msg::ControlEventKind kind) noexcept {
  switch (kind) {
    case msg::CONTROL_PRESSED: return controls::EventKind::kPressed;
    case msg::CONTROL_RELEASED: return controls::EventKind::kReleased;
    case msg::CONTROL_MOVED: return controls::EventKind::kMoved;
    case msg::CONTROL_PAGE_TURNED: return controls::EventKind::kPageTurned;
    case msg::CONTROL_MISSED: return controls::EventKind::kMissed;
    case msg::CONTROL_OPENED: return controls::EventKind::kOpened;
    case msg::CONTROL_MOVING: return controls::EventKind::kMoving;
  }
  return std::nullopt;
}

msg::ControlEvent ToMessage(const controls::ControlEvent& event, const std::string& session,
                            const std::string& user, std::uint64_t stamp_ns) {
  msg::ControlEvent m;
  m.session(session);
  m.user(user);
  m.control_id(std::string(event.id()));
  m.kind(ToMessage(event.kind));
  m.value(event.value);
  m.index(event.index);
  m.error_m(event.error_m);
  m.stamp_ns(stamp_ns);
  return m;
}

}  // namespace handshare::session
