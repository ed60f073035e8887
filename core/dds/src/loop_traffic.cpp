#include "handshare/dds/loop_traffic.hpp"

namespace handshare::dds {

LoopTraffic::LoopTraffic(const Participant& participant, Clock::time_point start)
    : participant_(participant), bytes_(participant.WrittenBytes()), since_(start) {}

void LoopTraffic::Fill(msg::LoopStatistics& out, Clock::time_point now) {
  const std::uint64_t bytes = participant_.WrittenBytes();
  const double period_s = std::chrono::duration<double>(now - since_).count();
  out.sent_bytes_per_s(period_s > 0.0 ? static_cast<double>(bytes - bytes_) / period_s : 0.0);
  out.deadline_misses(participant_.DeadlinesMissed());
  bytes_ = bytes;
  since_ = now;
}

}  // namespace handshare::dds
