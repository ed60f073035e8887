#pragma once
/// @file
/// The camera matrices the renderers load into OpenGL (see Camera for the convention), exposed
/// so that callers can pick or project points consistently with what is drawn.

#include <Eigen/Core>

#include "handshare/render/scene_view.hpp"

namespace handshare::render {

/// Which eye of a camera: the mono eye, or a stereo eye offset by -/+ separation / 2.
enum class Eye { kCenter, kLeft, kRight };

/// gluLookAt matrix (world W -> eye coordinates) for `eye`. Column-major like OpenGL.
[[nodiscard]] Eigen::Matrix4d ViewMatrix(const Camera& camera, Eye eye = Eye::kCenter);

/// gluPerspective matrix for kCenter, the off-axis glFrustum for kLeft / kRight, with the given
/// viewport aspect (width / height).
[[nodiscard]] Eigen::Matrix4d ProjectionMatrix(const Camera& camera, double aspect, Eye eye = Eye::kCenter);

/// Continuous image coordinates (col, row) of p_W in a width_px x height_px image of `eye`
/// (row 0 at the top), and its depth along the view direction [m] in z(). Depth <= 0 means
/// behind the eye (col, row are then meaningless).
[[nodiscard]] Eigen::Vector3d ProjectToImage(const Camera& camera, const Eigen::Vector3d& p_W,
                                             Eye eye = Eye::kCenter);

}  // namespace handshare::render
