#include "handshare/controls/controls.hpp"
#include "handshare/testing/allocation_counter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <random>

namespace handshare::controls {
namespace {

constexpr double kDt = 1e-3;        // 1 kHz haptic step
constexpr double kRadius = 0.008;   // fingertip radius [m]
const Eigen::Vector3d kFar(0.0, 0.0, 1.0);  // a fingertip far from every control

scene::ControlSpec Spec(scene::ControlType type, const std::string& id = "c") {
  // The loader's defaults: parse a minimal scene entry so the test sees what scenes get.
  scene::ControlSpec s;
  s.id = id;
  s.type = type;
  switch (type) {
    case scene::ControlType::kButton: s.size_m = Eigen::Vector3d(0.04, 0.04, 0.012); break;
    case scene::ControlType::kArrow:
      s.size_m = Eigen::Vector3d(0.09, 0.06, 0.01);
      s.push = {.travel_m = 0.0015, .click_at_m = 0.001, .release_at_m = 0.0005,
                .stiffness_N_per_m = 1500.0, .preload_N = 0.3, .click_drop = 0.0,
                .stop_stiffness_N_per_m = 4000.0};
      break;
    case scene::ControlType::kLever: s.size_m = Eigen::Vector3d(0.02, 0.012, 0.09); break;
    case scene::ControlType::kBook: s.size_m = Eigen::Vector3d(0.10, 0.14, 0.03); break;
  }
  return s;
}

// One hand (5 fingertips): the index fingertip (finger 1) at p_W, the others far away.
std::vector<Eigen::Vector3d> OneFinger(const Eigen::Vector3d& p_W) {
  std::vector<Eigen::Vector3d> tips(kFingers, kFar);
  tips[1] = p_W;
  return tips;
}

// One hand with all five fingertips spread 1.5 cm apart along x around p_W.
void WholeHand(const Eigen::Vector3d& p_W, std::vector<Eigen::Vector3d>& tips, int hand = 0) {
  for (int k = 0; k < kFingers; ++k) {
    tips[static_cast<std::size_t>(hand * kFingers + k)] = p_W + Eigen::Vector3d(0.015 * (k - 2), 0.0, 0.0);
  }
}

struct Recorder {
  EventBuffer events;
  std::vector<ControlEvent> all;     // every event but the motion reports
  std::vector<ControlEvent> motion;  // kMoving
  std::vector<Eigen::Vector3d> f;
  double t_s = 0.0;
  std::vector<double> motion_t_s;    // when each motion report came
  void Step(Control& c, const std::vector<Eigen::Vector3d>& tips) {
    f.assign(tips.size(), Eigen::Vector3d::Zero());
    events.Clear();
    c.Step(kDt, tips, kRadius, f, events);
    t_s += kDt;
    for (const auto& e : events) {
      if (e.kind == EventKind::kMoving) {
        motion.push_back(e);
        motion_t_s.push_back(t_s);
      } else {
        all.push_back(e);
      }
    }
  }
  int Count(EventKind k) const {
    return static_cast<int>(std::count_if(all.begin(), all.end(), [&](auto& e) { return e.kind == k; }));
  }
};

// ---------------------------------------------------------------------------------------------

TEST(PushButton, ClicksAtTheThresholdWithAForceDropAndReleasesOnReturn) {
  const scene::ControlSpec spec = Spec(scene::ControlType::kButton);
  PushControl button(spec);
  Recorder rec;
  // Lower the fingertip 0.01 mm per step from just above the face to 1 mm past the travel.
  double before_click_N = 0.0, after_click_N = 0.0, travel_at_press = -1.0;
  for (int i = 0; i <= 600; ++i) {
    const double depth = -0.001 + 1e-5 * i;  // of the fingertip below the face
    rec.Step(button, OneFinger(Eigen::Vector3d(0.003, -0.004, kRadius - depth)));
    const double fz = rec.f[1].z();
    EXPECT_NEAR(rec.f[1].head<2>().norm(), 0.0, 1e-12);
    if (rec.Count(EventKind::kPressed) == 0) {
      before_click_N = fz;
    } else if (travel_at_press < 0.0) {
      travel_at_press = rec.all.back().value;
      after_click_N = fz;
      EXPECT_NEAR(rec.all.back().error_m, 0.005, 1e-12);  // 3 mm, 4 mm off centre
      EXPECT_EQ(rec.all.back().hand, 0);
      EXPECT_EQ(rec.all.back().finger, 1);
    }
  }
  EXPECT_EQ(rec.Count(EventKind::kPressed), 1);
  // The click happens at click_at_m (to the 0.01 mm step).
  EXPECT_GE(travel_at_press, spec.push.click_at_m);
  EXPECT_LT(travel_at_press, spec.push.click_at_m + 1.1e-5);
  // Hand-worked: 0.3 N + 400 N/m * 2.5 mm = 1.3 N before, 40 % less (0.78 N) after.
  EXPECT_NEAR(before_click_N, 1.3, 0.01);
  EXPECT_NEAR(after_click_N, 0.78, 0.01);
  // Past the travel: the stop. At 1 mm past: 0.6 * (0.3 + 400 * 0.004) + 3000 * 0.001 > 3.5 N.
  EXPECT_NEAR(rec.f[1].z(), spec.max_force_N, 1e-9);

  // Coming back: RELEASED once the cap is above release_at_m, and the force is the lower one
  // on the way up (hysteresis of a tactile switch).
  for (int i = 600; i >= 0; --i) {
    const double depth = -0.001 + 1e-5 * i;
    rec.Step(button, OneFinger(Eigen::Vector3d(0.003, -0.004, kRadius - depth)));
    if (std::abs(depth - 0.002) < 5e-6) {
      EXPECT_NEAR(rec.f[1].z(), 0.6 * (0.3 + 400 * 0.002), 0.01);
    }
  }
  ASSERT_EQ(rec.Count(EventKind::kReleased), 1);
  const auto released = std::find_if(rec.all.begin(), rec.all.end(), [](auto& e) { return e.kind == EventKind::kReleased; });
  EXPECT_LE(released->value, spec.push.release_at_m);
  EXPECT_GT(released->value, spec.push.release_at_m - 1.1e-5);
  EXPECT_EQ(rec.Count(EventKind::kPressed), 1);
  EXPECT_EQ(rec.f[1].norm(), 0.0);  // lifted off
}

TEST(PushButton, WorksInItsOwnFrameAndIgnoresFingersBesideIt) {
  // A button on a wall: face towards -y of W.
  scene::ControlSpec spec = Spec(scene::ControlType::kButton);
  spec.p_WC_m = Eigen::Vector3d(0.1, 0.2, 0.3);
  spec.q_WC = Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  PushControl button(spec);
  Recorder rec;
  // z of C is -y of W... check: R_x(90) maps z to -y.
  const Eigen::Vector3d out_W = spec.q_WC * Eigen::Vector3d::UnitZ();
  ASSERT_NEAR(out_W.y(), -1.0, 1e-12);
  rec.Step(button, OneFinger(spec.p_WC_m + out_W * (kRadius - 0.003)));
  EXPECT_EQ(rec.Count(EventKind::kPressed), 1);
  EXPECT_GT(rec.f[1].dot(out_W), 0.5);                  // pushed back out of the face
  EXPECT_NEAR((rec.f[1] - rec.f[1].dot(out_W) * out_W).norm(), 0.0, 1e-9);
  // Beside the face (3 cm off along x of C): nothing.
  PushControl other(spec);
  Recorder rec2;
  rec2.Step(other, OneFinger(spec.p_WC_m + out_W * (kRadius - 0.003) + Eigen::Vector3d(0.03, 0, 0)));
  EXPECT_EQ(rec2.f[1].norm(), 0.0);
  EXPECT_EQ(rec2.Count(EventKind::kPressed), 0);
}

TEST(Arrow, ShortStiffPushGoes) {
  const scene::ControlSpec spec = Spec(scene::ControlType::kArrow);
  PushControl arrow(spec);
  Recorder rec;
  double force_at_press = 0.0;
  for (int i = 0; i <= 200; ++i) {
    const double depth = 1e-5 * i;
    rec.Step(arrow, OneFinger(Eigen::Vector3d(0.0, 0.0, kRadius - depth)));
    if (rec.Count(EventKind::kPressed) == 1 && force_at_press == 0.0) force_at_press = rec.f[1].z();
  }
  ASSERT_EQ(rec.Count(EventKind::kPressed), 1);
  EXPECT_EQ(rec.all[0].type, scene::ControlType::kArrow);
  EXPECT_NEAR(rec.all[0].value, 0.001, 1.1e-5);
  // No click drop: 0.3 N + 1500 N/m * 1 mm = 1.8 N.
  EXPECT_NEAR(force_at_press, 1.8, 0.02);
  // 2 mm deep: 0.5 mm into the stop: 0.3 + 1500 * 1.5 mm + 4000 * 0.5 mm = 4.55 N -> 3.5 N.
  EXPECT_NEAR(rec.f[1].z(), 3.5, 1e-9);
}

// A hand that was already on the control when its world appeared (it pressed the arrow at the
// same place in the world before) does not actuate it: arrows of consecutive worlds at one
// place would otherwise cascade through the worlds. Once the hand has left, it can.
TEST(Arrow, AHandAlreadyThereWhenTheWorldAppearsDoesNotActuateItUntilItLeaves) {
  PushControl arrow(Spec(scene::ControlType::kArrow));
  arrow.SetGuardFirstVisits(true);
  Recorder rec;
  double deepest_force = 0.0;
  auto push = [&] {
    for (int i = 0; i <= 200; ++i) rec.Step(arrow, OneFinger(Eigen::Vector3d(0.0, 0.0, kRadius - 1e-5 * i)));
    deepest_force = rec.f[1].norm();
    for (int i = 200; i >= 0; --i) rec.Step(arrow, OneFinger(Eigen::Vector3d(0.0, 0.0, kRadius - 1e-5 * i)));
  };
  push();  // from the first step on: inherited
  EXPECT_EQ(rec.Count(EventKind::kPressed), 0);
  EXPECT_EQ(rec.Count(EventKind::kReleased), 0);
  EXPECT_NEAR(deepest_force, 3.5, 1e-9);  // it still pushes back (into the stop, clamped)
  rec.Step(arrow, OneFinger(kFar));  // the hand leaves (no miss: it never came)
  EXPECT_EQ(rec.Count(EventKind::kMissed), 0);
  push();
  EXPECT_EQ(rec.Count(EventKind::kPressed), 1);
  EXPECT_EQ(rec.Count(EventKind::kReleased), 1);
  // Already 3 mm deep when the world appears, then rising: still nothing.
  PushControl deep(Spec(scene::ControlType::kArrow));
  deep.SetGuardFirstVisits(true);
  Recorder rec3;
  for (int i = 300; i >= 0; --i) rec3.Step(deep, OneFinger(Eigen::Vector3d(0.0, 0.0, kRadius - 1e-5 * i)));
  EXPECT_EQ(rec3.Count(EventKind::kPressed), 0);
  // Off (the default), the same first push actuates it.
  PushControl unguarded(Spec(scene::ControlType::kArrow));
  Recorder rec2;
  for (int i = 0; i <= 200; ++i) rec2.Step(unguarded, OneFinger(Eigen::Vector3d(0.0, 0.0, kRadius - 1e-5 * i)));
  EXPECT_EQ(rec2.Count(EventKind::kPressed), 1);
}

// ---------------------------------------------------------------------------------------------

// Fingertip at height z on the plane x = 0 of the lever, at lateral y.
std::vector<Eigen::Vector3d> LeverFinger(double y, double z) { return OneFinger(Eigen::Vector3d(0.0, y, z)); }

TEST(Lever, PushedFromItsSideItSnapsIntoTheNextDetent) {
  const scene::ControlSpec spec = Spec(scene::ControlType::kLever);
  Lever lever(spec);
  Recorder rec;
  const double z = 0.07;
  double peak_N = 0.0;
  int steps_to_move = -1;
  for (int i = 0; i < 4000 && steps_to_move < 0; ++i) {
    const double y = 0.016 - 2e-5 * i;  // moves towards -y at 2 cm/s
    rec.Step(lever, LeverFinger(y, z));
    peak_N = std::max(peak_N, rec.f[1].norm());
    if (rec.Count(EventKind::kMoved) > 0) steps_to_move = i;
    EXPECT_GE(rec.f[1].y(), -1e-12);  // it only ever pushes the finger back to +y
  }
  ASSERT_GT(steps_to_move, 0);
  ASSERT_EQ(rec.Count(EventKind::kMoved), 1);
  EXPECT_EQ(rec.all[0].index, 1);
  EXPECT_DOUBLE_EQ(rec.all[0].value, spec.lever.max_angle_rad);
  EXPECT_EQ(lever.detent(), 1);
  EXPECT_GT(rec.all[0].error_m, 0.0);
  EXPECT_LT(rec.all[0].error_m, 0.05);
  // The detent torque peak (0.06 N m) held at about 7 cm: ~0.86 N (the lever arm grows a
  // little as the handle tilts under the finger).
  EXPECT_NEAR(peak_N, 0.06 / 0.07, 0.1);
  // After the snap the handle ran ahead of the finger: no force, resting in the detent.
  for (int i = 0; i < 500; ++i) rec.Step(lever, LeverFinger(0.016, 0.2));
  EXPECT_NEAR(lever.angle_rad(), spec.lever.max_angle_rad, 1e-6);
  EXPECT_EQ(rec.Count(EventKind::kMoved), 1);
}

// The session's state (another user moved it, or the world was rebuilt): the lever is put into
// that detent without an event, stays there, and is pushed on from there.
TEST(Lever, AppliedStateIsADetentItRestsInWithoutAnEvent) {
  const scene::ControlSpec spec = Spec(scene::ControlType::kLever);
  Lever lever(spec);
  Recorder rec;
  lever.ApplyState(1, false);
  EXPECT_EQ(lever.detent(), 1);
  EXPECT_DOUBLE_EQ(lever.angle_rad(), spec.lever.max_angle_rad);
  for (int i = 0; i < 500; ++i) rec.Step(lever, OneFinger(kFar));
  EXPECT_NEAR(lever.angle_rad(), spec.lever.max_angle_rad, 1e-9);
  EXPECT_EQ(rec.all.size(), 0u);
  lever.ApplyState(7, false);  // a detent it does not have: ignored
  EXPECT_EQ(lever.detent(), 1);
  lever.ApplyState(0, false);
  EXPECT_EQ(lever.detent(), 0);
  EXPECT_DOUBLE_EQ(lever.angle_rad(), spec.lever.min_angle_rad);
}

// A state from elsewhere (another user moved the lever) waits while a hand is at the control,
// and is applied at the first step after the hand has left; a newer request replaces it.
TEST(Lever, ARequestedStateWaitsUntilNoHandIsAtIt) {
  const scene::ControlSpec spec = Spec(scene::ControlType::kLever);
  Lever lever(spec);
  Recorder rec;
  const Eigen::Vector3d beside(0.0, 0.02, 0.05);  // in the approach zone, 6 mm off the handle
  rec.Step(lever, OneFinger(beside));
  ASSERT_TRUE(lever.touched());
  lever.RequestState(0, false);
  lever.RequestState(1, false);  // the newer one counts
  for (int i = 0; i < 100; ++i) rec.Step(lever, OneFinger(beside));
  EXPECT_EQ(lever.detent(), 0);
  rec.Step(lever, OneFinger(kFar));  // the hand leaves during this step
  EXPECT_FALSE(lever.touched());
  EXPECT_EQ(lever.detent(), 0);
  rec.Step(lever, OneFinger(kFar));
  EXPECT_EQ(lever.detent(), 1);
  EXPECT_DOUBLE_EQ(lever.angle_rad(), spec.lever.max_angle_rad);
  EXPECT_EQ(rec.Count(EventKind::kMoved), 0);  // the move was another user's: no event here
}

TEST(Book, AppliedStateOpensItAtAPageOrShutsIt) {
  Book book(Spec(scene::ControlType::kBook));
  book.ApplyState(2, true);
  EXPECT_TRUE(book.open());
  EXPECT_EQ(book.page(), 2);
  EXPECT_DOUBLE_EQ(book.cover_angle_rad(), std::numbers::pi);
  book.ApplyState(-1, false);
  EXPECT_FALSE(book.open());
  EXPECT_DOUBLE_EQ(book.cover_angle_rad(), 0.0);
}

TEST(Lever, PushedFromTheWrongSideItDoesNotMove) {
  const scene::ControlSpec spec = Spec(scene::ControlType::kLever);
  Lever lever(spec);
  Recorder rec;
  double last_fy = 0.0;
  for (int i = 0; i < 400; ++i) {
    const double y = -0.016 + 2e-5 * i;  // from the -y side towards +y, 8 mm in
    rec.Step(lever, LeverFinger(y, 0.07));
    EXPECT_LE(rec.f[1].y(), 1e-12);
    if (i > 150) {
      EXPECT_LE(rec.f[1].y(), last_fy + 1e-12);  // a stiff end stop, growing
    }
    last_fy = rec.f[1].y();
  }
  EXPECT_EQ(rec.Count(EventKind::kMoved), 0);
  EXPECT_DOUBLE_EQ(lever.angle_rad(), spec.lever.min_angle_rad);
  EXPECT_NEAR(rec.f[1].norm(), spec.max_force_N, 1e-9);
}

TEST(Lever, ReleasedBeforeTheMidpointItReturnsAndBackFromTheOtherSide) {
  scene::ControlSpec spec = Spec(scene::ControlType::kLever);
  spec.lever.detents = 3;  // 0, 0.3, 0.6 rad
  Lever lever(spec);
  Recorder rec;
  // Push to ~0.1 rad (before the midpoint 0.15) and let go: back to detent 0, no event.
  for (int i = 0; i < 1000 && lever.angle_rad() < 0.1; ++i) rec.Step(lever, LeverFinger(0.016 - 2e-5 * i, 0.07));
  EXPECT_GT(lever.angle_rad(), 0.09);
  for (int i = 0; i < 500; ++i) rec.Step(lever, LeverFinger(0.05, 0.2));
  EXPECT_NEAR(lever.angle_rad(), 0.0, 1e-3);
  EXPECT_EQ(rec.Count(EventKind::kMoved), 0);
  // All the way: detents 1 and 2, one event each, in order.
  for (int i = 0; i < 6000 && lever.detent() < 2; ++i) rec.Step(lever, LeverFinger(0.016 - 2e-5 * i, 0.07));
  ASSERT_EQ(rec.Count(EventKind::kMoved), 2);
  EXPECT_EQ(rec.all[0].index, 1);
  EXPECT_NEAR(rec.all[0].value, 0.3, 1e-12);
  EXPECT_EQ(rec.all[1].index, 2);
  // Back from the -y side (the handle now leans to -y by 0.6 rad).
  const double rho = 0.07;
  for (int i = 0; i < 8000 && lever.detent() > 0; ++i) {
    const double phi = 0.6 + 0.3 - 1e-4 * i;  // polar angle of the fingertip, sweeping down
    rec.Step(lever, LeverFinger(-rho * std::sin(phi), rho * std::cos(phi)));
  }
  EXPECT_EQ(lever.detent(), 0);
  EXPECT_EQ(rec.all.back().index, 0);
}

// ---------------------------------------------------------------------------------------------

TEST(Book, OpensWhenTheCoverIsPushedPastItsAngleThenTurnsPages) {
  const scene::ControlSpec spec = Spec(scene::ControlType::kBook);
  Book book(spec);
  Recorder rec;
  const double press_z = kRadius - 0.001;  // 1 mm into the cover
  // Drag the cover from near its free edge towards the spine, 0.05 mm per step.
  double cover_before_open = 0.0;
  for (int i = 0; i <= 1000 && !book.open(); ++i) {
    rec.Step(book, OneFinger(Eigen::Vector3d(0.045 - 5e-5 * i, 0.01, press_z)));
    if (!book.open()) {
      cover_before_open = book.cover_angle_rad();
      EXPECT_GT(rec.f[1].z(), 0.0);
      if (i > 100) {
        EXPECT_NEAR(rec.f[1].x(), spec.book.page_drag_N, 1e-9);  // resists the drag
      }
    }
  }
  ASSERT_TRUE(book.open());
  ASSERT_EQ(rec.Count(EventKind::kOpened), 1);
  // Past open_angle_rad = 1.4 rad: after a drag of 1.4 / pi * 10 cm = 4.46 cm.
  EXPECT_LT(cover_before_open, spec.book.open_angle_rad);
  EXPECT_GT(cover_before_open, spec.book.open_angle_rad - 0.01);
  EXPECT_NEAR(rec.all[0].error_m, std::hypot(0.005, 0.01), 1e-9);  // from the free edge middle
  EXPECT_DOUBLE_EQ(book.cover_angle_rad(), std::numbers::pi);
  // The same touch goes on dragging: no page turns.
  for (int i = 0; i < 1000; ++i) rec.Step(book, OneFinger(Eigen::Vector3d(-0.005 - 2e-5 * i, 0.01, press_z)));
  EXPECT_EQ(rec.Count(EventKind::kPageTurned), 0);

  // Lift, touch the right page and swipe 4.5 cm towards the spine: page 1.
  rec.Step(book, OneFinger(Eigen::Vector3d(0.03, 0.0, 0.05)));
  for (int i = 0; i <= 900; ++i) rec.Step(book, OneFinger(Eigen::Vector3d(0.03 - 5e-5 * i, 0.0, press_z)));
  ASSERT_EQ(rec.Count(EventKind::kPageTurned), 1);
  EXPECT_EQ(rec.all.back().index, 1);
  EXPECT_DOUBLE_EQ(rec.all.back().value, 1.0);
  EXPECT_NEAR(rec.all.back().error_m, 0.03, 1e-9);
  EXPECT_EQ(book.page(), 1);
  // Lift, swipe on the left page away from the spine: back to page 0.
  rec.Step(book, OneFinger(Eigen::Vector3d(-0.09, 0.0, 0.05)));
  for (int i = 0; i <= 900; ++i) rec.Step(book, OneFinger(Eigen::Vector3d(-0.09 + 5e-5 * i, 0.0, press_z)));
  ASSERT_EQ(rec.Count(EventKind::kPageTurned), 2);
  EXPECT_EQ(rec.all.back().index, 0);
  EXPECT_EQ(book.page(), 0);
  // A short swipe (2 cm) turns nothing.
  rec.Step(book, OneFinger(Eigen::Vector3d(0.03, 0.0, 0.05)));
  for (int i = 0; i <= 400; ++i) rec.Step(book, OneFinger(Eigen::Vector3d(0.03 - 5e-5 * i, 0.0, press_z)));
  EXPECT_EQ(rec.Count(EventKind::kPageTurned), 2);
}

// A lever pushed halfway to its next detent and let go: while the hand moves it, its angle is
// reported (at most every 40 ms, each report 0.01 rad or more from the last); let go, it settles
// back and one last report says where it rests. None of it is an actuation: the visit is a miss.
TEST(Motion, ALeverPushedHalfwayReportsItsAngleThenComesToRest) {
  scene::ControlSpec spec = Spec(scene::ControlType::kLever);
  Lever lever(spec);
  Recorder rec;
  rec.Step(lever, OneFinger(kFar));  // the hand arrives after the lever appeared: its visit counts
  // Push the handle (from its +y side, 7 cm up; it leans to -y as its angle grows) by 0.15 rad
  // over 300 ms: the detents are 0.6 rad apart, the torque's peak at 0.3 rad; short of it, the
  // lever falls back.
  for (int i = 0; i < 300; ++i) {
    const double angle = 0.15 * i / 300.0;
    rec.Step(lever, OneFinger(Eigen::Vector3d(0.0, -0.07 * std::sin(angle) + 0.006 + kRadius - 0.0005,
                                              0.07 * std::cos(angle))));
  }
  const std::size_t while_pushed = rec.motion.size();
  EXPECT_GE(while_pushed, 3U);
  EXPECT_LE(while_pushed, 8U) << "at most one report per 40 ms";
  for (std::size_t k = 0; k < while_pushed; ++k) {
    EXPECT_EQ(rec.motion[k].index, 1) << "moving";
    EXPECT_EQ(rec.motion[k].hand, -1);
    if (k > 0) {
      EXPECT_GE(rec.motion_t_s[k] - rec.motion_t_s[k - 1], Control::kMotionPeriod_s - 1e-9);
      EXPECT_GT(rec.motion[k].value, rec.motion[k - 1].value + 0.01);
    }
  }
  EXPECT_GT(rec.motion.back().value, 0.05);
  // Let go (the hand far away): it settles back into detent 0 and says so once, at rest.
  for (int i = 0; i < 2000; ++i) rec.Step(lever, OneFinger(kFar));
  ASSERT_GT(rec.motion.size(), while_pushed);
  EXPECT_EQ(rec.motion.back().index, 0) << "the last report is at rest";
  EXPECT_NEAR(rec.motion.back().value, 0.0, 1e-9);
  const auto at_rest = std::count_if(rec.motion.begin(), rec.motion.end(), [](auto& e) { return e.index == 0; });
  EXPECT_EQ(at_rest, 1);
  EXPECT_EQ(rec.Count(EventKind::kMoved), 0);
  EXPECT_EQ(rec.Count(EventKind::kMissed), 1) << "moving a control is not actuating it";
  // Left alone, it says nothing more.
  const std::size_t reports = rec.motion.size();
  for (int i = 0; i < 1000; ++i) rec.Step(lever, OneFinger(kFar));
  EXPECT_EQ(rec.motion.size(), reports);
}

// A button pressed down reports its travel; a state set from elsewhere is no motion of this hand.
TEST(Motion, AButtonReportsItsTravelAndAnAppliedStateIsNotReported) {
  PushControl button(Spec(scene::ControlType::kButton));
  Recorder rec;
  for (int i = 0; i <= 500; ++i) rec.Step(button, OneFinger(Eigen::Vector3d(0.0, 0.0, kRadius - 0.004 * i / 500.0)));
  for (int i = 0; i < 100; ++i) rec.Step(button, OneFinger(Eigen::Vector3d(0.0, 0.0, kRadius - 0.004)));  // held down
  ASSERT_FALSE(rec.motion.empty());
  EXPECT_NEAR(rec.motion.back().value, button.travel_m(), 0.004 / 20.0 + 1e-9);
  EXPECT_EQ(rec.Count(EventKind::kPressed), 1);
  Lever lever(Spec(scene::ControlType::kLever));
  Recorder other;
  other.Step(lever, OneFinger(kFar));
  lever.RequestState(1, false);  // another user put it into detent 1
  for (int i = 0; i < 500; ++i) other.Step(lever, OneFinger(kFar));
  EXPECT_NEAR(lever.angle_rad(), 0.6, 1e-12);
  EXPECT_TRUE(other.motion.empty()) << "not this hand's motion";
}

TEST(Book, AHalfLiftedCoverFallsShut) {
  Book book(Spec(scene::ControlType::kBook));
  Recorder rec;
  for (int i = 0; i <= 400; ++i) rec.Step(book, OneFinger(Eigen::Vector3d(0.045 - 5e-5 * i, 0.0, kRadius - 0.001)));
  EXPECT_GT(book.cover_angle_rad(), 0.5);
  rec.Step(book, OneFinger(Eigen::Vector3d(0.02, 0.0, 0.05)));
  EXPECT_EQ(book.cover_angle_rad(), 0.0);
  EXPECT_FALSE(book.open());
  EXPECT_EQ(rec.Count(EventKind::kOpened), 0);
}

// ---------------------------------------------------------------------------------------------

TEST(Miss, ApproachAndWithdrawCountsOnce) {
  scene::ControlSpec spec = Spec(scene::ControlType::kButton, "button_x");
  PushControl button(spec);
  Recorder rec;
  std::vector<Eigen::Vector3d> tips(kFingers);
  // Down from 15 cm to 2 cm above the face (inside the 3 cm approach zone), and back.
  for (int i = 0; i <= 130; ++i) {
    WholeHand(Eigen::Vector3d(0.001, 0.0, 0.15 - 1e-3 * i), tips);
    rec.Step(button, tips);
  }
  EXPECT_EQ(rec.Count(EventKind::kMissed), 0);  // not yet: still there
  for (int i = 130; i >= 0; --i) {
    WholeHand(Eigen::Vector3d(0.001, 0.0, 0.15 - 1e-3 * i), tips);
    rec.Step(button, tips);
  }
  ASSERT_EQ(rec.Count(EventKind::kMissed), 1);
  const ControlEvent& miss = rec.all.back();
  EXPECT_EQ(miss.id(), "button_x");
  EXPECT_EQ(miss.hand, 0);
  EXPECT_EQ(miss.finger, 2);                      // the middle fingertip came closest
  EXPECT_NEAR(miss.error_m, std::hypot(0.001, 0.02), 1e-9);
  EXPECT_EQ(button.missed_count(), 1);
}

TEST(Miss, HoveringAtTheBorderCountsOnceAndAPressIsNoMiss) {
  PushControl button(Spec(scene::ControlType::kButton));
  Recorder rec;
  std::vector<Eigen::Vector3d> tips(kFingers);
  // The zone's border is 3 cm above the face: wobble between 2.8 and 3.3 cm, then leave.
  for (int i = 0; i < 2000; ++i) {
    WholeHand(Eigen::Vector3d(0.0, 0.0, 0.0305 + 0.0025 * std::sin(0.05 * i)), tips);
    rec.Step(button, tips);
  }
  WholeHand(Eigen::Vector3d(0.0, 0.0, 0.2), tips);
  rec.Step(button, tips);
  EXPECT_EQ(rec.Count(EventKind::kMissed), 1);

  // Reach and press 5 mm deep with the middle finger, then withdraw: a hit, not a miss.
  for (int i = 0; i <= 197; ++i) {
    WholeHand(Eigen::Vector3d(0.0, 0.0, 0.2 - 1e-3 * i), tips);
    tips[0] = tips[1] = tips[3] = tips[4] = kFar;
    rec.Step(button, tips);
  }
  EXPECT_EQ(rec.Count(EventKind::kPressed), 1);
  for (int i = 197; i >= 0; --i) {
    WholeHand(Eigen::Vector3d(0.0, 0.0, 0.2 - 1e-3 * i), tips);
    rec.Step(button, tips);
  }
  EXPECT_EQ(rec.Count(EventKind::kReleased), 1);
  EXPECT_EQ(rec.Count(EventKind::kMissed), 1);
  EXPECT_EQ(button.missed_count(), 1);
}

TEST(Miss, EachHandCountsItsOwnAndAHandPresentAtTheStartDoesNot) {
  PushControl button(Spec(scene::ControlType::kButton));
  Recorder rec;
  std::vector<Eigen::Vector3d> tips(2 * kFingers, kFar);
  // Hand 0 is on the button when it appears (a scene switch under the hand): leaving is no miss.
  WholeHand(Eigen::Vector3d(0.0, 0.0, 0.02), tips, 0);
  rec.Step(button, tips);
  WholeHand(Eigen::Vector3d(0.0, 0.0, 0.3), tips, 0);
  rec.Step(button, tips);
  EXPECT_EQ(rec.Count(EventKind::kMissed), 0);
  // Hand 1 reaches and withdraws: one miss, for hand 1.
  WholeHand(Eigen::Vector3d(0.0, 0.0, 0.02), tips, 1);
  rec.Step(button, tips);
  WholeHand(Eigen::Vector3d(0.0, 0.0, 0.3), tips, 1);
  rec.Step(button, tips);
  ASSERT_EQ(rec.Count(EventKind::kMissed), 1);
  EXPECT_EQ(rec.all.back().hand, 1);
}

TEST(Miss, ALeverPushedFromTheWrongSideIsAMiss) {
  Lever lever(Spec(scene::ControlType::kLever));
  Recorder rec;
  // From 15 cm on the -y side up to the handle and 8 mm into it, and back.
  for (int i = 0; i <= 1500; ++i) rec.Step(lever, LeverFinger(-0.15 + 1e-4 * i, 0.07));
  EXPECT_GT(rec.f[1].norm(), 1.0);  // it did push on the handle
  for (int i = 1500; i >= 0; --i) rec.Step(lever, LeverFinger(-0.15 + 1e-4 * i, 0.07));
  EXPECT_EQ(rec.Count(EventKind::kMoved), 0);
  EXPECT_EQ(rec.Count(EventKind::kMissed), 1);
}

// ---------------------------------------------------------------------------------------------

TEST(ControlSet, BuiltFromTheSceneWithActions) {
  const scene::Scene s = scene::LoadSceneByName("solar_system", std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes");
  ControlSet set = MakeControls(s);
  ASSERT_EQ(set.size(), s.controls.size());
  Control* lever = set.Find("lever_planet");
  ASSERT_NE(lever, nullptr);
  EXPECT_EQ(lever->type(), scene::ControlType::kLever);
  ControlEvent moved;
  std::snprintf(moved.control_id.data(), moved.control_id.size(), "%s", "lever_planet");
  moved.kind = EventKind::kMoved;
  moved.index = 1;
  const scene::Action* mars = set.ActionFor(moved);
  ASSERT_NE(mars, nullptr);
  EXPECT_DOUBLE_EQ(mars->gravity_W_m_per_s2.z(), -3.71);
  moved.kind = EventKind::kMissed;
  EXPECT_EQ(set.ActionFor(moved), nullptr);

  // Push the lever in the scene from the visitor's side (-y of W; the lever is turned 180
  // degrees about z): it moves to Mars.
  const Eigen::Vector3d hinge = s.controls[0].p_WC_m;
  EventBuffer events;
  std::vector<Eigen::Vector3d> tips(kFingers, kFar), f(kFingers);
  bool to_mars = false;
  for (int i = 0; i < 4000 && !to_mars; ++i) {
    tips[1] = hinge + Eigen::Vector3d(0.0, -0.016 + 2e-5 * i, 0.07);
    events.Clear();
    set.Step(kDt, tips, kRadius, f, events);
    for (const auto& e : events) {
      if (e.kind == EventKind::kMoved) {
        const scene::Action* a = set.ActionFor(e);
        ASSERT_NE(a, nullptr);
        to_mars = a->set_gravity && a->gravity_W_m_per_s2.z() == -3.71;
      }
    }
  }
  EXPECT_TRUE(to_mars);
}

// The start menu's solar-system book as a visitor uses it: opening shows page 1 (its messages,
// no world), a swipe on the right page resists like a detent and lets go as the page turns, and
// page 2 takes the book's world.
TEST(ControlSet, OpenTheBookTurnToPageTwoAndTakeItsAction) {
  const scene::Scene s = scene::LoadSceneByName("start_menu", std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes");
  ControlSet set = MakeControls(s);
  auto* book = dynamic_cast<Book*>(set.Find("book_solar_system"));
  ASSERT_NE(book, nullptr);
  const Eigen::Vector3d p_WC = book->spec().p_WC_m;  // the book lies unrotated: C is W moved
  const double press_z = kRadius - 0.001;            // 1 mm into the cover or the page
  EventBuffer events;
  std::vector<ControlEvent> all;
  std::vector<Eigen::Vector3d> f(kFingers);
  const auto step = [&](const Eigen::Vector3d& p_C) {
    events.Clear();
    set.Step(kDt, OneFinger(p_WC + p_C), kRadius, f, events);
    std::copy_if(events.begin(), events.end(), std::back_inserter(all),
                 [](const ControlEvent& e) { return e.kind != EventKind::kMoving; });
  };
  for (int i = 0; i <= 1000 && !book->open(); ++i) step(Eigen::Vector3d(0.045 - 5e-5 * i, 0.0, press_z));
  ASSERT_TRUE(book->open());
  ASSERT_EQ(all.size(), 1U);
  ASSERT_EQ(all[0].kind, EventKind::kOpened);
  const scene::Action* opened = set.ActionFor(all[0]);
  ASSERT_NE(opened, nullptr);
  EXPECT_TRUE(opened->goto_scene.empty()) << "opening shows page 1, in the start menu";
  ASSERT_FALSE(opened->messages.empty());
  EXPECT_EQ(opened->messages[0].text, "Planets in the solar system.");

  step(Eigen::Vector3d(0.03, 0.0, 0.05));  // lift
  double resisted_N = 0.0;
  bool let_go = false;
  for (int i = 0; i <= 900; ++i) {
    step(Eigen::Vector3d(0.03 - 5e-5 * i, 0.0, press_z));
    if (book->page() == 0) resisted_N = std::max(resisted_N, f[1].x());
    else if (!let_go) let_go = std::abs(f[1].x()) < 1e-12;
  }
  EXPECT_NEAR(resisted_N, book->spec().book.page_drag_N, 1e-9) << "the page resists the swipe";
  EXPECT_TRUE(let_go) << "and lets go once it has turned";
  ASSERT_EQ(all.size(), 2U);
  EXPECT_EQ(all[1].kind, EventKind::kPageTurned);
  EXPECT_EQ(all[1].index, 1);
  const scene::Action* page2 = set.ActionFor(all[1]);
  ASSERT_NE(page2, nullptr);
  EXPECT_EQ(page2->goto_scene, "solar_system");
}

// One rule for every control kind: which action an event takes.
TEST(ControlSet, ActionOfEachEventKind) {
  scene::Action go;
  go.goto_scene = "dinosaur";
  scene::Action say;
  say.title = "page";
  scene::ControlSpec button = Spec(scene::ControlType::kButton);
  button.action = go;
  EXPECT_EQ(ActionOf(button, EventKind::kPressed, -1), &button.action);
  EXPECT_EQ(ActionOf(button, EventKind::kReleased, -1), nullptr);
  EXPECT_EQ(ActionOf(button, EventKind::kMissed, -1), nullptr);
  EXPECT_EQ(ActionOf(button, EventKind::kOpened, 0), nullptr);
  scene::ControlSpec lever = Spec(scene::ControlType::kLever);
  lever.detent_actions = {scene::Action{}, go};
  EXPECT_EQ(ActionOf(lever, EventKind::kMoved, 0), nullptr) << "an empty action is none";
  EXPECT_EQ(ActionOf(lever, EventKind::kMoved, 1), &lever.detent_actions[1]);
  EXPECT_EQ(ActionOf(lever, EventKind::kMoved, 2), nullptr);
  EXPECT_EQ(ActionOf(lever, EventKind::kPressed, -1), nullptr);
  scene::ControlSpec book = Spec(scene::ControlType::kBook);
  book.page_actions = {say, go};
  EXPECT_EQ(ActionOf(book, EventKind::kOpened, 0), &book.page_actions[0]) << "without its own, page 1's";
  EXPECT_EQ(ActionOf(book, EventKind::kPageTurned, 1), &book.page_actions[1]);
  EXPECT_EQ(ActionOf(book, EventKind::kPageTurned, -1), nullptr);
  EXPECT_EQ(ActionOf(book, EventKind::kPressed, -1), nullptr);
  book.action = go;
  EXPECT_EQ(ActionOf(book, EventKind::kOpened, 0), &book.action) << "its own when it has one";
}

TEST(ControlSet, EveryProjectSceneBuildsItsControls) {
  for (const std::string& name : scene::SceneNames(std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes")) {
    const scene::Scene s = scene::LoadSceneByName(name, std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes");
    ControlSet set = MakeControls(s);
    ASSERT_EQ(set.size(), s.controls.size()) << name;
    // Every world of the encyclopedia has a way on and a way back (commons, the many-station
    // table, has only the way back).
    if (name != "commons") {
      EXPECT_GE(set.size(), 2u) << name;
    }
    for (std::size_t i = 0; i < set.size(); ++i) {
      EXPECT_EQ(set[i].id(), s.controls[i].id);
      EXPECT_EQ(set[i].type(), s.controls[i].type);
    }
  }
}

TEST(ControlSet, StepDoesNotAllocate) {
  const scene::Scene s = scene::LoadSceneByName("start_menu", std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes");
  ControlSet set = MakeControls(s);
  ASSERT_EQ(set.size(), 6u);
  std::vector<Eigen::Vector3d> tips(3 * kFingers), f(3 * kFingers);
  EventBuffer events;
  // Three hands sweeping over the books and buttons, pressing, dragging and leaving: every
  // branch (contacts, clicks, page turns, misses) runs inside the counted window.
  auto place = [&](int i) {
    const double t = i * kDt;
    for (int h = 0; h < 3; ++h) {
      const Eigen::Vector3d c(-0.2 + 0.4 * std::fmod(0.1 * t + 0.3 * h, 1.0), (h == 1 ? -0.08 : 0.08),
                              0.02 + 0.05 * std::cos(2.0 * t + h));
      WholeHand(c, tips, h);
    }
  };
  place(0);
  set.Step(kDt, tips, kRadius, f, events);  // warm-up outside the measured window
  long events_seen = 0;
  const long before = testing::AllocationCount();
  for (int i = 1; i < 20000; ++i) {
    place(i);
    events.Clear();
    set.Step(kDt, tips, kRadius, f, events);
    events_seen += events.size();
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_GT(events_seen, 0);  // the window did exercise the event paths
}

TEST(ControlSet, ForcesAreBoundedAndNaNFingertipsGetNone) {
  const scene::Scene s = scene::LoadSceneByName("start_menu", std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes");
  ControlSet set = MakeControls(s);
  std::mt19937 rng(7);  // fixed seed
  std::uniform_real_distribution<double> x(-0.25, 0.25), y(-0.2, 0.2), z(-0.04, 0.06);
  std::vector<Eigen::Vector3d> tips(2 * kFingers), f(2 * kFingers);
  EventBuffer events;
  double largest = 0.0;
  for (int i = 0; i < 20000; ++i) {
    for (auto& p : tips) p = Eigen::Vector3d(x(rng), y(rng), z(rng));
    tips[3] = Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
    events.Clear();
    set.Step(kDt, tips, kRadius, f, events);
    for (const auto& fi : f) {
      ASSERT_TRUE(fi.allFinite());
      largest = std::max(largest, fi.norm());
    }
    EXPECT_EQ(f[3].norm(), 0.0);
  }
  EXPECT_LE(largest, 3.5 + 1e-9);
  EXPECT_GT(largest, 3.0);  // the random fingertips did dig in
}

TEST(EventBuffer, CountsWhatDoesNotFit) {
  EventBuffer b;
  ControlEvent e;
  for (int i = 0; i < EventBuffer::kCapacity + 3; ++i) b.Push(e);
  EXPECT_EQ(b.size(), EventBuffer::kCapacity);
  EXPECT_EQ(b.dropped(), 3);
  static_assert(std::is_trivially_copyable_v<ControlEvent>);
}

}  // namespace
}  // namespace handshare::controls
