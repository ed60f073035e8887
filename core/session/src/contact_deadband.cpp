#include "handshare/session/contact_deadband.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "handshare/dds/contact_codec.hpp"

namespace handshare::session {

namespace {
using Vec3 = std::array<double, 3>;

double Norm(const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }
double Distance(const Vec3& a, const Vec3& b) {
  return Norm({a[0] - b[0], a[1] - b[1], a[2] - b[2]});
}
/// Weber's law with a floor: |now - sent| beyond weber |sent|, and beyond the floor.
bool PastWeber(const Vec3& sent, const Vec3& now, double weber, double floor) {
  return Distance(sent, now) > std::max(weber * Norm(sent), floor);
}
/// The angle between two unit quaternions (w, x, y, z), q and -q being the same turn.
double TurnBetween(const std::array<double, 4>& a, const std::array<double, 4>& b) {
  double dot = 0.0;
  for (int k = 0; k < 4; ++k) dot += a[k] * b[k];
  return 2.0 * std::acos(std::min(1.0, std::abs(dot)));
}

DeadbandReason FingerChange(const msg::FingerContact& sent, const msg::FingerContact& now, const DeadbandConfig& c) {
  if (sent.active() != now.active()) return DeadbandReason::kStructure;
  if (!now.active()) return DeadbandReason::kNone;  // both off: nothing of it is read
  if (sent.object_id() != now.object_id() || sent.surface_node() != now.surface_node()) {
    return DeadbandReason::kStructure;
  }
  // A finger on a rigid body or a control (no surface node): receivers read only that it is
  // there (whoever touches a body claims and simulates it); its force and point are not read.
  if (now.surface_node() < 0) return DeadbandReason::kNone;
  // On a deformable: the receivers' solves read the contact point, the imposed displacement
  // and the force (contact::FingerContact, as the codec decodes it); the fingertip centre,
  // normal and depth ride along. Same object on both sides: any index does for the compare.
  contact::FingerContact a, b;
  dds::DecodeFingerContact(sent, 0, 0, a);
  dds::DecodeFingerContact(now, 0, 0, b);
  if (PastWeber(a.f_O_N, b.f_O_N, c.weber, c.force_floor_N)) return DeadbandReason::kForce;
  if (PastWeber(a.u_O_m, b.u_O_m, c.weber, c.displacement_floor_m)) return DeadbandReason::kDisplacement;
  if (Distance(a.p_OC_m, b.p_OC_m) > c.position_m) return DeadbandReason::kPosition;
  return DeadbandReason::kNone;
}
}  // namespace

const char* ToString(DeadbandReason reason) noexcept {
  switch (reason) {
    case DeadbandReason::kNone: return "none";
    case DeadbandReason::kOff: return "off";
    case DeadbandReason::kFirst: return "first";
    case DeadbandReason::kStructure: return "structure";
    case DeadbandReason::kForce: return "force";
    case DeadbandReason::kDisplacement: return "displacement";
    case DeadbandReason::kPosition: return "position";
    case DeadbandReason::kBody: return "body";
    case DeadbandReason::kKeepalive: return "keepalive";
  }
  return "?";
}

std::array<double, 3> ReckonedPosition(const msg::ContactSet& set, double age_s) {
  const double t = std::clamp(age_s, 0.0, kMaxReckoning_s);
  const auto& p = set.p_WO_m();
  const auto& v = set.v_WO_m_per_s();
  return {p[0] + v[0] * t, p[1] + v[1] * t, p[2] + v[2] * t};
}

DeadbandReason PerceptibleChange(const msg::ContactSet& sent, const msg::ContactSet& now, double age_s,
                                 const DeadbandConfig& c) {
  if (sent.grasped_object_id() != now.grasped_object_id() || sent.simulating() != now.simulating() ||
      sent.simulated_object_id() != now.simulated_object_id()) {
    return DeadbandReason::kStructure;
  }
  DeadbandReason first = DeadbandReason::kNone;
  for (std::size_t i = 0; i < now.fingers().size(); ++i) {
    const DeadbandReason r = FingerChange(sent.fingers()[i], now.fingers()[i], c);
    if (r != DeadbandReason::kNone && (first == DeadbandReason::kNone || r < first)) first = r;
  }
  if (first != DeadbandReason::kNone) return first;
  // The held body: against where the receiver reckons it (the last pose sent, moved on at the
  // last velocity sent), so a body carried at a steady speed needs no sets. Its velocity counts
  // only through that reckoning (a wrong one soon puts the body past the threshold); a let-go,
  // the one moment its velocity alone decides where it flies, changes the grasp claim and
  // always goes out.
  if (now.simulating() &&
      (Distance(ReckonedPosition(sent, age_s), now.p_WO_m()) > c.position_m ||
       TurnBetween(sent.q_WO_wxyz(), now.q_WO_wxyz()) > c.angle_rad)) {
    return DeadbandReason::kBody;
  }
  return DeadbandReason::kNone;
}

ContactSetDeadband::ContactSetDeadband(DeadbandConfig config) : config_(config) {
  if (!(config_.weber >= 0.0 && config_.weber < 1.0)) {
    throw std::invalid_argument("deadband: the Weber fraction must be in [0, 1), got " + std::to_string(config_.weber));
  }
  if (config_.force_floor_N < 0.0 || config_.displacement_floor_m < 0.0 || config_.position_m < 0.0 ||
      config_.angle_rad < 0.0 || config_.keepalive.count() <= 0) {
    throw std::invalid_argument("deadband: thresholds must be >= 0 and the keepalive > 0");
  }
}

bool ContactSetDeadband::Offer(const msg::ContactSet& set, std::uint64_t now_ns, DeadbandReason* reason) {
  ++offered_;
  DeadbandReason why = DeadbandReason::kNone;
  if (config_.weber <= 0.0) {
    why = DeadbandReason::kOff;
  } else if (!have_sent_) {
    why = DeadbandReason::kFirst;
  } else {
    const double age_s = now_ns >= last_ns_ ? 1e-9 * static_cast<double>(now_ns - last_ns_) : 0.0;
    why = PerceptibleChange(last_, set, age_s, config_);
    if (why == DeadbandReason::kNone && now_ns >= last_ns_ &&
        now_ns - last_ns_ >= static_cast<std::uint64_t>(config_.keepalive.count())) {
      why = DeadbandReason::kKeepalive;
    }
  }
  if (reason != nullptr) *reason = why;
  if (why == DeadbandReason::kNone) return false;
  last_ = set;
  last_ns_ = now_ns;
  have_sent_ = true;
  ++sent_;
  ++by_reason_[static_cast<int>(why)];
  return true;
}

}  // namespace handshare::session
