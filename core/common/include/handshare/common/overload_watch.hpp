#pragma once
/// Says plainly when a node's periodic thread cannot keep its rate because the machine has no
/// room (docs/network.md, "A busy machine"): the haptic node's bridge (100 Hz: peers' contacts,
/// the hand's state for the screens) and the world server's tick (60 Hz: bodies, fields, the
/// board) run at normal priority, below the SCHED_FIFO haptic loops, and are the first to starve.
///
/// Over windows of window_s, a thread is overloaded when it ran fewer ticks than min_rate_Hz or
/// one of its intervals was longer than max_interval_s; it is well again after a whole window
/// within both. A thread that asks for longer intervals while it has little to do (the bridge's
/// idle ticks) says so with each tick: the rate is then its share of the ticks it asked for
/// (times rate_Hz), and an interval is late by what it ran over the one asked for (past
/// max_interval_s less one period at rate_Hz); with every interval asked at 1 / rate_Hz both
/// read as above. Tick() returns the line to log when that changes (empty otherwise), so a node
/// prints one line when an overload starts and one when it ends, not one per tick. Not
/// real-time: the thread's own, once a tick.
#include <cstdint>
#include <string>

namespace handshare::common {

struct OverloadLimits {
  double rate_Hz = 100.0;         ///< the rate asked for
  double min_rate_Hz = 50.0;      ///< below this over a window: overloaded
  double max_interval_s = 0.1;    ///< an interval longer than this: overloaded
  double window_s = 2.0;
};

class OverloadWatch {
 public:
  /// what: the thread, as the line names it ("the bridge", "the tick").
  OverloadWatch(std::string what, OverloadLimits limits);

  /// One tick at now_ns (steady clock), the interval since the last asked to be asked_s long
  /// (0: 1 / rate_Hz). The line to log if the state changed, else "".
  std::string Tick(std::uint64_t now_ns, double asked_s = 0.0);
  /// The thread was busy with work of its own since its last tick (the bridge building a world's
  /// models, 1.1 s for the dinosaur): that gap says nothing of the machine. The next window
  /// starts at now_ns; an overload under way stays one (its time counts on).
  void Restart(std::uint64_t now_ns);

  bool overloaded() const noexcept { return overloaded_; }
  /// Overloads so far, and the time spent overloaded (until the last tick) [s].
  int episodes() const noexcept { return episodes_; }
  double overloaded_s() const noexcept { return overloaded_s_; }
  /// "no overload" or "overloaded N time(s), X s in all": for a node's exit summary.
  std::string Summary() const;

 private:
  std::string what_;
  OverloadLimits limits_;
  std::uint64_t window_start_ns_ = 0;
  std::uint64_t last_ns_ = 0;
  std::uint64_t since_ns_ = 0;  // when the current overload began
  double longest_s_ = 0.0;
  double most_over_s_ = 0.0;  // the most an interval ran over the one asked, this window
  double asked_sum_s_ = 0.0;  // the intervals asked for, this window
  bool overloaded_ = false;
  int episodes_ = 0;
  double overloaded_s_ = 0.0;
};

}  // namespace handshare::common
