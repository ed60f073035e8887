#include "handshare/haptic/sim_hand.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace handshare::haptic {
namespace {

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
  auto error_of = [](const std::string& text) {
    try {
      HandScript::Parse(text, "hand.txt");
    } catch (const ScriptError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("start 0 0 0\nmove 1 0 0\n").find("hand.txt:2: missing z"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\n\njump 1\n").find("hand.txt:3: unknown command 'jump'"), std::string::npos);
  EXPECT_NE(error_of("move 1 0 0 0\n").find("hand.txt:1:"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 nan\n").find("z: 'nan' is not a number"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\ngrip 1 1.5\n").find("outside"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nhold -1\n").find("hand.txt:2: duration"), std::string::npos);
  EXPECT_NE(error_of("# nothing\n").find("empty script"), std::string::npos);
  EXPECT_NE(error_of("start 0 0 0\nhold 1 2\n").find("unexpected '2'"), std::string::npos);
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
