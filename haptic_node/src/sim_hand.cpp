#include "handshare/haptic/sim_hand.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

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

HandScript HandScript::Parse(const std::string& text, const std::string& origin) {
  HandScript script;
  bool started = false;
  double t = 0.0;
  HandPose current;
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
    double duration = 0.0;
    auto read_position = [&] {
      target.p_WH.x() = p.Number("x", -kMaxReach_m, kMaxReach_m);
      target.p_WH.y() = p.Number("y", -kMaxReach_m, kMaxReach_m);
      target.p_WH.z() = p.Number("z", -kMaxReach_m, kMaxReach_m);
    };
    auto read_optional_grip = [&] {
      std::string word;
      if (!p.Word(word)) return;
      if (word != "grip") p.Fail("expected 'grip' or end of line, got '" + word + "'");
      target.grip = p.Number("grip", 0.0, 1.0);
      if (p.Word(word)) p.Fail("unexpected '" + word + "' at end of line");
    };
    if (cmd == "start") {
      if (started || !script.segments_.empty()) p.Fail("'start' must be the first command");
      read_position();
      read_optional_grip();
      script.start_ = current = target;
      started = true;
      continue;
    }
    if (!started) p.Fail("the script must begin with 'start X Y Z'");
    if (cmd == "move") {
      duration = p.Number("duration", 1e-3, kMaxDuration_s);
      read_position();
      read_optional_grip();
    } else if (cmd == "grip") {
      duration = p.Number("duration", 1e-3, kMaxDuration_s);
      target.grip = p.Number("grip", 0.0, 1.0);
    } else if (cmd == "hold") {
      duration = p.Number("duration", 1e-3, kMaxDuration_s);
    } else {
      p.Fail("unknown command '" + cmd + "' (start, move, grip, hold)");
    }
    std::string extra;
    if (cmd != "move" && p.Word(extra)) p.Fail("unexpected '" + extra + "' at end of line");
    script.segments_.push_back(ScriptSegment{t, t + duration, current, target});
    t += duration;
    current = target;
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
      return pose;
    }
  }
  return segments_.back().to;
}

std::array<Eigen::Vector3d, kFingers> SimFingertips(const HandPose& pose) noexcept {
  // Open hand: fingertips of a flat hand, four fingers 24 mm apart (HIRO-II.md), thumb
  // 60 mm back and 45 mm to the side. Closed: every fingertip near a grasp centre 60 mm in
  // front of the palm. Grip interpolates linearly between the two.
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
  const double g = std::clamp(pose.grip, 0.0, 1.0);
  std::array<Eigen::Vector3d, kFingers> p_WE;
  for (int i = 0; i < kFingers; ++i) p_WE[i] = pose.p_WH + (1.0 - g) * kOpen[i] + g * kClosed[i];
  return p_WE;
}

void SimDevice::Read(double t_s, DeviceReading& out) noexcept {
  const HandPose pose = script_.PoseAt(t_s);
  out.p_WH = pose.p_WH;
  out.q_WH_wxyz = Eigen::Vector4d(1, 0, 0, 0);
  out.p_WE = SimFingertips(pose);
  out.valid = true;
}

}  // namespace handshare::haptic
