#pragma once
/// The DDS part of a node's loop statistics (LoopStatistics::deadline_misses and
/// sent_bytes_per_s), the same for every kind of node: the participant's deadline misses so
/// far, and the bytes its writers wrote per second since the previous statistics. Not
/// real-time: the thread that writes the statistics calls it.
#include <chrono>
#include <cstdint>

#include "handshare/dds/messages.hpp"
#include "handshare/dds/participant.hpp"

namespace handshare::dds {

class LoopTraffic {
 public:
  using Clock = std::chrono::steady_clock;
  /// The first rate covers the time from `start`.
  explicit LoopTraffic(const Participant& participant, Clock::time_point start = Clock::now());
  /// Sets out.deadline_misses() and out.sent_bytes_per_s() (the bytes written from the previous
  /// call, or the start, until `now`, per second; 0 when no time passed).
  void Fill(msg::LoopStatistics& out, Clock::time_point now = Clock::now());

 private:
  const Participant& participant_;
  std::uint64_t bytes_;
  Clock::time_point since_;
};

}  // namespace handshare::dds
