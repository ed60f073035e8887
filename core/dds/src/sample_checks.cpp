#include "handshare/dds/sample_checks.hpp"

#include <bit>

#include "handshare/common/utf8.hpp"
#include "handshare/dds/contact_codec.hpp"

#include <cmath>
#include <sstream>

namespace handshare::dds {

namespace {

// Builds the reason of the first failing field; later checks are skipped once one failed.
class Checker {
 public:
  bool ok() const { return reason_.empty(); }
  std::string reason() const { return reason_; }

  void Session(std::string_view got, std::string_view want) {
    if (ok() && got != want) Fail("session '" + std::string(got) + "' is not this session ('" + std::string(want) + "')");
  }
  void NonEmpty(std::string_view field, std::string_view value) {
    if (ok() && value.empty()) Fail(std::string(field) + " is empty");
  }
  template <class Array>
  void Vector(const std::string& field, const Array& v, std::size_t n, double max_norm) {
    if (!ok()) return;
    double sq = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      if (!std::isfinite(v[k])) {
        std::ostringstream s;
        s << field << "[" << k << "] is " << v[k];
        Fail(s.str());
        return;
      }
      sq += v[k] * v[k];
    }
    if (std::sqrt(sq) > max_norm) {
      std::ostringstream s;
      s << field << " has norm " << std::sqrt(sq) << " (at most " << max_norm << ")";
      Fail(s.str());
    }
  }
  template <class Array>
  void Quaternion(const std::string& field, const Array& q) {
    Vector(field, q, 4, 1e9);
    if (!ok()) return;
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (n < 0.5 || n > 2.0) {
      std::ostringstream s;
      s << field << " has norm " << n << " (a rotation's is 1)";
      Fail(s.str());
    }
  }
  void Range(const std::string& field, double v, double lo, double hi) {
    if (!ok()) return;
    if (!std::isfinite(v) || v < lo || v > hi) {
      std::ostringstream s;
      s << field << " is " << v << " (expected " << lo << " to " << hi << ")";
      Fail(s.str());
    }
  }
  void Fail(std::string reason) { reason_ = std::move(reason); }

 private:
  std::string reason_;
};

}  // namespace

std::string CheckContactSet(const msg::ContactSet& s, std::string_view session, const SampleBounds& b) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("user", s.user().to_string());
  for (int i = 0; i < static_cast<int>(s.fingers().size()) && c.ok(); ++i) {
    const auto& f = s.fingers()[i];
    if (!f.active()) continue;
    const std::string at = "fingers[" + std::to_string(i) + "].";
    c.NonEmpty(at + "object_id", f.object_id().to_string());
    // The contact as every receiver reads it (the codec); its fields carry the wire's names.
    contact::FingerContact fc;
    DecodeFingerContact(f, i, 0, fc);
    c.Vector(at + "p_OC_m", fc.p_OC_m, 3, b.max_position_m);
    c.Vector(at + "n_O", fc.n_O, 3, 2.0);
    c.Vector(at + "p_OE_m", fc.p_OE_m, 3, b.max_position_m);
    c.Range(at + "radius_m", f.radius_m(), 0.0, b.max_fingertip_radius_m);
    c.Range(at + "depth_m", fc.depth_m, -b.max_displacement_m, b.max_displacement_m);
    c.Vector(at + "u_O_m", fc.u_O_m, 3, b.max_displacement_m);
    c.Vector(at + "f_O_N", fc.f_O_N, 3, b.max_force_N);
  }
  if (s.simulating()) {
    c.NonEmpty("simulated_object_id", s.simulated_object_id().to_string());
    c.Vector("p_WO_m", s.p_WO_m(), 3, b.max_position_m);
    c.Quaternion("q_WO_wxyz", s.q_WO_wxyz());
    c.Vector("v_WO_m_per_s", s.v_WO_m_per_s(), 3, b.max_speed_m_per_s);
  }
  return c.reason();
}

