// nfq_delay: a packet delayer for network tests on kernels without sch_netem.
//
// Reads packets from an NFQUEUE (nft rule `queue num N bypass`), holds each one and issues its
// ACCEPT verdict after delay + jitter (or DROP with the loss probability). One thread: a min-heap
// of release times and ppoll() on the netlink socket with the time to the earliest release as
// its timeout; SIGINT/SIGTERM are only unblocked inside ppoll, so a signal ends the loop between
// two verdicts. On exit every held packet is accepted at once and the counters are printed.
//
// Reordering happens by itself when the jitter exceeds the gap between packets; --no-reorder
// keeps FIFO order (a packet is never released before the one queued before it, so the delay
// distribution is shifted up as with netem's rate/ordering).
//
// usage: nfq_delay --queue N --delay-ms D [--jitter-ms J] [--dist normal|uniform] [--seed S]
//                  [--loss-percent P] [--no-reorder] [--max-held M] [--rt-priority R]
//   --rt-priority: run under SCHED_FIFO R (root); on a loaded machine the default scheduler
//   releases packets milliseconds late.
//   normal:  delay ~ N(D, J) clamped at 0 (J is the standard deviation)
//   uniform: delay ~ U(D - J, D + J) clamped at 0 (standard deviation J / sqrt(3))
#include <arpa/inet.h>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <linux/netfilter.h>
#include <poll.h>
#include <queue>
#include <random>
#include <sched.h>
#include <string>
#include <string_view>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <unistd.h>
#include <vector>

extern "C" {
#include <libnetfilter_queue/libnetfilter_queue.h>
}

namespace {

using Ns = std::int64_t;

Ns NowNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return Ns{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

struct Options {
  int queue = -1;
  double delay_ms = -1;
  double jitter_ms = 0;
  bool uniform = false;
  std::uint64_t seed = 1;
  double loss_percent = 0;
  bool reorder = true;
  unsigned max_held = 65536;
  int rt_priority = 0;  // SCHED_FIFO priority; 0 keeps the normal scheduler
};

[[noreturn]] void Usage(const std::string& error) {
  std::fprintf(stderr,
               "nfq_delay: %s\n"
               "usage: nfq_delay --queue N --delay-ms D [--jitter-ms J] [--dist normal|uniform] [--seed S]\n"
               "                 [--loss-percent P] [--no-reorder] [--max-held M] [--rt-priority R]\n",
               error.c_str());
  std::exit(2);
}

double ParseNumber(std::string_view name, const char* text, double lo, double hi) {
  if (text == nullptr) Usage(std::string(name) + " needs a value");
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text, &end);
  if (errno != 0 || end == text || *end != '\0' || !(v >= lo && v <= hi)) {
    char range[64];
    std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
    Usage(std::string(name) + ": '" + text + "' is not a number in " + range);
  }
  return v;
}

Options Parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    if (a == "--queue") {
      const double q = ParseNumber(a, v, 0, 65535);
      if (q != static_cast<int>(q)) Usage("--queue must be an integer");
      o.queue = static_cast<int>(q);
      ++i;
    } else if (a == "--delay-ms") {
      o.delay_ms = ParseNumber(a, v, 0, 60'000);
      ++i;
    } else if (a == "--jitter-ms") {
      o.jitter_ms = ParseNumber(a, v, 0, 60'000);
      ++i;
    } else if (a == "--dist") {
      if (v == nullptr) Usage("--dist needs a value");
      if (std::string_view(v) == "uniform") {
        o.uniform = true;
      } else if (std::string_view(v) != "normal") {
        Usage(std::string("--dist: '") + v + "' is neither normal nor uniform");
      }
      ++i;
    } else if (a == "--seed") {
      o.seed = static_cast<std::uint64_t>(ParseNumber(a, v, 0, 1e15));
      ++i;
    } else if (a == "--loss-percent") {
      o.loss_percent = ParseNumber(a, v, 0, 100);
      ++i;
    } else if (a == "--max-held") {
      o.max_held = static_cast<unsigned>(ParseNumber(a, v, 1, 1 << 24));
      ++i;
    } else if (a == "--rt-priority") {
      o.rt_priority = static_cast<int>(ParseNumber(a, v, 0, 99));
      ++i;
    } else if (a == "--no-reorder") {
      o.reorder = false;
    } else if (a == "-h" || a == "--help") {
      Usage("help");
    } else {
      Usage("unknown option '" + std::string(a) + "'");
    }
  }
  if (o.queue < 0) Usage("--queue is required");
  if (o.delay_ms < 0) Usage("--delay-ms is required");
  return o;
}

struct Held {
  Ns release_ns;
  std::uint64_t seq;  // ties keep arrival order
  std::uint32_t id;
  Ns arrival_ns;
  bool operator>(const Held& o) const { return release_ns != o.release_ns ? release_ns > o.release_ns : seq > o.seq; }
};

struct Counters {
  std::uint64_t received = 0, accepted = 0, dropped = 0, verdict_errors = 0, enobufs = 0;
  std::size_t max_held = 0;
  double sum_ms = 0, sum_sq_ms = 0;  // applied delay (verdict time - arrival)
  Ns max_late_ns = 0;                // verdict time - scheduled release
  double sum_late_us = 0;
};

struct State {
  Options opt;
  std::mt19937_64 rng;
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform;
  std::uniform_real_distribution<double> unit{0.0, 1.0};
  std::priority_queue<Held, std::vector<Held>, std::greater<>> heap;
  std::uint64_t seq = 0;
  Ns last_release_ns = 0;
  Counters c;
  nfq_q_handle* qh = nullptr;

