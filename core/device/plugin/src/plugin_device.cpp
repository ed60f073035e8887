#include "handshare/haptic/plugin_device.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "handshare/common/clock.hpp"

namespace handshare::haptic {

namespace {

const char* const kFingerNames[kFingers] = {"thumb", "index", "middle", "ring", "little"};

/// The stated capabilities, checked field by field: what is wrong, or "" when they hold.
std::string CheckCapabilities(const hs_device_caps& c) {
  if (c.points < 1 || c.points > HS_DEVICE_MAX_POINTS) {
    return "caps.points is " + std::to_string(c.points) + " (must be 1 to " + std::to_string(HS_DEVICE_MAX_POINTS) + ")";
  }
  unsigned seen = 0;
  for (std::uint32_t i = 0; i < c.points; ++i) {
    const std::string at = "caps.finger[" + std::to_string(i) + "]";
    if (c.finger[i] >= static_cast<std::uint32_t>(kFingers)) return at + " is " + std::to_string(c.finger[i]) + " (must be 0 thumb to 4 little)";
    if ((seen >> c.finger[i]) & 1u) return at + " repeats finger " + std::to_string(c.finger[i]);
    seen |= 1u << c.finger[i];
    if (!std::isfinite(c.max_force_N[i]) || c.max_force_N[i] <= 0.0) {
      return "caps.max_force_N[" + std::to_string(i) + "] is " + std::to_string(c.max_force_N[i]) + " (must be > 0)";
    }
  }
  if (!std::isfinite(c.workspace_radius_m) || c.workspace_radius_m <= 0.0) {
    return "caps.workspace_radius_m is " + std::to_string(c.workspace_radius_m) + " (must be > 0)";
  }
  if (!std::isfinite(c.rate_Hz) || c.rate_Hz <= 0.0) return "caps.rate_Hz is " + std::to_string(c.rate_Hz) + " (must be > 0)";
  if (std::memchr(c.model, '\0', sizeof c.model) == nullptr) return "caps.model is not NUL-terminated";
  return "";
}

bool Finite3(const double p[3]) noexcept { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

}  // namespace

PluginDeviceOptions PluginDeviceOptions::FromSpec(const std::string& spec) {
  const std::string prefix = "plugin:";
  if (spec.rfind(prefix, 0) != 0 || spec.size() == prefix.size() || spec[prefix.size()] == ':') {
    throw std::invalid_argument("option --device: '" + spec + "' is not plugin:PATH.so[:ARGS]");
  }
  PluginDeviceOptions o;
  const std::string rest = spec.substr(prefix.size());
  // The path ends at the first ':' after ".so" (a path may hold colons only before its .so).
  const std::size_t so = rest.find(".so");
  const std::size_t colon = rest.find(':', so == std::string::npos ? 0 : so);
  o.path = rest.substr(0, colon);
  if (colon != std::string::npos) o.args = rest.substr(colon + 1);
  return o;
}

std::unique_ptr<PluginDevice> PluginDevice::Open(const PluginDeviceOptions& options) {
  const std::string who = "device plug-in " + options.path;
  if (!(options.deadline_s > 0.0) || !(options.max_jump_m > 0.0) || !(options.scale > 0.0) || !options.origin_W.allFinite()) {
    throw std::runtime_error(who + ": deadline, jump bound and scale must be > 0 and the origin finite");
  }
  std::unique_ptr<PluginDevice> d(new PluginDevice());
  d->options_ = options;
  d->deadline_ns_ = static_cast<std::int64_t>(std::llround(options.deadline_s * 1e9));
  // RTLD_NOW: an unresolved symbol fails here, with the loader's message, not at the first step.
  d->library_ = dlopen(options.path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (d->library_ == nullptr) {
    const char* why = dlerror();
    throw std::runtime_error(who + ": cannot load: " + (why ? why : "unknown dlopen error"));
  }
  dlerror();
  void* const entry = dlsym(d->library_, HS_DEVICE_ENTRY_NAME);
  if (entry == nullptr) {
    throw std::runtime_error(who + ": exports no function " HS_DEVICE_ENTRY_NAME " (is it a handshare device plug-in?)");
  }
  // POSIX: a function pointer converts to and from void* (dlsym's documented use).
  hs_device_plugin_entry get = nullptr;
  static_assert(sizeof get == sizeof entry);
  std::memcpy(&get, &entry, sizeof get);
  d->plugin_ = get();
  if (d->plugin_ == nullptr) throw std::runtime_error(who + ": " HS_DEVICE_ENTRY_NAME "() returned no table");
  if (d->plugin_->abi_version != HS_DEVICE_ABI_VERSION) {
    throw std::runtime_error(who + ": built for device ABI version " + std::to_string(d->plugin_->abi_version) +
                             ", this handshare reads version " + std::to_string(HS_DEVICE_ABI_VERSION) +
                             " (rebuild it against handshare/device_plugin.h)");
  }
  const hs_device_plugin& p = *d->plugin_;
  if (p.open == nullptr || p.read == nullptr || p.command == nullptr || p.close == nullptr || p.name == nullptr) {
    throw std::runtime_error(who + ": its table lacks name, open, read, command or close");
  }
  char error[256] = {};
  d->device_ = p.open(options.args.c_str(), &d->plugin_caps_, error, sizeof error);
  error[sizeof error - 1] = '\0';
  if (d->device_ == nullptr) {
    throw std::runtime_error(who + ": open(\"" + options.args + "\") failed: " + (error[0] ? error : "no reason given"));
  }
  if (const std::string bad = CheckCapabilities(d->plugin_caps_); !bad.empty()) {
    throw std::runtime_error(who + ": states impossible capabilities: " + bad);  // the destructor closes it
  }
  const hs_device_caps& c = d->plugin_caps_;
  DeviceCapabilities& caps = d->caps_;
  caps.fingers = static_cast<int>(c.points);
  caps.finger_mask = 0;
  caps.max_fingertip_force_N = c.max_force_N[0];
  for (std::uint32_t i = 0; i < c.points; ++i) {
    caps.finger_mask = static_cast<FingerMask>(caps.finger_mask | (1u << c.finger[i]));
    caps.max_fingertip_force_N = std::min(caps.max_fingertip_force_N, c.max_force_N[i]);
  }
  caps.workspace_radius_m = options.scale * c.workspace_radius_m;
  caps.control_rate_Hz = c.rate_Hz;
  caps.has_gripper = c.has_gripper != 0;
  for (auto& last : d->last_p_WE_) last = options.origin_W;  // where a point "was" before its first good read
  d->name_ = std::string("plugin:") + std::string(p.name).substr(0, 24);
  return d;
}

PluginDevice::~PluginDevice() {
  if (device_ != nullptr) plugin_->close(device_);
  if (library_ != nullptr) dlclose(library_);
}

void PluginDevice::Read(double /*t_s*/, DeviceReading& out) noexcept {
  const std::int64_t t0 = static_cast<std::int64_t>(common::SteadyNowNs());
  const int rc = plugin_->read(device_, &sample_);
  const std::uint64_t t1 = common::SteadyNowNs();
  bool ok = !command_fault_;  // the last command failed or overran: this step is a fault too
  command_fault_ = false;
  if (rc != 0) {
    read_errors_.fetch_add(1, std::memory_order_relaxed);
    ok = false;
  }
  if (static_cast<std::int64_t>(t1) - t0 > deadline_ns_) {
    overruns_.fetch_add(1, std::memory_order_relaxed);
    ok = false;
  }
  const hs_device_caps& c = plugin_caps_;
  bool finite = true;
  bool jumped = false;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::uint32_t i = 0; i < c.points; ++i) {
    const int f = static_cast<int>(c.finger[i]);
    if (!Finite3(sample_.p_D_m[i])) {
      finite = false;
      continue;
    }
    const Eigen::Vector3d p_W = options_.origin_W + options_.scale * Eigen::Vector3d(sample_.p_D_m[i][0], sample_.p_D_m[i][1], sample_.p_D_m[i][2]);
    if (have_last_ && (p_W - last_p_WE_[f]).norm() > options_.max_jump_m) jumped = true;
    last_p_WE_[f] = p_W;  // the next read compares with this one: a jump is one fault, not many
    out.p_WE[f] = p_W;
    sum += p_W;
  }
  Eigen::Vector4d q(1.0, 0.0, 0.0, 0.0);
  if (c.has_orientation != 0) {
    q = Eigen::Vector4d(sample_.q_D_wxyz[0], sample_.q_D_wxyz[1], sample_.q_D_wxyz[2], sample_.q_D_wxyz[3]);
    const double n = q.norm();
    if (!std::isfinite(n) || n < 0.5 || n > 2.0) {
      finite = false;
    } else {
      q /= n;
    }
  }
  if (!finite) {
    not_finite_.fetch_add(1, std::memory_order_relaxed);
    // Nothing non-finite leaves: the points stay where they last were (the loop publishes no
    // pose of a faulted reading, and the safety sees no jump when the data comes back).
    sum.setZero();
    for (std::uint32_t i = 0; i < c.points; ++i) {
      out.p_WE[c.finger[i]] = last_p_WE_[c.finger[i]];
      sum += last_p_WE_[c.finger[i]];
    }
    q = Eigen::Vector4d(1.0, 0.0, 0.0, 0.0);
  }
  if (jumped) jumps_.fetch_add(1, std::memory_order_relaxed);
  have_last_ = finite;
  ok = ok && finite && !jumped;
  // The hand base: the points' centre (a stylus: its tip), turned as the handle is.
  out.p_WH = sum / static_cast<double>(c.points);
  out.q_WH_wxyz = q;
  // Fingers the device lacks sit at the base, out of finger_mask: nothing simulates them.
  for (int f = 0; f < kFingers; ++f) {
    if (!HasFinger(caps_.finger_mask, f)) out.p_WE[f] = out.p_WH;
  }
  out.finger_mask = caps_.finger_mask;
  out.stamp_ns = t1;
  out.valid = ok;
}

void PluginDevice::Command(const std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept {
  const hs_device_caps& c = plugin_caps_;
  for (std::uint32_t i = 0; i < c.points; ++i) {
    for (int k = 0; k < 3; ++k) f_D_N_[i][k] = f_E_W[c.finger[i]][k];
  }
  const std::int64_t t0 = static_cast<std::int64_t>(common::SteadyNowNs());
  const int rc = plugin_->command(device_, f_D_N_);
  if (rc != 0) {
    read_errors_.fetch_add(1, std::memory_order_relaxed);
    command_fault_ = true;
  }
  if (static_cast<std::int64_t>(common::SteadyNowNs()) - t0 > deadline_ns_) {
    overruns_.fetch_add(1, std::memory_order_relaxed);
    command_fault_ = true;
  }
}

PluginFaults PluginDevice::faults() const noexcept {
  PluginFaults f;
  f.read_errors = read_errors_.load(std::memory_order_relaxed);
  f.not_finite = not_finite_.load(std::memory_order_relaxed);
  f.jumps = jumps_.load(std::memory_order_relaxed);
  f.overruns = overruns_.load(std::memory_order_relaxed);
  return f;
}

std::string PluginDevice::Describe() const {
  std::ostringstream s;
  const hs_device_caps& c = plugin_caps_;
  s << name_ << " (" << c.model << "): " << c.points << " contact point" << (c.points == 1 ? "" : "s") << " (";
  for (std::uint32_t i = 0; i < c.points; ++i) s << (i ? ", " : "") << kFingerNames[c.finger[i]];
  s << "), max force " << caps_.max_fingertip_force_N << " N, workspace radius " << caps_.workspace_radius_m
    << " m, rate " << c.rate_Hz << " Hz" << (c.has_gripper ? ", gripper" : "") << (c.has_orientation ? ", orientation" : "");
  return s.str();
}

}  // namespace handshare::haptic
