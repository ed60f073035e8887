// deadband_bench: what the contact-set deadband (session/contact_deadband.hpp) saves and what it
// costs, on a real session's full peer stream.
//
// Input: a recording (session_record) of a session whose haptic nodes ran with --deadband 0,
// so it holds every contact set each hand's bridge wrote (one per bridge tick while touching).
// For each Weber fraction, each user's stream goes through the sender's deadband in its
// recorded order and timing; a receiver holds the newest set that went out (zero-order hold,
// as session::PeerContacts does). At every recorded set, for every active finger, the error is
// the distance between the force (and imposed displacement) the sender had and the one the
// receiver holds.
//
// usage: deadband_bench --recording FILE [--weber 0,0.01,0.02,0.05,0.1,0.15,0.2] [--csv]
// CSV: weber,user,offered,sent,reduction_pct,sent_per_s,force_err_p50_N,force_err_p99_N,
//      force_err_max_N,force_rel_err_p99,disp_err_p99_um,body_err_p99_mm
// (body: a held body's position against where a receiver reckons it from the newest set sent)
// Measured here, never asserted.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "handshare/dds/messages.hpp"
#include "handshare/dds/serialization.hpp"
#include "handshare/dds/topics.hpp"
#include "handshare/session/contact_deadband.hpp"
#include "handshare/world_server/recording.hpp"

namespace {

using handshare::msg::ContactSet;

struct Stamped {
  std::int64_t t_ns;
  ContactSet set;
};

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t i = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

double Distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}
double Norm(const std::array<double, 3>& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

std::vector<double> ParseList(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !(v >= 0.0 && v < 1.0)) {
      throw std::invalid_argument("option --weber: '" + item + "' is not a fraction in [0, 1)");
    }
    out.push_back(v);
  }
  return out;
}

int Usage() {
  std::fprintf(stderr, "usage: deadband_bench --recording FILE [--weber 0,0.01,0.02,0.05,0.1,0.15,0.2] [--csv]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string file;
  std::vector<double> webers{0.0, 0.01, 0.02, 0.05, 0.10, 0.15, 0.20};
  bool csv = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--recording" && i + 1 < argc) {
        file = argv[++i];
      } else if (a == "--weber" && i + 1 < argc) {
        webers = ParseList(argv[++i]);
      } else if (a == "--csv") {
        csv = true;
      } else {
        return Usage();
      }
    }
    if (file.empty()) return Usage();

    // Every contact set of the recording, per user, in order of reception.
    std::map<std::string, std::vector<Stamped>> streams;
    handshare::server::RecordingReader reader(file);
    handshare::server::RecordedSample sample;
    while (reader.Next(sample)) {
      if (sample.topic != handshare::dds::topics::kContactSet.name ||
          sample.state != handshare::server::RecordedState::kAlive || sample.cdr.empty()) {
        continue;
      }
      Stamped s{sample.steady_ns, {}};
      handshare::dds::Deserialize(sample.cdr, s.set);
      streams[s.set.user().to_string()].push_back(std::move(s));
    }
    if (streams.empty()) throw std::runtime_error(file + ": no contact sets in this recording");

    std::printf(csv ? "weber,user,offered,sent,reduction_pct,sent_per_s,force_err_p50_N,force_err_p99_N,"
                      "force_err_max_N,force_rel_err_p99,disp_err_p99_um,body_err_p99_mm\n"
                    : "");
    for (const double weber : webers) {
      for (const auto& [user, stream] : streams) {
        handshare::session::ContactSetDeadband deadband(handshare::session::DeadbandConfig{.weber = weber});
        ContactSet held;
        std::int64_t held_ns = 0;
        std::vector<double> force_err, force_rel, disp_err, body_err;
        for (const Stamped& s : stream) {
          if (deadband.Offer(s.set, static_cast<std::uint64_t>(s.t_ns))) {
            held = s.set;
            held_ns = s.t_ns;
          }
          if (s.set.simulating() && held.simulating() && held.simulated_object_id() == s.set.simulated_object_id()) {
            body_err.push_back(Distance(handshare::session::ReckonedPosition(held, 1e-9 * static_cast<double>(s.t_ns - held_ns)),
                                        s.set.p_WO_m()));
          }
          for (std::size_t i = 0; i < s.set.fingers().size(); ++i) {
            const auto& now = s.set.fingers()[i];
            const auto& old = held.fingers()[i];
            // Receivers read a finger's force and displacement on deformables only (a finger on
            // a rigid body or a control, surface node -1, only claims it).
            if (!now.active() || now.surface_node() < 0) continue;
            const double e = old.active() ? Distance(now.f_O_N(), old.f_O_N()) : Norm(now.f_O_N());
            force_err.push_back(e);
            if (Norm(now.f_O_N()) > deadband.config().force_floor_N) force_rel.push_back(e / Norm(now.f_O_N()));
            disp_err.push_back(old.active() ? Distance(now.u_O_m(), old.u_O_m())
                                            : Norm(now.u_O_m()));
          }
        }
        const double span_s = stream.size() > 1 ? 1e-9 * static_cast<double>(stream.back().t_ns - stream.front().t_ns) : 0.0;
        const double per_s = span_s > 0.0 ? static_cast<double>(deadband.sent()) / span_s : 0.0;
        if (csv) {
          std::printf("%.3f,%s,%llu,%llu,%.1f,%.1f,%.4f,%.4f,%.4f,%.4f,%.2f,%.3f\n", weber, user.c_str(),
                      static_cast<unsigned long long>(deadband.offered()),
                      static_cast<unsigned long long>(deadband.sent()), 100.0 * deadband.reduction(), per_s,
                      Quantile(force_err, 0.5), Quantile(force_err, 0.99),
                      force_err.empty() ? 0.0 : *std::max_element(force_err.begin(), force_err.end()),
                      Quantile(force_rel, 0.99), 1e6 * Quantile(disp_err, 0.99), 1e3 * Quantile(body_err, 0.99));
        } else {
          std::string why;
          for (int r = 1; r < handshare::session::kDeadbandReasons; ++r) {
            const auto reason = static_cast<handshare::session::DeadbandReason>(r);
            if (deadband.sent_for(reason) > 0) {
              why += std::string(" ") + handshare::session::ToString(reason) + " " + std::to_string(deadband.sent_for(reason));
            }
          }
          std::printf("weber %.2f %-8s sets %6llu -> %6llu (%.1f %% fewer, %.1f/s; sent for:%s); force error on "
                      "deformables p50 %.4f p99 %.4f max %.4f N (p99 %.1f %% of the force); displacement error p99 %.1f um; "
                      "held body error p99 %.2f mm\n",
                      weber, user.c_str(), static_cast<unsigned long long>(deadband.offered()),
                      static_cast<unsigned long long>(deadband.sent()), 100.0 * deadband.reduction(), per_s, why.c_str(),
                      Quantile(force_err, 0.5), Quantile(force_err, 0.99),
                      force_err.empty() ? 0.0 : *std::max_element(force_err.begin(), force_err.end()),
                      100.0 * Quantile(force_rel, 0.99), 1e6 * Quantile(disp_err, 0.99), 1e3 * Quantile(body_err, 0.99));
        }
      }
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "deadband_bench: %s\n", e.what());
    return 1;
  }
}