  explicit State(const Options& o)
      : opt(o),
        rng(o.seed),
        normal(o.delay_ms, o.jitter_ms > 0 ? o.jitter_ms : 1e-12),
        uniform(o.delay_ms - o.jitter_ms, o.delay_ms + o.jitter_ms) {}

  double SampleDelayMs() {
    if (opt.jitter_ms <= 0) return opt.delay_ms;
    const double d = opt.uniform ? uniform(rng) : normal(rng);
    return d < 0 ? 0 : d;
  }

  void Verdict(std::uint32_t id, std::uint32_t verdict) {
    if (nfq_set_verdict(qh, id, verdict, 0, nullptr) < 0) ++c.verdict_errors;
  }

  void Release(const Held& h, Ns now) {
    Verdict(h.id, NF_ACCEPT);
    ++c.accepted;
    const double applied_ms = static_cast<double>(now - h.arrival_ns) * 1e-6;
    c.sum_ms += applied_ms;
    c.sum_sq_ms += applied_ms * applied_ms;
    const Ns late = now - h.release_ns;
    if (late > c.max_late_ns) c.max_late_ns = late;
    c.sum_late_us += static_cast<double>(late) * 1e-3;
  }
};

int OnPacket(nfq_q_handle* /*qh*/, nfgenmsg* /*msg*/, nfq_data* nfa, void* data) {
  auto& s = *static_cast<State*>(data);
  const nfqnl_msg_packet_hdr* ph = nfq_get_msg_packet_hdr(nfa);
  if (ph == nullptr) return 0;
  const std::uint32_t id = ntohl(ph->packet_id);
  const Ns now = NowNs();
  ++s.c.received;
  if (s.opt.loss_percent > 0 && s.unit(s.rng) * 100.0 < s.opt.loss_percent) {
    s.Verdict(id, NF_DROP);
    ++s.c.dropped;
    return 0;
  }
  if (s.heap.size() >= s.opt.max_held) {  // never hold more than asked: pass it on now
    s.Release({now, s.seq++, id, now}, now);
    return 0;
  }
  Ns release = now + static_cast<Ns>(s.SampleDelayMs() * 1e6);
  if (!s.opt.reorder && release < s.last_release_ns) release = s.last_release_ns;
  s.last_release_ns = release;
  s.heap.push({release, s.seq++, id, now});
  if (s.heap.size() > s.c.max_held) s.c.max_held = s.heap.size();
  return 0;
}

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  const Options opt = Parse(argc, argv);
  State s(opt);
  // Default timer slack (50 us) would add to every release; ask for the finest.
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  if (opt.rt_priority > 0) {
    sched_param sp{};
    sp.sched_priority = opt.rt_priority;
    if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
      std::fprintf(stderr, "nfq_delay: SCHED_FIFO %d refused (%s): releases may be late under load\n", opt.rt_priority,
                   std::strerror(errno));
    }
  }

  nfq_handle* h = nfq_open();
  if (h == nullptr) {
    std::fprintf(stderr, "nfq_delay: nfq_open failed: %s (root? nfnetlink_queue module?)\n", std::strerror(errno));
    return 1;
  }
  s.qh = nfq_create_queue(h, static_cast<std::uint16_t>(opt.queue), &OnPacket, &s);
  if (s.qh == nullptr) {
    std::fprintf(stderr, "nfq_delay: cannot bind queue %d: %s (another program on it?)\n", opt.queue,
                 std::strerror(errno));
    nfq_close(h);
    return 1;
  }
  // Only the metadata is needed for a verdict; no payload copy.
  if (nfq_set_mode(s.qh, NFQNL_COPY_META, 0) < 0 ||
      nfq_set_queue_maxlen(s.qh, opt.max_held + 1024) < 0) {
    std::fprintf(stderr, "nfq_delay: cannot configure queue %d: %s\n", opt.queue, std::strerror(errno));
    nfq_destroy_queue(s.qh);
    nfq_close(h);
    return 1;
  }
  // If the kernel queue overflows, accept rather than drop (a test asks for loss explicitly).
  nfq_set_queue_flags(s.qh, NFQA_CFG_F_FAIL_OPEN, NFQA_CFG_F_FAIL_OPEN);
  nfnl_rcvbufsiz(nfq_nfnlh(h), 8u << 20);
  const int fd = nfq_fd(h);
  int one = 1;
  setsockopt(fd, SOL_NETLINK, NETLINK_NO_ENOBUFS, &one, sizeof one);

  sigset_t block, wait_mask;
  sigemptyset(&block);
  sigaddset(&block, SIGINT);
  sigaddset(&block, SIGTERM);
  sigprocmask(SIG_BLOCK, &block, &wait_mask);
  sigdelset(&wait_mask, SIGINT);
  sigdelset(&wait_mask, SIGTERM);
  struct sigaction sa{};
  sa.sa_handler = OnSignal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  std::printf("nfq_delay: queue %d ready: delay %.3f ms, jitter %.3f ms (%s), loss %.2f%%, %s, seed %llu\n",
              opt.queue, opt.delay_ms, opt.jitter_ms, opt.uniform ? "uniform" : "normal", opt.loss_percent,
              opt.reorder ? "reordering allowed" : "FIFO", static_cast<unsigned long long>(opt.seed));
  std::fflush(stdout);

  std::vector<char> buf(1 << 16);
  int exit_code = 0;
  while (!g_stop) {
    Ns now = NowNs();
    while (!s.heap.empty() && s.heap.top().release_ns <= now) {
      s.Release(s.heap.top(), now);
      s.heap.pop();
      now = NowNs();
    }
    timespec timeout{};
    timespec* tp = nullptr;
    if (!s.heap.empty()) {
      const Ns wait = s.heap.top().release_ns - now;
      timeout.tv_sec = wait / 1'000'000'000;
      timeout.tv_nsec = wait % 1'000'000'000;
      tp = &timeout;
    }
    pollfd p{fd, POLLIN, 0};
    const int r = ppoll(&p, 1, tp, &wait_mask);
    if (r < 0) {
      if (errno == EINTR) continue;
      std::fprintf(stderr, "nfq_delay: ppoll: %s\n", std::strerror(errno));
      exit_code = 1;
      break;
    }
    if (r == 0) continue;
    for (;;) {
      const ssize_t n = recv(fd, buf.data(), buf.size(), MSG_DONTWAIT);
      if (n < 0) {
        if (errno == ENOBUFS) {
          ++s.c.enobufs;
          continue;
        }
        break;  // EAGAIN: drained
      }
      nfq_handle_packet(h, buf.data(), static_cast<int>(n));
    }
  }

  // Give every held packet back now; the nft rule's bypass covers the time after we unbind.
  const Ns end = NowNs();
  while (!s.heap.empty()) {
    s.Release(s.heap.top(), end);
    s.heap.pop();
  }
  const double n = static_cast<double>(s.c.accepted);
  const double mean = n > 0 ? s.c.sum_ms / n : 0;
  const double var = n > 1 ? (s.c.sum_sq_ms - n * mean * mean) / (n - 1) : 0;
  std::printf(
      "nfq_delay: queue %d: received %llu, accepted %llu, dropped %llu, max held %zu, applied delay mean %.3f ms "
      "sd %.3f ms, release late mean %.1f us max %.1f us, verdict errors %llu, enobufs %llu\n",
      opt.queue, static_cast<unsigned long long>(s.c.received), static_cast<unsigned long long>(s.c.accepted),
      static_cast<unsigned long long>(s.c.dropped), s.c.max_held, mean, var > 0 ? std::sqrt(var) : 0.0,
      n > 0 ? s.c.sum_late_us / n : 0.0, static_cast<double>(s.c.max_late_ns) * 1e-3,
      static_cast<unsigned long long>(s.c.verdict_errors), static_cast<unsigned long long>(s.c.enobufs));
  std::fflush(stdout);
  nfq_destroy_queue(s.qh);
  nfq_close(h);
  return exit_code;
}
