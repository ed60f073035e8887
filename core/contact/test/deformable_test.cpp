// Deformable contact through handshare::fem: the force on a fingertip pressing a FEM block equals
// a direct ContactPatchFinder + ContactSolver solve, and two hands on one object (one local, one
// remote, each in its own HapticWorld) get the forces of one solve with all their contacts.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "handshare/contact/haptic_world.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_patch.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/mesh.hpp"
#include "test_util.hpp"

namespace handshare::contact {
namespace {

constexpr double kR = 0.008;

// A 6 x 6 x 3 cm block, 4 mm cells, bottom fixed, E = 20 kPa (soft tissue-like), frame O at a
// shifted, rotated pose so frames are exercised.
struct Block {
  std::shared_ptr<fem::TetMesh> mesh;
  std::shared_ptr<const fem::Compliance> C;
  fem::Surface surface;
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  double top = 0.03;
};

const Block& TheBlock() {
  static const Block b = [] {
    Block s;
    const test::SoftBlock soft = test::MakeSoftBlock();
    s.mesh = soft.mesh;
    s.C = soft.C;
    s.surface = fem::ExtractSurface(*s.mesh);
    s.X_WO = Eigen::Translation3d(0.1, -0.05, 0.2) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
    return s;
  }();
  return b;
}

// The contact the world should find for a fingertip pressed straight down (O's -z) at (x, y).
struct Press {
  double x, y, depth;
};

Eigen::Vector3d TipAbove(const Block& b, const Press& p, double height) {
  return b.X_WO * Eigen::Vector3d(p.x, p.y, b.top + kR + height);
}

// Oracle: ContactPatchFinder::Sphere + one push-only ContactSolver::Solve with every press.
// Returns the force on each fingertip in W.
std::vector<Eigen::Vector3d> Direct(const Block& b, const std::vector<Press>& presses, int max_patch) {
  fem::ContactPatchFinder finder(*b.mesh, b.surface, *b.C);
  fem::ContactSolverOptions so;
  so.max_contacts = 256;
  so.push_only = true;
  fem::ContactSolver solver(b.C, so);
  std::vector<fem::ContactInput> in(256);
  std::vector<std::pair<int, int>> range;
  int m = 0;
  for (const Press& p : presses) {
    const auto r = finder.Sphere({p.x, p.y, b.top}, Eigen::Vector3d::UnitZ(), kR, p.depth,
                                 fem::ContactMode::kNormalOnly, std::span(in).subspan(m, max_patch));
    range.emplace_back(m, r.count);
    m += r.count;
  }
  EXPECT_EQ(solver.Solve(std::span(in.data(), m)), fem::StepStatus::kOk);
  std::vector<Eigen::Vector3d> f;
  for (auto [b0, n] : range) {
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) s += solver.forces_N()[static_cast<std::size_t>(b0 + i)];
    f.push_back(-(b.X_WO.linear() * s));
  }
  return f;
}

std::unique_ptr<HapticWorld> MakeWorld(const Block& b, int max_patch, ObjectId* id) {
  auto w = std::make_unique<HapticWorld>(WorldConfig{.max_hands = 2, .max_force_N = 100.0});
  DeformableDesc d;
  d.mesh = b.mesh;
  d.compliance = b.C;
  d.X_WO = b.X_WO;
  d.max_patch_nodes = max_patch;
  *id = w->AddDeformable(d);
  w->Init();
  return w;
}

// Lowers the given fingers from 2 mm above to their depths in 40 steps.
void Lower(HapticWorld& w, const Block& b, const std::vector<Press>& presses,
           std::span<const FingerContact> remote = {}) {
  for (int k = 0; k <= 40; ++k) {
    std::array<Eigen::Vector3d, kFingers> tips;
    for (int i = 0; i < kFingers; ++i) tips[static_cast<std::size_t>(i)] = Eigen::Vector3d(5.0, 5.0, 5.0 + i);
    for (std::size_t i = 0; i < presses.size(); ++i) {
      const double h = 0.002 - (0.002 + presses[i].depth) * k / 40.0;
      tips[i] = TipAbove(b, presses[i], h);
    }
    w.Step(1e-3, tips, remote);
  }
}

TEST(Deformable, FingertipForceMatchesADirectContactSolve) {
  const Block& b = TheBlock();
  ObjectId id = -1;
  auto w = MakeWorld(b, 32, &id);
  const std::vector<Press> presses = {{0.03, 0.03, 0.002}};
  Lower(*w, b, presses);
  const FingerResult& r = w->fingers()[0];
  ASSERT_TRUE(r.in_contact);
  EXPECT_EQ(r.object, id);
  EXPECT_NEAR(r.depth_m, 0.002, 1e-12);
  EXPECT_GT(r.patch_nodes, 3);
  const auto f = Direct(b, presses, 32);
  // Same patch and same solve: equal to round-off (1e-12 relative).
  EXPECT_LT((r.f_E_W_N - f[0]).norm(), 1e-12 * f[0].norm()) << r.f_E_W_N.transpose() << " vs " << f[0].transpose();
  // Pushes the fingertip out of the block (O's +z), a fraction of a newton for 2 mm into 20 kPa.
  const Eigen::Vector3d z_W = b.X_WO.linear() * Eigen::Vector3d::UnitZ();
  EXPECT_GT(r.f_E_W_N.dot(z_W), 0.9 * r.f_E_W_N.norm());
  // ContactSet fields: main node is a patch node next to the contact point; u = -depth n.
  ASSERT_GE(r.main_node, 0);
  EXPECT_LT((b.X_WO * b.mesh->positions_m()[static_cast<std::size_t>(r.main_node)] - r.p_WC_m).norm(), 0.004);
  EXPECT_LT((r.u_W_m + 0.002 * z_W).norm(), 1e-12);
  // Held loads: forces on the object, summing to minus the fingertip force (in O).
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const fem::NodeLoad& l : w->held_loads(id)) sum += l.f_N;
  EXPECT_LT((b.X_WO.linear() * sum + r.f_E_W_N).norm(), 1e-12);
}

