#pragma once
/// What a hand feels, drawn for a person without a force display (a desk, docs/devices.md):
/// each fingertip coloured by the force on it (white at 0 N, yellow at half the device's
/// limit, red at the limit and above) with an arrow along the force, 1 cm per newton, and a
/// line of text with each fingertip's force and the weight the hand holds. No DDS: plain
/// arrays in, scene parts out.
#include <array>
#include <string>

#include <Eigen/Core>

#include "handshare/common/hand.hpp"
#include "handshare/render/scene_view.hpp"

namespace handshare::graphics {

/// Arrow length per newton of fingertip force [m/N].
inline constexpr double kForceArrow_m_per_N = 0.01;

/// The colour of a fingertip feeling |f| = force_N, for a device limit of max_force_N.
[[nodiscard]] render::Rgb ForceColour(double force_N, double max_force_N);

/// Colours the fingertip markers and adds an arrow (a thin box and a ball at its head) from
/// each fingertip p_WE along the force on it f_E_W_N, longer than 0.2 mm only (0.02 N).
void AddForceFeedback(const std::array<Eigen::Vector3d, common::kFingers>& p_WE,
                      const std::array<Eigen::Vector3d, common::kFingers>& f_E_W_N, double fingertip_radius_m,
                      double max_force_N, render::SceneView& view);

/// Two lines: each fingertip's force (thumb first) and what the hand holds: "weight held X N"
/// when the fingertips' forces sum to a load downwards (minus their vertical sum), "pressing
/// down X N" when up, else "no load".
[[nodiscard]] std::string ForceReadout(const std::array<Eigen::Vector3d, common::kFingers>& f_E_W_N);

/// The weight the fingertips hold [N]: minus the vertical sum of the forces on them (a held
/// body pushes them down), 0 when they push down on something instead.
[[nodiscard]] double HeldWeight_N(const std::array<Eigen::Vector3d, common::kFingers>& f_E_W_N);

}  // namespace handshare::graphics
