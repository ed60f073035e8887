// The one contact type's conversion from the world frame (finger_contact.hpp): a contact a test
// or a tool gives in W comes out in the object's frame O as the haptic world itself shares it.
#include <gtest/gtest.h>

#include <array>

#include "handshare/contact/finger_contact.hpp"
#include "handshare/contact/haptic_world.hpp"
#include "test_util.hpp"

namespace handshare::contact {
namespace {

// Oracle: the world's own shared contact (HapticWorld::SharedContact, frame O) of a fingertip
// pressing a soft block at a shifted, rotated pose. The same contact given in W (FingerResult's
// point, normal, displacement and felt force, the fingertip centre where the hand had it) must
// convert to it field by field: the fingertip centre E is not the contact point C (they are a
// fingertip radius minus the depth apart).
TEST(FingerContact, AContactGivenInWIsTheWorldsOwnContactInO) {
  const test::SoftBlock block = test::MakeSoftBlock();
  HapticWorld w(WorldConfig{.max_force_N = 100.0});
  DeformableDesc d;
  d.mesh = block.mesh;
  d.compliance = block.C;
  d.X_WO = Eigen::Translation3d(0.1, -0.05, 0.2) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
  const ObjectId id = w.AddDeformable(d);
  w.Init();
  const double r = w.config().fingertip_radius_m, depth = 0.0015;
  // Lowered from 2 mm above the top face (z = 3 cm in O) to the depth: the proxy comes from outside.
  Eigen::Vector3d p_WE;
  for (int k = 0; k <= 40; ++k) {
    p_WE = d.X_WO * Eigen::Vector3d(0.03, 0.025, 0.03 + r + 0.002 - (0.002 + depth) * k / 40.0);
    const std::array<Eigen::Vector3d, 1> tips = {p_WE};
    w.Step(1e-3, tips);
  }
  const FingerResult& res = w.fingers()[0];
  ASSERT_TRUE(res.in_contact);
  ASSERT_EQ(res.contact.object, id);
  const FingerContact c = ContactInObjectFrame(w.pose(id), 0, id, res.p_WC_m, p_WE, res.u_W_m, res.f_E_W_N, res.n_W);
  const FingerContact& shared = res.contact;
  // 1e-12 m / 1e-9 N: one rotation there and back in doubles.
  auto near = [](const Vec3& a, const Vec3& b, double tol) { return (AsVector(a) - AsVector(b)).norm() < tol; };
  EXPECT_TRUE(near(c.p_OE_m, shared.p_OE_m, 1e-12)) << AsVector(c.p_OE_m).transpose() << " vs " << AsVector(shared.p_OE_m).transpose();
  EXPECT_TRUE(near(c.p_OC_m, shared.p_OC_m, 1e-12)) << AsVector(c.p_OC_m).transpose() << " vs " << AsVector(shared.p_OC_m).transpose();
  EXPECT_TRUE(near(c.n_O, shared.n_O, 1e-12));
  EXPECT_TRUE(near(c.u_O_m, shared.u_O_m, 1e-12));
  EXPECT_TRUE(near(c.f_O_N, shared.f_O_N, 1e-9));
  EXPECT_NEAR(c.depth_m, shared.depth_m, 1e-12);
  EXPECT_EQ(c.finger, shared.finger);
  EXPECT_EQ(c.object, shared.object);
  // E and C really differ here, so the first check means something.
  EXPECT_GT((AsVector(shared.p_OE_m) - AsVector(shared.p_OC_m)).norm(), 0.5 * r);
}

}  // namespace
}  // namespace handshare::contact