std::string CheckObjectState(const msg::ObjectState& s, std::string_view session, const SampleBounds& b) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("object_id", s.object_id().to_string());
  c.Vector("p_WO_m", s.p_WO_m(), 3, b.max_position_m);
  c.Quaternion("q_WO_wxyz", s.q_WO_wxyz());
  c.Vector("v_WO_m_per_s", s.v_WO_m_per_s(), 3, b.max_speed_m_per_s);
  c.Vector("w_WO_rad_per_s", s.w_WO_rad_per_s(), 3, b.max_angular_speed_rad_per_s);
  return c.reason();
}

std::string CheckSceneState(const msg::SceneState& s, std::string_view session, const SampleBounds& b) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("scene", s.scene().to_string());
  // A scene name is a file name in the scenes folder: no path may be smuggled in.
  const std::string name = s.scene().to_string();
  if (c.ok() && name.find_first_of("/\\") != std::string::npos) c.Fail("scene '" + name + "' is not a plain name");
  if (c.ok() && name.find("..") != std::string::npos) c.Fail("scene '" + name + "' is not a plain name");
  c.Vector("gravity_W_m_per_s2", s.gravity_W_m_per_s2(), 3, b.max_gravity_m_per_s2);
  c.Range("tick_Hz", s.tick_Hz(), 0.0, b.max_rate_Hz);
  return c.reason();
}

std::string CheckControlState(const msg::ControlState& s, std::string_view session) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("control_id", s.control_id().to_string());
  c.NonEmpty("scene", s.scene().to_string());
  c.Range("index", s.index(), -1.0, 1000.0);
  c.Range("position", s.position(), -10.0, 10.0);  // radians or metres: finite and small
  return c.reason();
}

std::string CheckSessionRoster(const msg::SessionRoster& s, std::string_view session) {
  Checker c;
  c.Session(s.session().to_string(), session);
  for (std::size_t i = 0; i < s.members().size() && c.ok(); ++i) {
    c.NonEmpty("members[" + std::to_string(i) + "]", s.members()[i].to_string());
  }
  return c.reason();
}

std::string CheckControlEvent(const msg::ControlEvent& s, std::string_view session) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("user", s.user().to_string());
  c.NonEmpty("control_id", s.control_id().to_string());
  const auto kind = static_cast<int>(s.kind());
  if (c.ok() && (kind < static_cast<int>(msg::CONTROL_PRESSED) || kind > static_cast<int>(msg::CONTROL_MOVING))) {
    c.Fail("kind " + std::to_string(kind) + " is not a control event kind");
  }
  c.Range("index", static_cast<double>(s.index()), -1.0, 1000.0);
  if (c.ok() && s.kind() == msg::CONTROL_MOVING) {
    c.Range("value", s.value(), -10.0, 10.0);  // where it is: radians or metres
    c.Range("index", static_cast<double>(s.index()), 0.0, 1.0);
  }
  return c.reason();
}

std::string CheckVisitAnswers(const msg::VisitAnswers& s, std::string_view session) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("user", s.user().to_string());
  c.NonEmpty("visitor", s.visitor().to_string());
  bool answered = false;
  for (std::size_t k = 0; k < s.scores().size() && c.ok(); ++k) {
    for (std::size_t q = 0; q < s.scores()[k].size() && c.ok(); ++q) {
      const int score = s.scores()[k][q];
      if (score > 7) c.Fail("scores[" + std::to_string(k) + "][" + std::to_string(q) + "] " + std::to_string(score) + " is not 0..7");
      answered = answered || score > 0;
    }
  }
  if (c.ok() && !answered) c.Fail("no score answered");
  return c.reason();
}

std::string CheckOperatorCommand(const msg::OperatorCommand& s, std::string_view session) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("user", s.user().to_string());
  const auto kind = static_cast<int>(s.kind());
  if (c.ok() && (kind < static_cast<int>(msg::OPERATOR_GO_TO_WORLD) || kind > static_cast<int>(msg::OPERATOR_END_TURN))) {
    c.Fail("kind " + std::to_string(kind) + " is not an operator command");
  }
  if (c.ok() && s.kind() == msg::OPERATOR_GO_TO_WORLD) {
    const std::string world = s.world().to_string();
    c.NonEmpty("world", world);
    if (c.ok() && world.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") != std::string::npos) {
      c.Fail("world '" + world + "' is not a world's name ([a-z0-9_])");
    }
  }
  if (c.ok() && s.kind() == msg::OPERATOR_END_TURN) c.NonEmpty("visitor", s.visitor().to_string());
  return c.reason();
}