TEST(Deformable, TwoHandsOnOneObjectAreSolvedTogether) {
  const Block& b = TheBlock();
  ObjectId id_a = -1, id_b = -1;
  auto a = MakeWorld(b, 16, &id_a);  // hand A: local here, remote there
  auto h = MakeWorld(b, 16, &id_b);  // hand B
  const std::vector<Press> pa = {{0.02, 0.02, 0.002}, {0.035, 0.02, 0.0015}};
  const std::vector<Press> pb = {{0.03, 0.042, 0.0025}, {0.045, 0.035, 0.001}, {0.015, 0.04, 0.002}};
  // Both hands press; each world gets the other's last contacts (as the ContactSet carries).
  auto contacts_of = [](const HapticWorld& w) {
    std::vector<FingerContact> out;
    for (int i = 0; i < kFingers; ++i) {
      const FingerResult& r = w.fingers()[static_cast<std::size_t>(i)];
      if (r.in_contact) out.push_back(r.contact);  // a peer's contact is just the other hand's result
    }
    return out;
  };
  Lower(*h, b, pb);
  const auto from_b = contacts_of(*h);
  ASSERT_EQ(from_b.size(), 3u);
  Lower(*a, b, pa, from_b);
  const auto from_a = contacts_of(*a);
  ASSERT_EQ(from_a.size(), 2u);
  Lower(*h, b, pb, from_a);
  std::vector<Press> all = pa;
  all.insert(all.end(), pb.begin(), pb.end());
  const auto f = Direct(b, all, 16);
  for (int i = 0; i < 2; ++i) {
    EXPECT_LT((a->fingers()[static_cast<std::size_t>(i)].f_E_W_N - f[static_cast<std::size_t>(i)]).norm(), 1e-12 * f[static_cast<std::size_t>(i)].norm() + 1e-15);
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT((h->fingers()[static_cast<std::size_t>(i)].f_E_W_N - f[static_cast<std::size_t>(2 + i)]).norm(), 1e-12 * f[static_cast<std::size_t>(2 + i)].norm() + 1e-15);
  }
  // Solving each hand alone would differ (the block couples the hands), so the test can fail.
  const auto alone = Direct(b, pa, 16);
  EXPECT_GT((alone[0] - f[0]).norm(), 1e-4 * f[0].norm());
  // Both worlds hold the same node loads.
  ASSERT_EQ(a->held_loads(id_a).size(), h->held_loads(id_b).size());
}

