#pragma once
/// @file
/// The one contact type of handshare: a fingertip touching an object, as a hand's haptic step
/// makes it (contact::HapticWorld::fingers()[i].contact), as the bridge hands it to DDS
/// (dds::EncodeFingerContact), as a receiver decodes it (dds::DecodeFingerContact) and as a
/// solve takes it for that other hand (HapticWorld::Step's `remote`): a peer's contact is just
/// another hand's result. Plain, trivially copyable data (snapshots and lock-free channels carry
/// it), no middleware, header-only (handshare::contact_types).
///
/// Frame: everything is in the touched object's frame O, which moves with the object. A body that
/// moves rigidly while touched (a swimming deformable, a carried ball) is seen at slightly
/// different poses by the hand that touches it and by the processes that solve that hand's
/// contact again (their clocks and samples differ by milliseconds): in O they rebuild the very
/// patch the hand solved, whatever pose they hold for the body.
///
/// Sign convention, stated once for every process: f_O_N is the force the fingertip puts ON THE
/// OBJECT. The fingertip feels -f_O_N.
#include <array>
#include <cstdint>
#include <type_traits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace handshare::contact {

/// An object of one process's haptic models (an index: each process maps the scene's object
/// ids to its own indices).
using ObjectId = std::int32_t;

/// A vector stored as plain doubles (x, y, z): what snapshots and the wire carry.
using Vec3 = std::array<double, 3>;
/// A unit quaternion stored as plain doubles (w, x, y, z).
using QuatWxyz = std::array<double, 4>;

/// One fingertip E touching one object O. Frame O throughout (see the file comment).
struct FingerContact {
  std::int32_t finger = 0;  ///< 0 thumb, 1 index, 2 middle, 3 ring, 4 little
  ObjectId object = -1;     ///< the touched object; -1: this finger touches nothing
  std::int32_t node = -1;   ///< deformable: the patch node nearest p_OC_m; -1: rigid
  /// Contact point on the object's undeformed (rest) surface [m]. With friction on a deformable:
  /// where the step's patch was found plus its slide, so that a receiver rebuilds that patch
  /// around p_OC_m - stick (stick: the part of u_O_m along the surface).
  Vec3 p_OC_m{};
  Vec3 n_O{};     ///< outward unit surface normal at p_OC_m (zero: unknown, taken as -u / |u|)
  Vec3 p_OE_m{};  ///< fingertip centre [m]
  /// Deformable: the displacement the fingertip imposes on the surface [m], the indentation
  /// -depth_m n_O plus the fingertip's stick (friction). Rigid: zero.
  Vec3 u_O_m{};
  Vec3 f_O_N{};   ///< force on the object [N] (the fingertip feels minus this)
  double depth_m = 0.0;  ///< penetration of the fingertip along -n_O [m]

  bool active() const noexcept { return object >= 0; }
};
static_assert(std::is_trivially_copyable_v<FingerContact>);

/// Another hand's contact as it arrived in this process: the contact (not faded), who sent it
/// and when it came. Plain data.
struct PeerContact {
  FingerContact contact;
  std::int32_t hand = 0;          ///< 1, 2, ... in user-name order (changes as users come and go)
  std::uint64_t user_key = 0;     ///< the user's, for as long as the user is there (UserKey); 0: unknown
  std::uint64_t received_ns = 0;  ///< when its set arrived here (steady clock, common::SteadyNowNs) [ns]
};
static_assert(std::is_trivially_copyable_v<PeerContact>);

// ---- The one conversion between plain arrays (snapshots, the wire) and Eigen ----

/// A plain vector seen as an Eigen vector (no copy).
inline Eigen::Map<const Eigen::Vector3d> AsVector(const Vec3& v) noexcept { return Eigen::Map<const Eigen::Vector3d>(v.data()); }
inline Eigen::Map<Eigen::Vector3d> AsVector(Vec3& v) noexcept { return Eigen::Map<Eigen::Vector3d>(v.data()); }
/// An Eigen vector as a plain one.
inline Vec3 ToVec3(const Eigen::Vector3d& v) noexcept { return {v.x(), v.y(), v.z()}; }

/// The pose (p, q_wxyz), its quaternion normalized. False (X untouched) when p or q is not
/// finite or q is not near unit length (|q| <= 0.5): a pose nobody can trust.
inline bool ToPose(const Vec3& p, const QuatWxyz& q_wxyz, Eigen::Isometry3d& X) noexcept {
  const Eigen::Quaterniond q(q_wxyz[0], q_wxyz[1], q_wxyz[2], q_wxyz[3]);
  if (!q.coeffs().allFinite() || !(q.norm() > 0.5) || !AsVector(p).allFinite()) return false;
  X.setIdentity();
  X.linear() = q.normalized().toRotationMatrix();
  X.translation() = AsVector(p);
  return true;
}
/// The same as a value; identity for a pose nobody can trust.
inline Eigen::Isometry3d ToPose(const Vec3& p, const QuatWxyz& q_wxyz) noexcept {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  ToPose(p, q_wxyz, X);
  return X;
}
/// A pose as (p, q_wxyz), the quaternion with w >= 0 as Eigen gives it.
inline void FromPose(const Eigen::Isometry3d& X, Vec3& p, QuatWxyz& q_wxyz) noexcept {
  const Eigen::Quaterniond q(X.linear());
  p = ToVec3(X.translation());
  q_wxyz = {q.w(), q.x(), q.y(), q.z()};
}

/// A contact given in the world frame W (a test's, a tool's) in the frame O of an object at
/// pose X_WO: the contact point p_WC, the fingertip centre p_WE, the imposed displacement u_W and
/// the normal n_W in W, f_E_W_N the force the fingertip feels in W. Depth: -u . n (|u| without
/// a normal), as a frictionless deformable's contact has it.
inline FingerContact ContactInObjectFrame(const Eigen::Isometry3d& X_WO, std::int32_t finger, ObjectId object,
                                          const Eigen::Vector3d& p_WC_m, const Eigen::Vector3d& p_WE_m,
                                          const Eigen::Vector3d& u_W_m,
                                          const Eigen::Vector3d& f_E_W_N = Eigen::Vector3d::Zero(),
                                          const Eigen::Vector3d& n_W = Eigen::Vector3d::Zero()) noexcept {
  const Eigen::Isometry3d X_OW = X_WO.inverse();
  FingerContact c;
  c.finger = finger;
  c.object = object;
  c.p_OC_m = ToVec3(X_OW * p_WC_m);
  c.p_OE_m = ToVec3(X_OW * p_WE_m);
  c.u_O_m = ToVec3(X_OW.linear() * u_W_m);
  c.f_O_N = ToVec3(X_OW.linear() * -f_E_W_N);
  c.n_O = ToVec3(X_OW.linear() * n_W);
  const Eigen::Vector3d n_O = AsVector(c.n_O);
  c.depth_m = n_O.squaredNorm() > 0.0 ? -AsVector(c.u_O_m).dot(n_O) : AsVector(c.u_O_m).norm();
  return c;
}

}  // namespace handshare::contact
