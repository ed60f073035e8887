#pragma once
/// Workspace volume of a HIRO II finger: the volume of the set of fingertip positions E it
/// reaches over its joint ranges (the chapter's Table 1 gives 535 cm^3 for a finger and
/// 713 cm^3 for the thumb; docs/hiro.md compares). Offline; not for the haptic thread.
#include "handshare/hiro/hiro_model.hpp"

namespace handshare::hiro {

/// The other posture of joints 2 and 3 that puts the fingertip at the same place: the two
/// flexion joints form a planar two-link chain, mirrored about the line from joint 2 to the
/// fingertip: q3' = -q3, q2' = q2 + 2 atan2(l3 sin q3, l2 + l3 cos q3) (l2, l3 = link_m[1],
/// link_m[2]); q1 unchanged. [rad]
FingerVector MirrorFingerPosture(const FingerSpec& finger, const FingerVector& q_rad) noexcept;

/// Volume [m^3] of the fingertip's reachable set: the integral over the joint ranges of
/// |det J_HE(q)| (FingerFk's fingertip Jacobian), each posture weighted by 1 / (the number of
/// in-range postures reaching the same fingertip: 2 where MirrorFingerPosture is in range,
/// else 1). The weight makes the fold at a straight finger (q3 = 0, det J = 0, where a posture
/// and its mirror meet) count once. The count is exact when joint 1 spans less than 180 deg
/// (else the finger turned by 180 deg with joints 2-3 reflected reaches the same points),
/// joint 2 less than 360 deg and joint 3 lies within [-180, 180] deg; otherwise NaN.
/// Midpoint rule: n_q1 nodes over joint 1 (|det J| does not depend on q1, so a few do), n_q23
/// over joints 2 and 3 each.
double FingerWorkspaceVolume(const FingerSpec& finger, int n_q1, int n_q23) noexcept;

}  // namespace handshare::hiro
