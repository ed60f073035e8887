#include "handshare/haptic/sim_hand.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string_view>

namespace handshare::haptic {

namespace {

// Minimum-jerk profile s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 on tau in [0, 1].
double MinimumJerk(double tau) noexcept {
  tau = std::clamp(tau, 0.0, 1.0);
  return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
}

class LineParser {
 public:
  LineParser(const std::string& origin, int line, const std::string& text)
      : origin_(origin), line_(line), in_(text) {}
  [[noreturn]] void Fail(const std::string& what) const {
    throw ScriptError(origin_ + ":" + std::to_string(line_) + ": " + what);
  }
  double Number(const char* field, double min, double max) {
    std::string token;
    if (!(in_ >> token)) Fail(std::string("missing ") + field);
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (*end != '\0' || !std::isfinite(v)) Fail(std::string(field) + ": '" + token + "' is not a number");
    if (v < min || v > max) {
      std::ostringstream s;
      s << field << ": " << v << " is outside [" << min << ", " << max << "]";
      Fail(s.str());
    }
    return v;
  }
  bool Word(std::string& out) { return static_cast<bool>(in_ >> out); }

 private:
  std::string origin_;
  int line_;
  std::istringstream in_;
};

constexpr double kMaxReach_m = 2.0;  // sanity bound on script positions
constexpr double kMaxDuration_s = 1e5;

}  // namespace

namespace {

// Fingertip offsets from the hand base for a grip value: an open flat hand, four fingers
// 24 mm apart (HIRO-II.md), thumb 60 mm back and 45 mm to the side; closed: every fingertip
// near a grasp centre 60 mm in front of the palm. Grip interpolates linearly.
std::array<Eigen::Vector3d, kFingers> GripOffsets(double grip) noexcept {
  static const std::array<Eigen::Vector3d, kFingers> kOpen = {
      Eigen::Vector3d(-0.060, 0.040, -0.010),  // thumb
      Eigen::Vector3d(-0.036, 0.100, 0.000),   // index
      Eigen::Vector3d(-0.012, 0.105, 0.000),   // middle
      Eigen::Vector3d(0.012, 0.100, 0.000),    // ring
      Eigen::Vector3d(0.036, 0.090, 0.000)};   // little
  static const std::array<Eigen::Vector3d, kFingers> kClosed = {
      Eigen::Vector3d(-0.025, 0.060, -0.030), Eigen::Vector3d(0.000, 0.075, -0.020),
      Eigen::Vector3d(0.012, 0.070, -0.025), Eigen::Vector3d(0.020, 0.062, -0.028),
      Eigen::Vector3d(0.024, 0.055, -0.030)};
  const double g = std::clamp(grip, 0.0, 1.0);
  std::array<Eigen::Vector3d, kFingers> p_HE;
  for (int i = 0; i < kFingers; ++i) p_HE[i] = (1.0 - g) * kOpen[i] + g * kClosed[i];
  return p_HE;
}

// Pointing hand: the index fingertip 40 mm below and ahead of the curled fingers, so only it
// touches what it pokes or presses.
constexpr int kThumb = 0, kIndex = 1;
const std::array<Eigen::Vector3d, kFingers> kPointShape = {
    Eigen::Vector3d(-0.040, 0.040, 0.000), Eigen::Vector3d(-0.030, 0.100, -0.040),
    Eigen::Vector3d(-0.010, 0.050, 0.010), Eigen::Vector3d(0.010, 0.045, 0.010),
    Eigen::Vector3d(0.030, 0.040, 0.010)};

// A hand pose whose fingertips are at the given world points (shape weight 1).
HandPose ShapedAt(const Eigen::Vector3d& p_WH, const std::array<Eigen::Vector3d, kFingers>& p_WE) {
  HandPose pose;
  pose.p_WH = p_WH;
  pose.shape_weight = 1.0;
  for (int i = 0; i < kFingers; ++i) pose.p_HE_shape[i] = p_WE[i] - p_WH;
  return pose;
}

}  // namespace

HandScript HandScript::Parse(const std::string& text, const std::string& origin) {
  HandScript script;
  bool started = false;
  double t = 0.0;
  HandPose current;
  // Appends a segment from the current pose. An unshaped end carries its grip offsets as its
  // shape, so blending between grip and task shapes moves every fingertip along a straight,
  // minimum-jerk path.
  auto add = [&](double duration, HandPose target) {
    HandPose from = current;
    if (from.shape_weight == 0.0) from.p_HE_shape = GripOffsets(from.grip);
    if (target.shape_weight == 0.0) target.p_HE_shape = GripOffsets(target.grip);
    script.segments_.push_back(ScriptSegment{t, t + duration, from, target});
    t += duration;
    current = target;
  };
  std::istringstream lines(text);
  std::string raw;
  int line_no = 0;
  while (std::getline(lines, raw)) {
    ++line_no;
    if (const auto hash = raw.find('#'); hash != std::string::npos) raw.resize(hash);
    LineParser p(origin, line_no, raw);
    std::string cmd;
    if (!p.Word(cmd)) continue;  // blank or comment
    HandPose target = current;
    auto read_point = [&] {
      Eigen::Vector3d v;
      v.x() = p.Number("x", -kMaxReach_m, kMaxReach_m);
      v.y() = p.Number("y", -kMaxReach_m, kMaxReach_m);
      v.z() = p.Number("z", -kMaxReach_m, kMaxReach_m);
      return v;
    };
    auto read_delta = [&] {
      Eigen::Vector3d v;
      v.x() = p.Number("dx", -kMaxReach_m, kMaxReach_m);
      v.y() = p.Number("dy", -kMaxReach_m, kMaxReach_m);
      v.z() = p.Number("dz", -kMaxReach_m, kMaxReach_m);
      return v;
    };
    auto read_optional_grip = [&] {
      std::string word;
      if (!p.Word(word)) return;
      if (word != "grip") p.Fail("expected 'grip' or end of line, got '" + word + "'");
      target.grip = p.Number("grip", 0.0, 1.0);
      target.shape_weight = 0.0;
      if (p.Word(word)) p.Fail("unexpected '" + word + "' at end of line");
    };
    auto end_of_line = [&] {
      std::string extra;
      if (p.Word(extra)) p.Fail("unexpected '" + extra + "' at end of line");
    };
    auto optional_number = [&](const char* field, double min, double max, double fallback) {
      std::string word;
      if (!p.Word(word)) return fallback;
      LineParser q(origin, line_no, word);
      const double v = q.Number(field, min, max);
      end_of_line();
      return v;
    };
    if (cmd == "start") {
      if (started || !script.segments_.empty()) p.Fail("'start' must be the first command");
      target.p_WH = read_point();
      read_optional_grip();
      script.start_ = current = target;
      started = true;
      continue;
    }
    if (!started) p.Fail("the script must begin with 'start X Y Z'");
    if (cmd == "await_world") {
      std::string world;
      if (!p.Word(world)) {
        // Plain: the first world, at the start only (later it would always be here already).
        if (!script.segments_.empty() || !script.waits_.empty()) {
          p.Fail("'await_world' must come right after 'start' (later in a script, name the world: "
                 "await_world NAME)");
        }
        script.waits_.push_back(WorldWait{t, {}, line_no});
        continue;
      }
      const bool is_name = std::isalpha(static_cast<unsigned char>(world.front())) &&
                           std::all_of(world.begin(), world.end(), [](char c) {
                             return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
                           });
      if (!is_name) {
        p.Fail("await_world: '" + world + "' is not a world name (a scene name such as solar_system; "
               "to wait a time, use hold DUR)");
      }
      end_of_line();
      script.waits_.push_back(WorldWait{t, world, line_no});
      continue;
    }
    static constexpr std::array<std::string_view, 11> kVerbs = {
        "move", "reach", "grip", "hold", "poke", "press", "pinch", "grasp", "lift", "pull", "release"};
    if (std::find(kVerbs.begin(), kVerbs.end(), cmd) == kVerbs.end()) {
      p.Fail("unknown command '" + cmd +
             "' (start, await_world, move, reach, grip, hold, poke, press, pinch, grasp, lift, pull, release)");
    }
    const double duration = p.Number("duration", 1e-3, kMaxDuration_s);
    if (cmd == "move") {
      target.p_WH = read_point();
      read_optional_grip();
      add(duration, target);
    } else if (cmd == "reach") {
      target = HandPose{read_point(), 0.2};
      end_of_line();
      add(duration, target);
    } else if (cmd == "grip") {
      target.grip = p.Number("grip", 0.0, 1.0);
      target.shape_weight = 0.0;
      end_of_line();
      add(duration, target);
    } else if (cmd == "hold") {
      end_of_line();
      add(duration, target);
    } else if (cmd == "poke" || cmd == "press") {
      const Eigen::Vector3d p_WI = read_point();
      const double depth = cmd == "press" ? p.Number("depth", 0.0, 0.2) : 0.0;
      end_of_line();
      std::array<Eigen::Vector3d, kFingers> p_WE;
      const Eigen::Vector3d p_WH = p_WI - kPointShape[kIndex];
      for (int i = 0; i < kFingers; ++i) p_WE[i] = p_WH + kPointShape[i];
      const HandPose at = ShapedAt(p_WH, p_WE);
      if (cmd == "poke") {
        add(duration, at);
      } else {
        HandPose down = at;
        down.p_WH.z() -= depth;
        add(duration / 3.0, at);
        add(duration / 3.0, down);
        add(duration / 3.0, at);
      }
    } else if (cmd == "pinch") {
      const Eigen::Vector3d p_WC = read_point();
      const double width = optional_number("width", 0.0, 0.2, 2.0 * kSimFingertipRadius_m);
      const Eigen::Vector3d p_WH = p_WC + Eigen::Vector3d(0.0, -0.07, 0.02);
      std::array<Eigen::Vector3d, kFingers> p_WE;
      for (int i = 0; i < kFingers; ++i) p_WE[i] = p_WH + kPointShape[i] + Eigen::Vector3d(0, 0, 0.02);
      p_WE[kThumb] = p_WC - Eigen::Vector3d(0.5 * width, 0, 0);
      p_WE[kIndex] = p_WC + Eigen::Vector3d(0.5 * width, 0, 0);
      add(duration, ShapedAt(p_WH, p_WE));
    } else if (cmd == "grasp") {
      const Eigen::Vector3d p_WC = read_point();
      const double radius = p.Number("radius", 1e-3, 1.0);
      const double squeeze = optional_number("squeeze", 0.0, kSimFingertipRadius_m, 0.002);
      // Five fingertips 72 deg apart around the vertical (their pushes cancel sideways), the
      // thumb on the user's side, 15 deg below the equator (their pushes hold the object up).
      const double contact_m = radius + kSimFingertipRadius_m - squeeze;
      const double elevation = -15.0 * std::numbers::pi / 180.0;
      // Like a person: shape the hand above the object, come down beside it, then close in
      // (40, 30, 30% of the time), so no fingertip path cuts through the object.
      const double open_m = contact_m + 0.02;
      std::array<Eigen::Vector3d, kFingers> hover, beside, p_WE;
      for (int i = 0; i < kFingers; ++i) {
        const double azimuth = -0.5 * std::numbers::pi + 2.0 * std::numbers::pi * i / kFingers;
        const Eigen::Vector3d n(std::cos(elevation) * std::cos(azimuth),
                                std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
        p_WE[i] = p_WC + contact_m * n;
        beside[i] = p_WC + open_m * n;
        hover[i] = beside[i] + Eigen::Vector3d(0, 0, radius + open_m);
      }
      const Eigen::Vector3d p_WH = p_WC + Eigen::Vector3d(0.0, -0.02, radius + 0.05);
      add(0.4 * duration, ShapedAt(p_WH + Eigen::Vector3d(0, 0, radius + open_m), hover));
      add(0.3 * duration, ShapedAt(p_WH, beside));
      add(0.3 * duration, ShapedAt(p_WH, p_WE));
    } else if (cmd == "lift" || cmd == "pull") {
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      if (cmd == "lift") {
        d.z() = p.Number("dz", -kMaxReach_m, kMaxReach_m);
      } else {
        d = read_delta();
      }
      end_of_line();
      target.p_WH += d;
      add(duration, target);
    } else if (cmd == "release") {
      end_of_line();
      const auto p_WE = SimFingertips(current);
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (const auto& e : p_WE) centroid += e / kFingers;
      std::array<Eigen::Vector3d, kFingers> away;
      for (int i = 0; i < kFingers; ++i) {
        const Eigen::Vector3d r = p_WE[i] - centroid;
        away[i] = p_WE[i] + (r.norm() > 1e-9 ? Eigen::Vector3d(0.03 * r.normalized()) : Eigen::Vector3d(0, 0, 0.03));
      }
      // Open away from the object, then lift clear of it (40, 60% of the time), so the next
      // move does not sweep through what was just let go.
      add(0.4 * duration, ShapedAt(current.p_WH, away));
      std::array<Eigen::Vector3d, kFingers> above = away;
      for (auto& tip : above) tip.z() += 0.05;
      add(0.6 * duration, ShapedAt(current.p_WH + Eigen::Vector3d(0, 0, 0.05), above));
    }
  }
  if (!started) throw ScriptError(origin + ": empty script (needs at least 'start X Y Z')");
  return script;
}

HandScript HandScript::Load(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ScriptError(file.string() + ": cannot open hand script");
  std::stringstream text;
  text << in.rdbuf();
  return Parse(text.str(), file.string());
}

HandScript HandScript::Default(const Eigen::Vector3d& p_center) {
  std::ostringstream s;
  const auto& c = p_center;
  s << "start " << c.x() << " " << c.y() << " " << c.z() + 0.05 << "\n"
    << "move 1.5 " << c.x() << " " << c.y() << " " << c.z() << " grip 0.3\n"
    << "hold 0.5\n"
    << "move 1.5 " << c.x() << " " << c.y() << " " << c.z() + 0.05 << " grip 0\n";
  return Parse(s.str(), "default script");
}

HandPose HandScript::PoseAt(double t_s) const noexcept {
  if (segments_.empty() || t_s <= segments_.front().t0_s) return start_;
  // Segments are few (a script is written by hand): a linear scan is cheap and allocation-free.
  for (const auto& seg : segments_) {
    if (t_s < seg.t1_s) {
      const double s = MinimumJerk((t_s - seg.t0_s) / (seg.t1_s - seg.t0_s));
      HandPose pose;
      pose.p_WH = seg.from.p_WH + s * (seg.to.p_WH - seg.from.p_WH);
      pose.grip = seg.from.grip + s * (seg.to.grip - seg.from.grip);
      pose.shape_weight = seg.from.shape_weight + s * (seg.to.shape_weight - seg.from.shape_weight);
      for (int i = 0; i < kFingers; ++i) {
        pose.p_HE_shape[i] = seg.from.p_HE_shape[i] + s * (seg.to.p_HE_shape[i] - seg.from.p_HE_shape[i]);
      }
      return pose;
    }
  }
  return segments_.back().to;
}

std::array<Eigen::Vector3d, kFingers> SimFingertips(const HandPose& pose) noexcept {
  const auto grip = GripOffsets(pose.grip);
  const double w = std::clamp(pose.shape_weight, 0.0, 1.0);
  std::array<Eigen::Vector3d, kFingers> p_WE;
  for (int i = 0; i < kFingers; ++i) p_WE[i] = pose.p_WH + (1.0 - w) * grip[i] + w * pose.p_HE_shape[i];
  return p_WE;
}

ScriptClock::ScriptClock(const HandScript& script) {
  for (const auto& wait : script.waits()) {
    std::uint64_t code = kNoWorld;
    if (!wait.world.empty()) {
      auto it = std::find(names_.begin(), names_.end(), wait.world);
      if (it == names_.end()) it = names_.insert(names_.end(), wait.world);
      code = static_cast<std::uint64_t>(it - names_.begin()) + 1;
    }
    wait_t_s_.push_back(wait.t_s);
    wait_code_.push_back(code);
  }
  static_assert(std::atomic<std::uint64_t>::is_always_lock_free && std::atomic<double>::is_always_lock_free);
}

std::uint64_t ScriptClock::CodeOf(std::string_view world) const noexcept {
  for (std::size_t i = 0; i < names_.size(); ++i) {
    if (names_[i] == world) return static_cast<std::uint64_t>(i) + 1;
  }
  return kOtherWorld;
}

bool ScriptClock::OnWorldReady(double t_s, std::string_view world) noexcept {
  if (wait_t_s_.empty() || !std::isfinite(t_s)) return false;
  t_s = std::max(t_s, 0.0);
  bool first = false;
  // The first world: compare_exchange compares bit patterns, so it matches the NaN just read.
  double none = first_world_s_.load();
  while (std::isnan(none)) {
    if (first_world_s_.compare_exchange_weak(none, t_s)) {
      first = true;
      break;
    }
  }
  // The current world, with the time it arrived; a new revision of it keeps that time.
  const std::uint64_t code = CodeOf(world);
  const std::uint64_t arrived = (static_cast<std::uint64_t>(std::llround(t_s * 1e6)) << 16) | code;
  std::uint64_t old = world_.load();
  bool changed = false;
  while ((old & 0xFFFF) != code) {
    if (world_.compare_exchange_weak(old, arrived)) {
      changed = true;
      break;
    }
  }
  // A script that holds at its very start begins now if this is the world it awaits there.
  const bool starts = wait_t_s_.front() <= 0.0 && (wait_code_.front() == kNoWorld ? first
                                                     : changed && code == wait_code_.front());
  return starts && !start_released_.exchange(true);
}

double ScriptClock::ScriptTime(double t_s) noexcept {
  while (next_ < wait_t_s_.size()) {
    const double t_wait = wait_t_s_[next_];
    if (t_s - origin_s_ < t_wait) break;  // not there yet
    // The script is at this wait (since device time origin_s_ + t_wait): is its world here,
    // and since when?
    double arrived_s = 0.0;
    if (wait_code_[next_] == kNoWorld) {
      arrived_s = first_world_s_.load(std::memory_order_acquire);
      if (std::isnan(arrived_s)) return t_wait;  // hold
    } else {
      const std::uint64_t now = world_.load(std::memory_order_acquire);
      if ((now & 0xFFFF) != wait_code_[next_]) return t_wait;  // hold
      arrived_s = static_cast<double>(now >> 16) * 1e-6;
    }
    // Already here when the script got to the wait: no hold. Else run on from its arrival
    // (not later than now: the bridge's clock may be read just after this thread's).
    origin_s_ = std::max(origin_s_, std::min(arrived_s, t_s) - t_wait);
    ++next_;
  }
  return t_s - origin_s_;
}

bool SimDevice::OnWorldReady(double t_s, std::string_view world) noexcept {
  return clock_.OnWorldReady(t_s, world);
}

void SimDevice::Read(double t_s, DeviceReading& out) noexcept {
  const HandPose pose = script_.PoseAt(clock_.ScriptTime(t_s));
  out.p_WH = pose.p_WH;
  out.q_WH_wxyz = Eigen::Vector4d(1, 0, 0, 0);
  out.p_WE = SimFingertips(pose);
  out.valid = true;
}

}  // namespace handshare::haptic
