#include "handshare/haptic/plugin_device.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <string>

#include "handshare/haptic/haptic_loop.hpp"
#include "handshare/testing/allocation_counter.hpp"

namespace handshare::haptic {
namespace {

PluginDeviceOptions Options(const std::string& path, const std::string& args) {
  PluginDeviceOptions o;
  o.path = path;
  o.args = args;
  o.origin_W = Eigen::Vector3d(0.1, -0.05, 0.12);
  // Wider than the node's default (0.5 ms): this test's thread is not real-time, and a busy
  // machine may preempt it inside a call. The slow read sleeps 3 ms.
  o.deadline_s = 0.002;
  return o;
}

/// The message Open() throws with, or "" when it opens.
std::string OpenError(const std::string& path, const std::string& args) {
  try {
    PluginDevice::Open(Options(path, args));
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(PluginDeviceOptions, ParsesPathAndArgs) {
  auto o = PluginDeviceOptions::FromSpec("plugin:/opt/x/libfalcon.so:press=1,2,3 period=2");
  EXPECT_EQ(o.path, "/opt/x/libfalcon.so");
  EXPECT_EQ(o.args, "press=1,2,3 period=2");
  o = PluginDeviceOptions::FromSpec("plugin:libtouch.so");
  EXPECT_EQ(o.path, "libtouch.so");
  EXPECT_EQ(o.args, "");
  o = PluginDeviceOptions::FromSpec("plugin:./libomega.so:serial=a:b");
  EXPECT_EQ(o.path, "./libomega.so");
  EXPECT_EQ(o.args, "serial=a:b");
  EXPECT_THROW(PluginDeviceOptions::FromSpec("plugin:"), std::invalid_argument);
  EXPECT_THROW(PluginDeviceOptions::FromSpec("plugin::args"), std::invalid_argument);
  EXPECT_THROW(PluginDeviceOptions::FromSpec("falcon.so"), std::invalid_argument);
}

TEST(PluginDevice, TheExampleStylusIsOneIndexFingertip) {
  auto d = PluginDevice::Open(Options(HANDSHARE_STYLUS_PLUGIN, "press=0.01,0.02,-0.03 period=4"));
  const DeviceCapabilities caps = d->capabilities();
  EXPECT_EQ(caps.fingers, 1);
  EXPECT_EQ(caps.finger_mask, FingerMask{0b00010});  // index
  EXPECT_DOUBLE_EQ(caps.max_fingertip_force_N, 3.3);
  EXPECT_DOUBLE_EQ(caps.control_rate_Hz, 1000.0);
  EXPECT_STREQ(d->name(), "plugin:scripted_stylus");
  EXPECT_NE(d->Describe().find("1 contact point (index)"), std::string::npos) << d->Describe();
  DeviceReading r;
  d->Read(0.0, r);
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.finger_mask, FingerMask{0b00010});
  // At its start the stylus hovers 5 cm over the point: D placed at origin_W.
  EXPECT_NEAR(r.p_WE[1].x(), 0.11, 1e-12);
  EXPECT_NEAR(r.p_WE[1].y(), -0.03, 1e-12);
  EXPECT_NEAR(r.p_WE[1].z(), 0.12 - 0.03 + 0.05, 1e-4);
  EXPECT_TRUE(r.p_WH.isApprox(r.p_WE[1]));
  for (int f : {0, 2, 3, 4}) EXPECT_TRUE(r.p_WE[f].isApprox(r.p_WH)) << "finger " << f;
  EXPECT_EQ(d->faults().total(), 0u);
}

TEST(PluginDevice, RefusesWhatCannotBeADevice) {
  EXPECT_NE(OpenError("/nonexistent/libnothing.so", "").find("device plug-in /nonexistent/libnothing.so: cannot load"),
            std::string::npos);
  const std::string v99 = OpenError(HANDSHARE_TEST_PLUGIN_V99, "ok");
  EXPECT_NE(v99.find("built for device ABI version 99, this handshare reads version 1"), std::string::npos) << v99;
  const std::string none = OpenError(HANDSHARE_TEST_PLUGIN_NO_ENTRY, "ok");
  EXPECT_NE(none.find("exports no function handshare_device_plugin"), std::string::npos) << none;
  const std::string failed = OpenError(HANDSHARE_TEST_PLUGIN, "fail-open");
  EXPECT_NE(failed.find("open(\"fail-open\") failed: no device on /dev/test0 (asked to fail)"), std::string::npos) << failed;
  const std::string caps = OpenError(HANDSHARE_TEST_PLUGIN, "bad-caps");
  EXPECT_NE(caps.find("impossible capabilities: caps.points is 0 (must be 1 to 5)"), std::string::npos) << caps;
  EXPECT_EQ(OpenError(HANDSHARE_TEST_PLUGIN, "ok"), "");
}

TEST(PluginDevice, ATwoPointDeviceIsAPinchWithoutStandIns) {
  auto d = PluginDevice::Open(Options(HANDSHARE_TEST_PLUGIN, "ok points=2"));
  EXPECT_EQ(d->capabilities().finger_mask, FingerMask{0b00011});  // thumb and index
  DeviceReading r;
  for (auto& p : r.p_WE) p.setConstant(std::numeric_limits<double>::quiet_NaN());
  d->Read(0.0, r);
  ASSERT_TRUE(r.valid);
  EXPECT_TRUE(r.p_WE[0].isApprox(Eigen::Vector3d(0.1, -0.05, 0.12)));
  EXPECT_TRUE(r.p_WE[1].isApprox(Eigen::Vector3d(0.12, -0.05, 0.12)));
  for (const auto& p : r.p_WE) EXPECT_TRUE(p.allFinite());
}

struct Misbehaviour {
  const char* mode;
  std::uint64_t PluginFaults::*counter;
};

class PluginDeviceFault : public ::testing::TestWithParam<Misbehaviour> {};

// Each kind of bad data is a fault at the read it happens, counted by its kind; the next good
// read is valid again (a jump's new place is taken as the new normal).
TEST_P(PluginDeviceFault, IsCountedAndInvalidatesOnlyItsReading) {
  auto d = PluginDevice::Open(Options(HANDSHARE_TEST_PLUGIN, std::string(GetParam().mode) + " after=3"));
  DeviceReading r;
  for (int n = 0; n < 6; ++n) {
    d->Read(1e-3 * n, r);
    EXPECT_EQ(r.valid, n != 3) << GetParam().mode << " read " << n;
    if (!r.valid) {
      for (const auto& p : r.p_WE) EXPECT_TRUE(p.allFinite());
    }
  }
  const PluginFaults f = d->faults();
  EXPECT_EQ(f.*(GetParam().counter), 1u);
  EXPECT_EQ(f.total(), 1u);
}

INSTANTIATE_TEST_SUITE_P(Kinds, PluginDeviceFault,
                         ::testing::Values(Misbehaviour{"nan", &PluginFaults::not_finite},
                                           Misbehaviour{"inf", &PluginFaults::not_finite},
                                           Misbehaviour{"jump", &PluginFaults::jumps},
                                           Misbehaviour{"slow", &PluginFaults::overruns},
                                           Misbehaviour{"error", &PluginFaults::read_errors}),
                         [](const ::testing::TestParamInfo<Misbehaviour>& kind) { return std::string(kind.param.mode); });

/// A renderer that asks every fingertip for a fixed force.
class ConstantRenderer final : public ForceRenderer {
 public:
  void Render(double, double, std::uint64_t, const DeviceReading&, std::array<Eigen::Vector3d, kFingers>& out) noexcept override {
    for (auto& f : out) f = Eigen::Vector3d(0.0, 0.0, 1.0);
  }
  void ReleaseAll() noexcept override {}
};

// Through the haptic loop: a plug-in that gives NaN for 100 reads has its force ramped to zero
// within the fault ramp (20 ms), held there, and ramped back in without a jump; the fingers it
// lacks never get a force, even from a renderer that asks every finger for one; no step
// allocates.
TEST(PluginDevice, ANaNDeviceGetsZeroForceThroughTheRampAndComesBackSmoothly) {
  auto d = PluginDevice::Open(Options(HANDSHARE_TEST_PLUGIN, "nan after=300 count=100 points=2"));
  HapticLoopConfig config{1000.0, false};
  config.safety.passivity = false;
  HapticLoop loop(*d, config);
  loop.SetRenderer(std::make_shared<ConstantRenderer>());
  const double rate_step_N = config.safety.max_force_rate_N_per_s * 1e-3;
  double previous = 0.0;
  const long before = testing::AllocationCount();
  for (int k = 0; k < 700; ++k) {
    loop.Step(1e-3 * k);
    const auto& f = loop.safety_output().f_E_W;
    const double fz = f[1].z();
    EXPECT_LE(std::abs(fz - previous), rate_step_N + 1e-9) << "step " << k;
    previous = fz;
    for (int i : {2, 3, 4}) EXPECT_TRUE(f[i].isZero()) << "finger " << i << " step " << k;
    if (k == 299) {
      EXPECT_NEAR(fz, 1.0, 1e-9);
    }
    if (k >= 300 + 20 && k < 400) {
      EXPECT_EQ(fz, 0.0) << "step " << k;
    }
    if (k == 699) {
      EXPECT_NEAR(fz, 1.0, 1e-9);
    }
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_EQ(d->faults().not_finite, 100u);
  EXPECT_EQ(loop.faults(), 100u);
}

}  // namespace
}  // namespace handshare::haptic