std::string CheckDeviceState(const msg::DeviceState& s, std::string_view session, const SampleBounds& b) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("user", s.user().to_string());
  c.Vector("p_WH_m", s.p_WH_m(), 3, b.max_position_m);
  c.Quaternion("q_WH_wxyz", s.q_WH_wxyz());
  for (int i = 0; i < static_cast<int>(s.p_WE_m().size()) && c.ok(); ++i) {
    c.Vector("p_WE_m[" + std::to_string(i) + "]", s.p_WE_m()[i], 3, b.max_position_m);
    c.Vector("f_E_W_N[" + std::to_string(i) + "]", s.f_E_W_N()[i], 3, b.max_force_N);
  }
  c.Range("fingertip_radius_m", s.fingertip_radius_m(), 0.0, b.max_fingertip_radius_m);
  // A device has at least one of the five fingers.
  if (c.ok() && (s.absent_fingers() & ~0x1Fu) != 0) c.Fail("absent_fingers " + std::to_string(s.absent_fingers()) + " names a sixth finger");
  if (c.ok() && s.absent_fingers() == 0x1F) c.Fail("absent_fingers 31: a device without a finger");
  // Joint angles (screens draw a HIRO II's hand from them): finite, each within a few turns.
  for (std::size_t j = 0; j < s.q_hand_rad().size(); ++j) c.Range("q_hand_rad[" + std::to_string(j) + "]", s.q_hand_rad()[j], -20.0, 20.0);
  for (std::size_t j = 0; j < s.q_arm_rad().size(); ++j) c.Range("q_arm_rad[" + std::to_string(j) + "]", s.q_arm_rad()[j], -20.0, 20.0);
  return c.reason();
}

std::string CheckDeskInput(const msg::DeskInput& s, std::string_view session, const SampleBounds& b) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("user", s.user().to_string());
  c.Vector("p_WH_m", s.p_WH_m(), 3, b.max_position_m);
  c.Quaternion("q_WH_wxyz", s.q_WH_wxyz());
  for (std::size_t i = 0; i < s.closure().size(); ++i) c.Range("closure[" + std::to_string(i) + "]", s.closure()[i], 0.0, 1.0);
  return c.reason();
}

std::string CheckDeformation(const msg::Deformation& s, std::string_view session, const SampleBounds& b) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("object_id", s.object_id().to_string());
  if (c.ok() && s.u_W_m().size() != 3 * s.node_ids().size()) {
    c.Fail(std::to_string(s.u_W_m().size()) + " displacements for " + std::to_string(s.node_ids().size()) +
           " node ids (3 each)");
  }
  for (std::size_t i = 0; i < s.node_ids().size() && c.ok(); ++i) {
    if (s.surface_node_count() > 0 && s.node_ids()[i] >= s.surface_node_count()) {
      c.Fail("node_ids[" + std::to_string(i) + "] = " + std::to_string(s.node_ids()[i]) + " is not below " +
             "surface_node_count " + std::to_string(s.surface_node_count()));
    }
    const float* u = s.u_W_m().data() + 3 * i;
    c.Vector("u_W_m of node_ids[" + std::to_string(i) + "]", u, 3, b.max_displacement_m);
  }
  return c.reason();
}

std::string CheckMessageBoard(const msg::MessageBoard& s, std::string_view session) {
  Checker c;
  c.Session(s.session().to_string(), session);
  const std::string language = s.language().to_string();
  c.NonEmpty("language", language);
  if (c.ok() && language != "en" && language != "ja") c.Fail("language '" + language + "' is not en or ja");
  if (c.ok() && language == "ja") {
    const std::string reading = s.reading().to_string();
    c.NonEmpty("reading", reading);
    if (const auto at = common::FirstOutsideKanaReading(reading); c.ok() && at) {
      c.Fail("reading: byte " + std::to_string(*at) + " is not kana, ASCII, 、 or 。");
    }
  }
  return c.reason();
}

