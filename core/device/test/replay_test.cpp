#include "handshare/haptic/replay.hpp"

#include <gtest/gtest.h>

#include <iomanip>
#include <sstream>

#include "handshare/haptic/haptic_loop.hpp"
#include "handshare/haptic/sim_hand.hpp"

namespace handshare::haptic {
namespace {

std::string ErrorOf(const std::string& text) {
  try {
    ReplayLog::Parse(text, "log.csv");
  } catch (const ReplayError& e) {
    return e.what();
  }
  return "";
}

// Record a scripted hand the way `haptic_node --trace` does (100 Hz rows of loop snapshots),
// replay it at 1 kHz: the replayed fingertips follow the original within the linear
// interpolation error of a minimum-jerk path sampled every 10 ms.
TEST(Replay, RecordedSimHandReplaysWithinInterpolationError) {
  SimDevice sim(HandScript::Parse("start 0 -0.2 0.2\ngrasp 1 0 0.05 0.04 0.04\nlift 1 0.05\n", "t"));
  HapticLoop loop(sim, HapticLoopConfig{1000.0, false});
  std::ostringstream trace;
  trace << std::setprecision(9);
  WriteTraceHeader(trace);
  HapticSnapshot snap;
  for (int k = 0; k <= 2500; ++k) {
    loop.Step(k * 1e-3);
    if (k % 10 == 0 && loop.TakeSnapshot(snap)) WriteTraceRow(trace, snap);
  }
  ReplayDevice replay(ReplayLog::Parse(trace.str(), "trace"));
  double max_error = 0.0;
  DeviceReading original, replayed;
  for (int k = 0; k <= 2500; ++k) {
    sim.Read(k * 1e-3, original);
    replay.Read(k * 1e-3, replayed);
    ASSERT_TRUE(replayed.valid);
    for (int i = 0; i < kFingers; ++i) max_error = std::max(max_error, (original.p_WE[i] - replayed.p_WE[i]).norm());
    EXPECT_TRUE(original.p_WH.isApprox(replayed.p_WH, 1e-3)) << k;
  }
  // Linear interpolation over h = 10 ms errs by at most a_max h^2 / 8, with a_max the peak
  // fingertip acceleration (second differences of the script at 1 ms); 1% for the estimate.
  double a_max = 0.0;
  DeviceReading r0, r1, r2;
  for (int k = 1; k < 2500; ++k) {
    sim.Read((k - 1) * 1e-3, r0);
    sim.Read(k * 1e-3, r1);
    sim.Read((k + 1) * 1e-3, r2);
    for (int i = 0; i < kFingers; ++i) a_max = std::max(a_max, (r0.p_WE[i] - 2 * r1.p_WE[i] + r2.p_WE[i]).norm() / 1e-6);
  }
  EXPECT_LT(max_error, 1.01 * a_max * 1e-4 / 8.0) << "a_max " << a_max;
  EXPECT_GT(max_error, 0.0);  // it did interpolate, not copy
}

TEST(Replay, FaultRowsReplayAsFaultsAndTheEndHoldsOrLoops) {
  const std::string text =
      "t_s,fault,x0,y0,z0,x1,y1,z1,x2,y2,z2,x3,y3,z3,x4,y4,z4\n"
      "0.0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n"
      "1.0,0,1,0,0,1,0,0,1,0,0,1,0,0,1,0,0\n"
      "2.0,1,1,0,0,1,0,0,1,0,0,1,0,0,1,0,0\n"
      "3.0,0,3,0,0,3,0,0,3,0,0,3,0,0,3,0,0\n";
  ReplayDevice hold(ReplayLog::Parse(text, "t"));
  DeviceReading r;
  hold.Read(0.5, r);
  EXPECT_TRUE(r.valid);
  EXPECT_NEAR(r.p_WE[2].x(), 0.5, 1e-12);
  EXPECT_NEAR(r.p_WH.x(), 0.5, 1e-12);  // no hand columns: the fingertips' centroid
  hold.Read(1.5, r);
  EXPECT_FALSE(r.valid);  // interval ends in a fault
  hold.Read(2.5, r);
  EXPECT_FALSE(r.valid);  // interval starts in a fault
  hold.Read(9.0, r);
  EXPECT_TRUE(r.valid);
  EXPECT_NEAR(r.p_WE[0].x(), 3.0, 1e-12);
  ReplayDevice looping(ReplayLog::Parse(text, "t"), true);
  looping.Read(3.5, r);
  EXPECT_NEAR(r.p_WE[0].x(), 0.5, 1e-12);
}

TEST(Replay, BadLogsNameFileLineAndColumn) {
  const std::string header = "t_s,fault,x0,y0,z0,x1,y1,z1,x2,y2,z2,x3,y3,z3,x4,y4,z4\n";
  EXPECT_NE(ErrorOf("").find("log.csv: empty"), std::string::npos);
  EXPECT_NE(ErrorOf(header).find("no samples"), std::string::npos);
  EXPECT_NE(ErrorOf("t_s,fault,x0\n").find("log.csv:1: header has no column 'y0'"), std::string::npos);
  EXPECT_NE(ErrorOf(header + "0,0,1,2\n").find("log.csv:2: expected 17 columns, found 4"), std::string::npos);
  EXPECT_NE(ErrorOf(header + "0,0,0,0,0,0,0,0,0,zz,0,0,0,0,0,0,0\n").find("log.csv:2: column 'y2': 'zz'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(header + "1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n0.5,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n")
                .find("log.csv:3: t_s goes backwards"),
            std::string::npos);
  EXPECT_NE(ErrorOf("x\n").find("log.csv:1: header has no column 't_s'"), std::string::npos);
}

// Non-finite positions in a log are device data the loop must survive: the loop turns them
// into a fault with zero force.
TEST(Replay, NonFinitePositionsBecomeALoopFault) {
  ReplayDevice replay(ReplayLog::Parse(
      "t_s,fault,x0,y0,z0,x1,y1,z1,x2,y2,z2,x3,y3,z3,x4,y4,z4\n0,0,nan,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n", "t"));
  HapticLoop loop(replay, HapticLoopConfig{1000.0, false});
  loop.Step(0.0);
  HapticSnapshot s;
  ASSERT_TRUE(loop.TakeSnapshot(s));
  EXPECT_TRUE(s.fault);
  EXPECT_EQ(loop.faults(), 1u);
}

}  // namespace
}  // namespace handshare::haptic

namespace handshare::haptic {
namespace {

// A trace of a device with fewer fingers (a stylus: the index only) replays as that device:
// the same fingers, not a whole hand with four made-up ones; a bad or changing mask is named.
TEST(Replay, ATraceKeepsTheFingersTheDeviceHad) {
  HapticSnapshot snap;
  snap.finger_mask = 0b00010;
  snap.t_s = 0.0;
  std::ostringstream trace;
  WriteTraceHeader(trace);
  WriteTraceRow(trace, snap);
  snap.t_s = 0.01;
  WriteTraceRow(trace, snap);
  ReplayDevice replay(ReplayLog::Parse(trace.str(), "trace"));
  EXPECT_EQ(replay.capabilities().finger_mask, FingerMask{0b00010});
  EXPECT_EQ(replay.capabilities().fingers, 1);
  DeviceReading r;
  replay.Read(0.005, r);
  EXPECT_EQ(r.finger_mask, FingerMask{0b00010});
  // Older logs, without the column: a whole hand.
  const std::string header = "t_s,fault,x0,y0,z0,x1,y1,z1,x2,y2,z2,x3,y3,z3,x4,y4,z4";
  const std::string row = "0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0";
  EXPECT_EQ(ReplayLog::Parse(header + "\n" + row + "\n", "old").finger_mask(), kEveryFinger);
  EXPECT_NE(ErrorOf(header + ",fingers\n" + row + ",0\n").find("log.csv:2: column 'fingers': '0' is not a finger mask (1 to 31)"),
            std::string::npos);
  EXPECT_NE(ErrorOf(header + ",fingers\n" + row + ",2\n0.1" + row.substr(1) + ",3\n")
                .find("log.csv:3: column 'fingers' changes from 2 to 3 (one device per log)"),
            std::string::npos);
}

}  // namespace
}  // namespace handshare::haptic
