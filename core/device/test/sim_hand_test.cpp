#include "handshare/haptic/sim_hand.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "handshare/testing/allocation_counter.hpp"

namespace handshare::haptic {
namespace {

// The message of the ScriptError that parsing `text` throws (empty if it parses).
std::string ParseError(const std::string& text, const std::string& origin) {
  try {
    HandScript::Parse(text, origin);
  } catch (const ScriptError& e) {
    return e.what();
  }
  return {};
}

TEST(HandScript, MinimumJerkEndpointsMidpointAndZeroEndVelocity) {
  const HandScript s = HandScript::Parse("start 0 0 0\nmove 2.0 0.2 0 0 grip 1\n", "t");
  EXPECT_TRUE(s.PoseAt(0.0).p_WH.isApprox(Eigen::Vector3d::Zero()));
  EXPECT_NEAR(s.PoseAt(2.0).p_WH.x(), 0.2, 1e-15);
  EXPECT_NEAR(s.PoseAt(1.0).p_WH.x(), 0.1, 1e-15);  // symmetric profile: half way at half time
  EXPECT_NEAR(s.PoseAt(1.0).grip, 0.5, 1e-15);
  // Velocity by central differences: zero at both ends, peak 1.875 * distance / duration.
  const double h = 1e-6;
  auto v = [&](double t) { return (s.PoseAt(t + h).p_WH.x() - s.PoseAt(t - h).p_WH.x()) / (2 * h); };
  EXPECT_NEAR(v(h), 0.0, 1e-6);
  EXPECT_NEAR(v(2.0 - h), 0.0, 1e-6);
  EXPECT_NEAR(v(1.0), 1.875 * 0.2 / 2.0, 1e-6);
  EXPECT_NEAR(s.PoseAt(100.0).p_WH.x(), 0.2, 1e-15);  // holds after the end
  EXPECT_DOUBLE_EQ(s.duration_s(), 2.0);
}

TEST(HandScript, SegmentsChainInTime) {
  const HandScript s = HandScript::Parse(
      "# reach, close, hold, lift\nstart 0 0 0.1\nmove 1 0 0.05 0.1\ngrip 0.5 1\nhold 1\n"
      "move 1 0 0.05 0.2\n", "t");
  EXPECT_DOUBLE_EQ(s.duration_s(), 3.5);
  EXPECT_NEAR(s.PoseAt(1.5).grip, 1.0, 1e-15);
  EXPECT_NEAR(s.PoseAt(2.0).p_WH.z(), 0.1, 1e-15);
  EXPECT_NEAR(s.PoseAt(3.5).p_WH.z(), 0.2, 1e-15);
}

TEST(HandScript, ErrorsNameOriginAndLine) {
  auto error_of = [](const std::string& text) { return ParseError(text, "hand.txt"); };
  EXPECT_NE(error_of("start 0 0 0\nmove 1 0 0\n").find("hand.txt:2: missing z"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\n\njump 1\n").find("hand.txt:3: unknown command 'jump'"), std::string::npos);
  EXPECT_NE(error_of("move 1 0 0 0\n").find("hand.txt:1:"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 nan\n").find("z: 'nan' is not a number"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\ngrip 1 1.5\n").find("outside"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nhold -1\n").find("hand.txt:2: duration"), std::string::npos);
  EXPECT_NE(error_of("# nothing\n").find("empty script"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nhold 1 2\n").find("unexpected '2'"), std::string::npos);
}

// A script that awaits the world holds its start pose until OnWorldReady, then runs on a clock
// that starts there; one without await_world runs from the device clock's zero and ignores it.
TEST(HandScript, AwaitWorldStartsTheScriptWhenTheWorldIsHere) {
  SimDevice awaiting(HandScript::Parse("start 0 0 0\nawait_world\nmove 2.0 0.2 0 0\n", "t"));
  DeviceReading r;
  awaiting.Read(5.0, r);  // no world yet: still at the start
  EXPECT_NEAR(r.p_WH.x(), 0.0, 1e-15);
  EXPECT_TRUE(awaiting.OnWorldReady(5.0, "start_menu"));
  EXPECT_FALSE(awaiting.OnWorldReady(6.0, "solar_system"));  // the first call counts
  awaiting.Read(6.0, r);                      // script time 1 s: half way
  EXPECT_NEAR(r.p_WH.x(), 0.1, 1e-15);
  awaiting.Read(7.0, r);
  EXPECT_NEAR(r.p_WH.x(), 0.2, 1e-15);

  SimDevice plain(HandScript::Parse("start 0 0 0\nmove 2.0 0.2 0 0\n", "t"));
  EXPECT_FALSE(plain.OnWorldReady(0.5, "start_menu"));
  plain.Read(1.0, r);
  EXPECT_NEAR(r.p_WH.x(), 0.1, 1e-15);

  auto error_of = [](const std::string& text) { return ParseError(text, "h"); };
  EXPECT_NE(error_of("start 0 0 0\nhold 1\nawait_world\n").find("h:3: 'await_world' must come right after 'start'"),
            std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nhold 1\nawait_world\n").find("await_world NAME"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nawait_world\nawait_world\n").find("h:3:"), std::string::npos);
  EXPECT_NE(error_of("await_world\n").find("h:1: the script must begin with 'start X Y Z'"), std::string::npos);
}

// await_world NAME in the middle of a script: the hand holds where it is until that world is
// the node's, ignores other worlds, and runs on from when it arrived.
constexpr const char* kWaitsForDinosaur =
    "start 0 0 0\nmove 1 0.1 0 0\nawait_world dinosaur\nmove 1 0.2 0 0\n";

TEST(HandScript, AwaitWorldNameHoldsUntilThatWorldIsHere) {
  const HandScript script = HandScript::Parse(kWaitsForDinosaur, "t");
  ASSERT_EQ(script.waits().size(), 1u);
  EXPECT_EQ(script.waits()[0].world, "dinosaur");
  EXPECT_DOUBLE_EQ(script.waits()[0].t_s, 1.0);
  EXPECT_EQ(script.waits()[0].line, 3);
  SimDevice hand(script);
  DeviceReading r;
  hand.Read(0.5, r);  // moving: a wait later in the script does not hold the start
  EXPECT_NEAR(r.p_WH.x(), 0.05, 1e-12);
  EXPECT_FALSE(hand.OnWorldReady(0.8, "start_menu"));  // not the one it waits for
  hand.Read(2.0, r);
  EXPECT_NEAR(r.p_WH.x(), 0.1, 1e-12);  // holds at the wait
  EXPECT_FALSE(hand.OnWorldReady(2.5, "solar_system"));
  hand.Read(3.0, r);
  EXPECT_NEAR(r.p_WH.x(), 0.1, 1e-12);  // other worlds are ignored
  EXPECT_FALSE(hand.OnWorldReady(3.5, "dinosaur"));  // runs on; the script had started before
  hand.Read(4.0, r);                                  // 0.5 s after the world arrived: half way
  EXPECT_NEAR(r.p_WH.x(), 0.15, 1e-9);
  hand.Read(4.5, r);
  EXPECT_NEAR(r.p_WH.x(), 0.2, 1e-12);
  hand.Read(9.0, r);
  EXPECT_NEAR(r.p_WH.x(), 0.2, 1e-12);
}

TEST(HandScript, AwaitWorldNameDoesNotHoldWhenTheWorldIsAlreadyHere) {
  DeviceReading r;
  // Here before the script got to the wait: no hold at all.
  SimDevice early(HandScript::Parse(kWaitsForDinosaur, "t"));
  early.OnWorldReady(0.2, "dinosaur");
  early.OnWorldReady(0.7, "dinosaur");  // a new revision of the same world (new gravity)
  early.Read(1.5, r);
  EXPECT_NEAR(r.p_WH.x(), 0.15, 1e-9);
  // Came and went before the script got there: it holds until the world is back.
  SimDevice gone(HandScript::Parse(kWaitsForDinosaur, "t"));
  gone.OnWorldReady(0.2, "dinosaur");
  gone.OnWorldReady(0.5, "microscopic");
  gone.Read(1.5, r);
  EXPECT_NEAR(r.p_WH.x(), 0.1, 1e-12);
  gone.OnWorldReady(2.0, "dinosaur");
  gone.Read(2.5, r);
  EXPECT_NEAR(r.p_WH.x(), 0.15, 1e-9);
}

// Several waits, one at the start: the start one releases the script (true once), the later
// one holds it again; the script times shift by each hold.
TEST(HandScript, AwaitWorldAtTheStartAndLaterEachHold) {
  SimDevice hand(HandScript::Parse("start 0 0 0\nawait_world solar_system\nmove 1 0.1 0 0\n"
                                   "await_world dinosaur\nmove 1 0.2 0 0\nawait_world start_menu\n"
                                   "move 1 0.3 0 0\n", "t"));
  DeviceReading r;
  EXPECT_FALSE(hand.OnWorldReady(1.0, "start_menu"));
  hand.Read(2.0, r);
  EXPECT_NEAR(r.p_WH.x(), 0.0, 1e-12);  // the start pose until the solar system is here
  EXPECT_TRUE(hand.OnWorldReady(3.0, "solar_system"));
  EXPECT_FALSE(hand.OnWorldReady(3.1, "solar_system"));  // true only once
  hand.Read(3.5, r);
  EXPECT_NEAR(r.p_WH.x(), 0.05, 1e-9);
  hand.Read(5.0, r);
  EXPECT_NEAR(r.p_WH.x(), 0.1, 1e-12);
  EXPECT_FALSE(hand.OnWorldReady(6.0, "dinosaur"));
  hand.Read(6.5, r);
  EXPECT_NEAR(r.p_WH.x(), 0.15, 1e-9);
  EXPECT_FALSE(hand.OnWorldReady(6.8, "start_menu"));  // here before the script gets there
  hand.Read(7.5, r);                                   // script time 2.5: no hold at 2
  EXPECT_NEAR(r.p_WH.x(), 0.25, 1e-9);
}

// The bridge thread's call and the haptic thread's read allocate nothing (real-time rules).
TEST(HandScript, AwaitWorldCallsDoNotAllocate) {
  SimDevice hand(HandScript::Parse(kWaitsForDinosaur, "t"));
  DeviceReading r;
  const std::string world = "dinosaur";
  const long before = testing::AllocationCount();
  hand.Read(2.0, r);
  hand.OnWorldReady(2.5, "start_menu");
  hand.OnWorldReady(3.0, world);
  hand.Read(3.5, r);
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_NEAR(r.p_WH.x(), 0.15, 1e-9);
}

TEST(HandScript, AwaitWorldBadUsesNameTheLine) {
  auto error_of = [](const std::string& text) { return ParseError(text, "h.hand"); };
  EXPECT_NE(error_of("await_world dinosaur\n").find("h.hand:1: the script must begin with 'start X Y Z'"),
            std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nhold 1\nawait_world 2.0\n").find("h.hand:3: await_world: '2.0' is not a world name"),
            std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nawait_world solar-system\n").find("h.hand:2: await_world: 'solar-system'"),
            std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nawait_world dinosaur now\n").find("h.hand:2: unexpected 'now'"),
            std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nawait_world now later\n").find("h.hand:2: unexpected 'later'"),
            std::string::npos);
  EXPECT_EQ(error_of("start 0 0 0\nawait_world\nawait_world dinosaur\nhold 1\nawait_world dinosaur\n"), "");
}

TEST(SimFingertips, FiveDistinctFingertipsThatCloseTogether) {
  HandPose open{Eigen::Vector3d(0.1, 0.2, 0.3), 0.0}, closed{Eigen::Vector3d(0.1, 0.2, 0.3), 1.0};
  const auto po = SimFingertips(open), pc = SimFingertips(closed);
  double spread_open = 0, spread_closed = 0;
  for (int i = 0; i < kFingers; ++i) {
    for (int j = i + 1; j < kFingers; ++j) {
      EXPECT_GT((po[i] - po[j]).norm(), 0.016) << i << "," << j;  // two fingertip radii apart
      spread_open += (po[i] - po[j]).norm();
      spread_closed += (pc[i] - pc[j]).norm();
    }
    EXPECT_LT((po[i] - open.p_WH).norm(), 0.15);  // within a hand's reach of its base
  }
  EXPECT_LT(spread_closed, 0.5 * spread_open);
}

}  // namespace
}  // namespace handshare::haptic

namespace handshare::haptic {
namespace {

// Every script the project ships (demo and tests) parses and stays within the table's reach.
TEST(HandScript, ShippedScriptsParse) {
  int count = 0;
  for (const char* dir : {HANDSHARE_SCRIPT_DIR, HANDSHARE_TEST_DATA_DIR}) {
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (entry.path().extension() != ".hand") continue;
      const HandScript s = HandScript::Load(entry.path());
      EXPECT_GT(s.duration_s(), 1.0) << entry.path();
      // A world a script waits for is one of the project's scenes (a typo would hold forever).
      for (const auto& wait : s.waits()) {
        if (wait.world.empty()) continue;
        EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(HANDSHARE_SCENE_DIR) / (wait.world + ".json")))
            << entry.path() << ":" << wait.line << ": no scene '" << wait.world << "'";
      }
      for (double t = 0.0; t <= s.duration_s(); t += 0.1) {
        EXPECT_LT(s.PoseAt(t).p_WH.norm(), 0.5) << entry.path() << " at " << t << " s";
      }
      ++count;
    }
  }
  EXPECT_GE(count, 4);
}

}  // namespace
}  // namespace handshare::haptic

namespace handshare::haptic {
namespace {

std::array<Eigen::Vector3d, kFingers> TipsAt(const HandScript& s, double t) { return SimFingertips(s.PoseAt(t)); }

TEST(HandScriptVerbs, GraspPlacesFiveFingertipsOnTheSphereAroundTheCentre) {
  const HandScript s = HandScript::Parse("start 0 -0.2 0.2\ngrasp 1.5 0.01 0.05 0.04 0.04 0.003\n", "t");
  const Eigen::Vector3d c(0.01, 0.05, 0.04);
  const auto tips = TipsAt(s, 1.5);
  Eigen::Vector3d sum_n = Eigen::Vector3d::Zero();
  for (const auto& p : tips) {
    EXPECT_NEAR((p - c).norm(), 0.04 + kSimFingertipRadius_m - 0.003, 1e-12);
    EXPECT_LT(p.z(), c.z());  // below the equator: pushes hold the object up
    sum_n += (p - c).normalized();
  }
  // Equal squeezes cancel sideways: the normals' horizontal sum vanishes.
  EXPECT_NEAR(sum_n.x(), 0.0, 1e-12);
  EXPECT_NEAR(sum_n.y(), 0.0, 1e-12);
  EXPECT_LT(tips[0].y(), c.y());  // thumb on the user's side
}

TEST(HandScriptVerbs, PressGoesDownByDepthAndBackWithOnlyTheIndexLowest) {
  const HandScript s = HandScript::Parse("start 0 -0.2 0.2\npress 3 0.1 0.1 0.05 0.012\n", "t");
  EXPECT_TRUE(TipsAt(s, 1.0)[1].isApprox(Eigen::Vector3d(0.1, 0.1, 0.05), 1e-12));
  EXPECT_TRUE(TipsAt(s, 2.0)[1].isApprox(Eigen::Vector3d(0.1, 0.1, 0.038), 1e-12));
  EXPECT_TRUE(TipsAt(s, 3.0)[1].isApprox(Eigen::Vector3d(0.1, 0.1, 0.05), 1e-12));
  const auto tips = TipsAt(s, 2.0);
  for (int i = 0; i < kFingers; ++i) {
    if (i != 1) {
      EXPECT_GT(tips[i].z() - tips[1].z(), 0.03) << i;
    }
  }
}

TEST(HandScriptVerbs, PinchPokeLiftPullRelease) {
  const HandScript s = HandScript::Parse(
      "start 0 -0.2 0.2\npinch 1 0 0 0.1 0.03\nlift 1 0.05\npull 1 0.01 -0.02 0\n"
      "poke 1 0.2 0.1 0.1\nrelease 0.5\n", "t");
  auto tips = TipsAt(s, 1.0);
  EXPECT_NEAR((tips[0] - tips[1]).norm(), 0.03, 1e-12);
  EXPECT_TRUE((0.5 * (tips[0] + tips[1])).isApprox(Eigen::Vector3d(0, 0, 0.1), 1e-12));
  const auto lifted = TipsAt(s, 2.0), pulled = TipsAt(s, 3.0);
  for (int i = 0; i < kFingers; ++i) {
    EXPECT_TRUE((lifted[i] - tips[i]).isApprox(Eigen::Vector3d(0, 0, 0.05), 1e-12)) << i;
    EXPECT_TRUE((pulled[i] - lifted[i]).isApprox(Eigen::Vector3d(0.01, -0.02, 0), 1e-12)) << i;
  }
  const auto poked = TipsAt(s, 4.0), released = TipsAt(s, 4.2), raised = TipsAt(s, 4.5);
  EXPECT_TRUE(poked[1].isApprox(Eigen::Vector3d(0.2, 0.1, 0.1), 1e-12));
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : poked) centroid += p / kFingers;
  for (int i = 0; i < kFingers; ++i) {
    EXPECT_NEAR((released[i] - centroid).norm() - (poked[i] - centroid).norm(), 0.03, 1e-12) << i;
    EXPECT_TRUE((raised[i] - released[i]).isApprox(Eigen::Vector3d(0, 0, 0.05), 1e-12)) << i;
  }
}

// Human-like motion: every fingertip moves continuously across verbs of every kind, with a
// speed below what a hand does (under 2 m/s for these short scripted moves).
TEST(HandScriptVerbs, FingertipPathsAreContinuousAcrossVerbs) {
  const HandScript s = HandScript::Parse(
      "start 0 -0.2 0.2\nreach 1 0 0 0.15\ngrasp 1 0 0.05 0.04 0.04\nlift 1 0.05\nrelease 0.5\n"
      "grip 0.5 1\npress 1.5 0.1 0.1 0.05 0.01\nmove 1 0 0 0.2\n", "t");
  const double dt = 1e-3;
  double max_speed = 0.0;
  auto prev = TipsAt(s, 0.0);
  for (double t = dt; t <= s.duration_s() + dt; t += dt) {
    const auto now = TipsAt(s, t);
    for (int i = 0; i < kFingers; ++i) max_speed = std::max(max_speed, (now[i] - prev[i]).norm() / dt);
    prev = now;
  }
  EXPECT_GT(max_speed, 0.05);
  EXPECT_LT(max_speed, 2.0);
}

TEST(HandScriptVerbs, BadArgumentsNameTheLine) {
  auto error_of = [](const std::string& text) { return ParseError(text, "h"); };
  EXPECT_NE(error_of("start 0 0 0\ngrasp 1 0 0 0\n").find("h:2: missing radius"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\ngrasp 1 0 0 0 0.04 0.5\n").find("h:2: squeeze"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\npress 1 0 0 0 -1\n").find("h:2: depth"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nlift 1 0.1 2\n").find("unexpected '2'"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nrelease\n").find("h:2: missing duration"), std::string::npos);
}

}  // namespace
}  // namespace handshare::haptic