std::string CheckMemberInfo(const msg::MemberInfo& s, std::string_view session) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("user", s.user().to_string());
  const auto kind = static_cast<int>(s.kind());
  if (c.ok() && (kind < static_cast<int>(msg::NODE_WORLD_SERVER) || kind > static_cast<int>(msg::NODE_AUDIO_GUIDE))) {
    c.Fail("kind " + std::to_string(kind) + " is not a node kind");
  }
  c.Range("view_Hz", s.view_Hz(), 0.0, SampleBounds{}.max_rate_Hz);
  // The device's capabilities (all zero: no device): 1 to 5 points, as many fingers as points.
  const msg::DeviceCaps& d = s.device_caps();
  if (c.ok() && d.contact_points() > 0) {
    const int fingers = std::popcount(static_cast<unsigned>(d.finger_mask()));
    if (d.contact_points() > 5 || (d.finger_mask() & ~0x1Fu) != 0 || fingers != d.contact_points()) {
      c.Fail("device_caps: " + std::to_string(d.contact_points()) + " contact points on finger mask " +
             std::to_string(d.finger_mask()) + " (1 to 5 points, one per finger 0 to 4)");
    }
    c.Range("device_caps.max_force_N", d.max_force_N(), 0.0, SampleBounds{}.max_force_N);
    c.Range("device_caps.workspace_radius_m", d.workspace_radius_m(), 0.0, SampleBounds{}.max_position_m);
    c.Range("device_caps.rate_Hz", d.rate_Hz(), 0.0, 1e5);
  }
  return c.reason();
}

std::string CheckLoopStatistics(const msg::LoopStatistics& s, std::string_view session) {
  Checker c;
  c.Session(s.session().to_string(), session);
  c.NonEmpty("node", s.node().to_string());
  const std::pair<const char*, double> values[] = {
      {"rate_Hz", s.rate_Hz()},           {"jitter_p50_us", s.jitter_p50_us()}, {"jitter_p99_us", s.jitter_p99_us()},
      {"jitter_max_us", s.jitter_max_us()}, {"step_p50_us", s.step_p50_us()},     {"step_p99_us", s.step_p99_us()},
      {"latency_p50_us", s.latency_p50_us()}, {"sent_bytes_per_s", s.sent_bytes_per_s()}};
  for (const auto& [field, v] : values) c.Range(field, v, 0.0, 1e9);
  return c.reason();
}

std::string DroppedSamples::Count(std::string_view topic, std::string_view sender, const std::string& reason) {
  ++total_;
  auto it = by_topic_.find(topic);
  if (it == by_topic_.end()) it = by_topic_.emplace(std::string(topic), 0).first;
  const std::uint64_t n = ++it->second;
  // Each sender's first bad sample of a topic is named (at most kNamedSenders per topic: a flood
  // with forged names must not print a line per sample), then every 1000th of the topic.
  std::size_t& named = named_per_topic_[std::string(topic)];
  const bool first_of_sender = named < kNamedSenders && named_.emplace(std::string(topic), std::string(sender)).second;
  if (first_of_sender) ++named;
  if (!first_of_sender && n % 1000 != 0) return "";
  return "dropped a bad " + std::string(topic) + " sample from '" + std::string(sender) + "': " + reason + " (" +
         std::to_string(n) + " dropped on this topic so far)";
}

std::uint64_t DroppedSamples::of(std::string_view topic) const {
  const auto it = by_topic_.find(topic);
  return it == by_topic_.end() ? 0 : it->second;
}

std::string DroppedSamples::Summary() const {
  if (by_topic_.empty()) return "none";
  std::string out;
  for (const auto& [topic, n] : by_topic_) out += (out.empty() ? "" : ", ") + topic + " " + std::to_string(n);
  return out;
}

}  // namespace handshare::dds