// A peer's contacts change at the network's rate, so the world keeps each remote contact's patch
// from the step before and reuses it while the contact is the same. Every change must still be
// seen: over a sequence where a peer's contacts deepen, move, swap places in its list, go and
// come back, the force each remote contact puts on the block equals that of a new world (no
// earlier step) given the same contacts.
TEST(Deformable, APeersContactsAreFollowedThroughEveryChange) {
  const Block& b = TheBlock();
  const Eigen::Vector3d n_W = b.X_WO.linear() * Eigen::Vector3d::UnitZ();
  auto at = [&](int finger, double x, double y, double depth) {
    return ContactInObjectFrame(b.X_WO, finger, 0, b.X_WO * Eigen::Vector3d(x, y, b.top),
                                b.X_WO * Eigen::Vector3d(x, y, b.top + kR - depth), -depth * n_W,
                                Eigen::Vector3d::Zero(), n_W);
  };
  const FingerContact c0 = at(0, 0.02, 0.02, 0.0015), c1 = at(1, 0.04, 0.035, 0.001);
  FingerContact c0_deeper = c0;
  AsVector(c0_deeper.u_O_m) = -0.0022 * Eigen::Vector3d::UnitZ();  // n_O
  FingerContact c1_moved = c1;
  c1_moved.p_OC_m[0] += 0.001;
  const std::vector<std::vector<FingerContact>> schedule = {
      {c0, c1}, {c0, c1}, {c0, c1}, {c0_deeper, c1}, {c0_deeper, c1}, {c0_deeper, c1_moved},
      {c1_moved, c0_deeper}, {c1_moved, c0_deeper}, {c0, c1}, {c0}, {c0, c1}, {c1}, {c0, c1}};
  ObjectId id = -1;
  auto w = MakeWorld(b, 16, &id);
  ASSERT_EQ(id, 0);
  std::array<Eigen::Vector3d, kFingers> away;
  for (int i = 0; i < kFingers; ++i) away[static_cast<std::size_t>(i)] = Eigen::Vector3d(5.0, 5.0, 5.0 + i);
  for (std::size_t k = 0; k < schedule.size(); ++k) {
    w->Step(1e-3, away, schedule[k]);
    ObjectId id_fresh = -1;
    auto fresh = MakeWorld(b, 16, &id_fresh);
    fresh->Step(1e-3, away, schedule[k]);
    ASSERT_EQ(w->remote_forces_O().size(), schedule[k].size());
    ASSERT_EQ(fresh->remote_forces_O().size(), schedule[k].size());
    for (std::size_t r = 0; r < schedule[k].size(); ++r) {
      const Eigen::Vector3d f = w->remote_forces_O()[r], g = fresh->remote_forces_O()[r];
      ASSERT_GT(g.norm(), 0.01) << "step " << k << " contact " << r;
      EXPECT_LT((f - g).norm(), 1e-12 * g.norm()) << "step " << k << " contact " << r << ": " << f.transpose()
                                                  << " against " << g.transpose();
    }
  }
}

// A hand has 1 to 5 contact points: a one-point device (a stylus) hands in one fingertip, with no
// NaN stand-ins for the fingers it lacks, and a process with no hand at all (the world server)
// hands in none and still solves the others' contacts.
TEST(Deformable, AOnePointHandAndAHandlessSolveNeedNoStandIns) {
  const Block& b = TheBlock();
  ObjectId id = -1;
  auto five = MakeWorld(b, 16, &id);
  Lower(*five, b, {{0.03, 0.03, 0.002}});  // finger 0 presses, the other four far away
  auto one = MakeWorld(b, 16, &id);
  StepReport rep;
  for (int k = 0; k <= 40; ++k) {
    const std::array<Eigen::Vector3d, 1> tip = {TipAbove(b, {0.03, 0.03, 0.002}, 0.002 - 0.004 * k / 40.0)};
    rep = one->Step(1e-3, tip);
  }
  EXPECT_TRUE(rep.ok);
  EXPECT_EQ(rep.invalid_fingers, 0);  // the missing fingers are not faults
  const FingerResult& r = one->fingers()[0];
  ASSERT_TRUE(r.in_contact);
  EXPECT_LT((r.f_E_W_N - five->fingers()[0].f_E_W_N).norm(), 1e-12 * r.f_E_W_N.norm());
  for (int i = 1; i < kFingers; ++i) {
    const FingerResult& absent = one->fingers()[static_cast<std::size_t>(i)];
    EXPECT_FALSE(absent.in_contact);
    EXPECT_TRUE(absent.f_E_W_N.isZero(0.0));
    EXPECT_FALSE(absent.contact.active());
    EXPECT_EQ(absent.contact.finger, i);
  }
  // No hand: the one-point hand's contact alone, as the world server solves it.
  auto server = MakeWorld(b, 16, &id);
  const StepReport srep = server->Step(1e-3, std::span<const Eigen::Vector3d>{}, std::span(&r.contact, 1));
  EXPECT_TRUE(srep.ok);
  EXPECT_EQ(srep.invalid_fingers, 0);
  EXPECT_LT((server->remote_forces_O()[0] - AsVector(r.contact.f_O_N)).norm(), 1e-9 * r.f_E_W_N.norm());
  // More contact points than a hand has: refused, nothing felt.
  const std::array<Eigen::Vector3d, kFingers + 1> six{};
  EXPECT_FALSE(server->Step(1e-3, six).ok);
}

