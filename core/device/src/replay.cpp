#include "handshare/haptic/replay.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "handshare/common/clock.hpp"

namespace handshare::haptic {

namespace {

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

}  // namespace

void WriteTraceHeader(std::ostream& out) {
  out << "seq,t_s,fault,hx,hy,hz,qw,qx,qy,qz";
  for (int i = 0; i < kFingers; ++i) out << ",x" << i << ",y" << i << ",z" << i;
  for (int i = 0; i < kFingers; ++i) out << ",fx" << i << ",fy" << i << ",fz" << i;
  out << ",stamp_ns";
  for (int i = 0; i < kFingers; ++i) out << ",jx" << i << ",jy" << i << ",jz" << i;
  out << ",fingers";  // the fingers the device has (bit f: finger f; 31 a whole hand)
  out << "\n";
}

void WriteTraceRow(std::ostream& out, const HapticSnapshot& s) {
  out << s.seq << "," << s.t_s << "," << (s.fault ? 1 : 0);
  for (double v : s.p_WH_m) out << "," << v;
  for (double v : s.q_WH_wxyz) out << "," << v;
  for (const auto& p : s.p_WE_m) out << "," << p[0] << "," << p[1] << "," << p[2];
  for (const auto& f : s.f_E_W_N) out << "," << f[0] << "," << f[1] << "," << f[2];
  // The host's steady clock (CLOCK_MONOTONIC), so a test can place events it timed itself.
  // Flushed per row: a test can follow the trace while the node runs (the bridge thread
  // writes it at the publish rate; the haptic thread never does).
  out << "," << s.stamp_ns;
  for (const auto& j : s.impulse_E_W_Ns) out << "," << j[0] << "," << j[1] << "," << j[2];
  out << "," << static_cast<unsigned>(s.finger_mask);
  out << "\n";
  out.flush();
}

ReplayLog ReplayLog::Parse(const std::string& text, const std::string& origin) {
  std::istringstream lines(text);
  std::string line;
  int line_no = 0;
  auto fail = [&](const std::string& what) -> void {
    throw ReplayError(origin + ":" + std::to_string(line_no) + ": " + what);
  };
  // Header: map column names to indices.
  std::map<std::string, std::size_t> column;
  std::size_t width = 0;
  while (std::getline(lines, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto names = SplitCsv(line);
    for (std::size_t i = 0; i < names.size(); ++i) column[names[i]] = i;
    width = names.size();
    break;
  }
  if (width == 0) throw ReplayError(origin + ": empty device-state log (no header line)");
  auto require = [&](const std::string& name) {
    const auto it = column.find(name);
    if (it == column.end()) fail("header has no column '" + name + "'");
    return it->second;
  };
  auto optional = [&](const std::string& name) {
    const auto it = column.find(name);
    return it == column.end() ? static_cast<std::size_t>(-1) : it->second;
  };
  const std::size_t c_t = require("t_s"), c_fault = require("fault");
  std::array<std::array<std::size_t, 3>, kFingers> c_tip{};
  for (int i = 0; i < kFingers; ++i) {
    const std::string n = std::to_string(i);
    c_tip[i] = {require("x" + n), require("y" + n), require("z" + n)};
  }
  const std::array<std::size_t, 3> c_hand = {optional("hx"), optional("hy"), optional("hz")};
  const std::array<std::size_t, 4> c_q = {optional("qw"), optional("qx"), optional("qy"), optional("qz")};
  const std::size_t c_fingers = optional("fingers");  // older logs: a whole hand

  ReplayLog log;
  while (std::getline(lines, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto cells = SplitCsv(line);
    if (cells.size() != width) {
      fail("expected " + std::to_string(width) + " columns, found " + std::to_string(cells.size()));
    }
    auto number = [&](std::size_t c) {
      const std::string& s = cells[c];
      char* end = nullptr;
      const double v = std::strtod(s.c_str(), &end);
      if (s.empty() || *end != '\0') fail("column '" + [&] {
        for (const auto& [name, idx] : column) {
          if (idx == c) return name;
        }
        return std::string("?");
      }() + "': '" + s + "' is not a number");
      return v;
    };
    ReplaySample sample;
    sample.t_s = number(c_t);
    if (!std::isfinite(sample.t_s)) fail("column 't_s' is not finite");
    if (!log.samples_.empty() && sample.t_s < log.samples_.back().t_s) {
      fail("t_s goes backwards (" + cells[c_t] + " after " + std::to_string(log.samples_.back().t_s) + ")");
    }
    // Non-finite positions are kept: they replay as what they were, device data the loop
    // must survive (it turns them into a fault and zero force).
    sample.fault = number(c_fault) != 0.0;
    for (int i = 0; i < kFingers; ++i) {
      for (int k = 0; k < 3; ++k) sample.p_WE[i][k] = number(c_tip[i][k]);
    }
    if (c_hand[0] != static_cast<std::size_t>(-1) && c_hand[1] != static_cast<std::size_t>(-1) &&
        c_hand[2] != static_cast<std::size_t>(-1)) {
      for (int k = 0; k < 3; ++k) sample.p_WH[k] = number(c_hand[k]);
    } else {
      for (const auto& p : sample.p_WE) sample.p_WH += p / kFingers;
    }
    if (std::all_of(c_q.begin(), c_q.end(), [](std::size_t c) { return c != static_cast<std::size_t>(-1); })) {
      for (int k = 0; k < 4; ++k) sample.q_WH_wxyz[k] = number(c_q[k]);
    }
    if (c_fingers != static_cast<std::size_t>(-1)) {
      const double mask = number(c_fingers);
      if (!(mask >= 1.0 && mask <= kEveryFinger) || mask != std::floor(mask)) {
        fail("column 'fingers': '" + cells[c_fingers] + "' is not a finger mask (1 to 31)");
      }
      const auto m = static_cast<FingerMask>(mask);
      if (!log.samples_.empty() && m != log.finger_mask_) {
        fail("column 'fingers' changes from " + std::to_string(log.finger_mask_) + " to " + cells[c_fingers] +
             " (one device per log)");
      }
      log.finger_mask_ = m;
    }
    log.samples_.push_back(sample);
  }
  if (log.samples_.empty()) throw ReplayError(origin + ": device-state log has a header but no samples");
  return log;
}

ReplayLog ReplayLog::Load(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ReplayError(file.string() + ": cannot open device-state log");
  std::stringstream text;
  text << in.rdbuf();
  return Parse(text.str(), file.string());
}

void ReplayDevice::Read(double t_s, DeviceReading& out) noexcept {
  const auto& s = log_.samples();
  const double t0 = s.front().t_s;
  double t = t0 + t_s;
  if (loop_ && log_.duration_s() > 0.0) t = t0 + std::fmod(t_s, log_.duration_s());
  // Time runs forward: advance the cursor; a jump back (loop, restart) rescans from the start.
  if (cursor_ >= s.size() || s[cursor_].t_s > t) cursor_ = 0;
  while (cursor_ + 1 < s.size() && s[cursor_ + 1].t_s <= t) ++cursor_;
  const ReplaySample& a = s[cursor_];
  const ReplaySample& b = cursor_ + 1 < s.size() ? s[cursor_ + 1] : a;
  const double span = b.t_s - a.t_s;
  const double w = span > 0.0 ? std::clamp((t - a.t_s) / span, 0.0, 1.0) : 0.0;
  out.stamp_ns = common::SteadyNowNs();
  out.p_WH = a.p_WH + w * (b.p_WH - a.p_WH);
  out.q_WH_wxyz = (a.q_WH_wxyz + w * (b.q_WH_wxyz - a.q_WH_wxyz)).normalized();
  for (int i = 0; i < kFingers; ++i) out.p_WE[i] = a.p_WE[i] + w * (b.p_WE[i] - a.p_WE[i]);
  out.valid = !a.fault && !(w > 0.0 && b.fault);
  out.finger_mask = log_.finger_mask();
}

}  // namespace handshare::haptic
