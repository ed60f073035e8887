#pragma once
/// When a node that has heard nothing from the world server since joining should join again
/// with a new participant: a secured pair of participants that never finished authenticating
/// stays so for good (Fast DDS 2.9, docs/security.md), and a new participant starts a new
/// handshake with everyone. Shared by the haptic node, the spectator and the audio guide.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>

namespace handshare::node {

class RejoinClock {
 public:
  using Clock = std::chrono::steady_clock;
  /// after: how long a node may go unheard after joining; 0 or less: never rejoin.
  explicit RejoinClock(std::chrono::duration<double> after) : after_(after), joined_(Clock::now()) {}

  /// True when `after` has passed since (re)joining and the server was not `heard`: then a
  /// rejoin is counted and the clock starts again (the caller makes the new participant).
  bool Due(bool heard) {
    if (after_.count() <= 0.0 || heard || Clock::now() - joined_ < after_) return false;
    ++rejoins_;
    joined_ = Clock::now();
    return true;
  }
  /// The log line of the rejoin Due just counted; `what` is what the node waits for ("world").
  std::string Message(std::string_view what) const {
    char line[200];
    std::snprintf(line, sizeof(line),
                  "no %.*s from the world server %.1f s after joining: leaving and joining again with a new "
                  "participant (rejoin %d)",
                  static_cast<int>(what.size()), what.data(), after_.count(), rejoins_);
    return line;
  }
  /// The rejoin Due just counted: closes the old participant (`link` reset), opens the new one
  /// (`link = open()`), starts the wait again from then (a slow close or open does not count
  /// against it) and returns RunRejoin's line.
  template <class Link, class Open>
  std::string Swap(std::unique_ptr<Link>& link, Open open);
  int rejoins() const { return rejoins_; }

 private:
  std::chrono::duration<double> after_;
  Clock::time_point joined_;
  int rejoins_ = 0;
};

/// Runs rejoin number `rejoin`, begun at `begun`: `close()` closes the old participant, `open()`
/// opens the new one. Returns the log line of how long each took (a close or an open that never
/// returns shows as this line missing after the line that announced the rejoin) and sets `opened`
/// to when the new participant was open. For every rejoin, whichever watch counted it.
template <class Close, class Open>
std::string RunRejoin(int rejoin, RejoinClock::Clock::time_point begun, Close close, Open open,
                      RejoinClock::Clock::time_point& opened) {
  close();
  const auto closed = RejoinClock::Clock::now();
  open();
  opened = RejoinClock::Clock::now();
  char line[160];
  std::snprintf(line, sizeof(line), "joined again (rejoin %d): the old participant closed in %.2f s, the new one opened in %.2f s",
                rejoin, std::chrono::duration<double>(closed - begun).count(),
                std::chrono::duration<double>(opened - closed).count());
  return line;
}

template <class Link, class Open>
std::string RejoinClock::Swap(std::unique_ptr<Link>& link, Open open) {
  return RunRejoin(rejoins_, joined_, [&] { link.reset(); }, [&] { link = open(); }, joined_);
}

}  // namespace handshare::node