// A deformable that moves as a rigid body (a swimming Daphnia, a bob): the hand that presses it
// and a process that solves that hand's contact again (the world server, a peer) hold the body at
// poses a few milliseconds apart. The contact travels in the body's frame O, so the receiver
// rebuilds the patch the hand solved and puts the force the hand felt on the body, wherever it
// has the body. Carried in the world frame (as contact sets did before), the receiver mapped
// the point into the body with its own pose: another patch, another force (0.4-4 % for a 10 mm,
// 2.5 s bob in the tour's terms); the second half of the test keeps that old path as the
// counter-example, so the test fails if the contact were rebuilt from W again.
TEST(Deformable, AMovingBodyIsSolvedAsTheHandFeltItWhereverTheReceiverHasIt) {
  const Block& b = TheBlock();
  ObjectId id = -1;
  auto hand = MakeWorld(b, 16, &id);
  Lower(*hand, b, {{0.03, 0.03, 0.002}});
  const FingerResult& r = hand->fingers()[0];
  ASSERT_TRUE(r.in_contact);
  ASSERT_EQ(r.contact.object, id);
  // The hand felt minus the force on the body (in O).
  const Eigen::Vector3d f_on_body_O = AsVector(r.contact.f_O_N);
  EXPECT_LT((b.X_WO.linear() * f_on_body_O + r.f_E_W_N).norm(), 1e-12 * r.f_E_W_N.norm());
  std::array<Eigen::Vector3d, kFingers> away;
  for (int i = 0; i < kFingers; ++i) away[static_cast<std::size_t>(i)] = Eigen::Vector3d(5.0, 5.0, 5.0 + i);
  // The receiver has the body 0.4 mm further along its swim (10 mm amplitude, 2.5 s period:
  // 25 mm/s at mid-swing, 16 ms apart) and turned a little.
  const Eigen::Isometry3d X_moved =
      Eigen::Translation3d(0.0003, -0.0002, 0.0002) * b.X_WO * Eigen::AngleAxisd(0.002, Eigen::Vector3d::UnitX());
  auto receiver = [&](const FingerContact& c) {
    ObjectId rid = -1;
    auto w = MakeWorld(b, 16, &rid);
    w->SetPose(rid, X_moved);
    w->Step(1e-3, away, std::span(&c, 1));
    return Eigen::Vector3d(w->remote_forces_O()[0]);
  };
  const Eigen::Vector3d f_here = receiver(r.contact);
  EXPECT_LT((f_here - f_on_body_O).norm(), 1e-9 * f_on_body_O.norm())
      << f_here.transpose() << " against the felt " << f_on_body_O.transpose();
  // The old way: the point, normal and displacement in W as the hand had the body, mapped into
  // the body with the receiver's pose.
  const FingerContact in_W = ContactInObjectFrame(X_moved, 0, id, b.X_WO * AsVector(r.contact.p_OC_m),
                                                  b.X_WO * AsVector(r.contact.p_OE_m),
                                                  b.X_WO.linear() * AsVector(r.contact.u_O_m), r.f_E_W_N,
                                                  b.X_WO.linear() * AsVector(r.contact.n_O));
  const Eigen::Vector3d f_old = receiver(in_W);
  RecordProperty("world_frame_error", std::to_string((f_old - f_on_body_O).norm() / f_on_body_O.norm()));
  EXPECT_GT((f_old - f_on_body_O).norm(), 0.004 * f_on_body_O.norm()) << "the counter-example no longer differs";
}

}  // namespace
}  // namespace handshare::contact
