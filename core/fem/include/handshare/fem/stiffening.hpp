#pragma once
/// A large-deformation correction of the press force, from precomputed nonlinear responses
/// (docs/fem.md, "A correction beyond the paper").
///
/// The compliance model is linear; under a deep press the real (neo-Hookean) part pushes back
/// harder or softer, by how much depending on where it is pressed and which way. Offline,
/// CalculiX presses single surface nodes of the mesh (a farthest-point sample of them) with a
/// neo-Hookean solid of the same small-strain moduli, along the normal and 30 degrees oblique
/// along two tangents, at 4 and 10 mm, and records each press's gain: the nonlinear reaction over
/// the linear one (projected on it). Those samples are the table's file. At run time a node
/// held at displacement u under a patch of normal n has the gain its neighbouring samples give
/// (inverse-distance weights, samples facing the same way), at its depth -u.n, blended between
/// the normal and the oblique gains by how far its stick leans (|u_t| / (u_n tan 30 deg)); a
/// fingertip patch's force is scaled by its nodes' gains weighted by their push. Scaling the
/// patch's sum, never a node's own force, keeps the large self-cancelling pairs of neighbouring
/// nodes under one fingertip cancelling (scaling each node's force apart made a five-finger
/// press on the leg 13-40 % off where the linear model is 1-3 %).
#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/mesh.hpp"

namespace handshare::fem {

/// Depths at which the samples' gains are measured [m]; the gain is 1 at depth 0, linear
/// between, and the deepest value beyond.
inline constexpr std::array<double, 2> kStiffeningDepths_m = {0.004, 0.010};
/// The oblique presses' angle from the normal.
inline constexpr double kStiffeningObliqueRad = 0.5235987755982988;  // 30 degrees

/// One sampled node: where, which way, and its gains.
struct StiffeningSample {
  Eigen::Vector3d p_m = Eigen::Vector3d::Zero();    ///< rest position (the mesh's frame).
  Eigen::Vector3d n_out = Eigen::Vector3d::Zero();  ///< unit outward normal there.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  ///< t1 = axis projected on the tangent plane.
  std::array<double, 2> g_normal{1.0, 1.0};         ///< pressed along -n_out, per depth.
  std::array<double, 2> g_t1{1.0, 1.0};             ///< 30 deg oblique toward t1.
  std::array<double, 2> g_t2{1.0, 1.0};             ///< 30 deg oblique toward t2 = n_out x t1.
};

/// t1 of a tangent plane with normal n from an axis (the other two unit axes when the axis is
/// nearly along n).
Eigen::Vector3d StiffeningTangent(const Eigen::Vector3d& axis, const Eigen::Vector3d& n);

/// Reads a sample file (CSV, '#' comment lines; columns x_m,y_m,z_m,nx,ny,nz,ax,ay,az,
/// g_normal_4mm,g_normal_10mm,g_t1_4mm,g_t1_10mm,g_t2_4mm,g_t2_10mm).
/// @throws InputError naming the file, line and field for anything else (a gain must be finite
///         and in [0.2, 5]).
std::vector<StiffeningSample> ReadStiffeningSamples(const std::filesystem::path& file);
/// Writes them (with `comment` as leading '#' lines).
void WriteStiffeningSamples(const std::filesystem::path& file, std::span<const StiffeningSample> samples,
                            const std::string& comment);

/// The samples interpolated onto every surface node of one mesh.
class StiffeningTable {
 public:
  /// Each surface node takes the inverse-square-distance mean of its (up to) 4 nearest samples
  /// whose normal is within 60 degrees of its own; a node with none within 1.5 sample spacings
  /// (the median distance between neighbouring samples) keeps gain 1.
  StiffeningTable(const TetMesh& mesh, const Surface& surface, std::span<const StiffeningSample> samples);

  /// The gain of mesh node `node` held at displacement u_m [m] under a patch of outward normal
  /// n_out; 1 for a node the table does not cover or that is not pressed in. No allocation.
  double NodeGain(std::int32_t node, const Eigen::Vector3d& u_m, const Eigen::Vector3d& n_out) const noexcept;

  /// The gain of one fingertip patch: `inputs` its nodes (ContactInput::u_m the normal part
  /// imposed), `forces` their forces on the object, n_out its normal and stick_m its stick (the
  /// patch's slide; zero without friction): the nodes' gains at u_m + stick_m weighted by their
  /// push -f.n_out. 1 if none pushes. No allocation.
  double PatchGain(std::span<const ContactInput> inputs, std::span<const Eigen::Vector3d> forces,
                   const Eigen::Vector3d& n_out, const Eigen::Vector3d& stick_m) const noexcept;

  /// Nodes with samples near them, and samples.
  std::size_t covered_nodes() const noexcept { return covered_; }
  std::size_t num_samples() const noexcept { return num_samples_; }

 private:
  // NodeGain with the tangent t1 of n_out already found (a patch finds it once for its nodes).
  double NodeGain(std::int32_t node, const Eigen::Vector3d& u_m, const Eigen::Vector3d& n_out,
                  const Eigen::Vector3d& t1) const noexcept;
  struct Gains {
    float g_normal[2];
    float g_t1[2];
    float g_t2[2];
    bool covered;
  };
  std::vector<Gains> gains_;  // per mesh node
  Eigen::Vector3d axis_ = Eigen::Vector3d::UnitX();
  std::size_t covered_ = 0;
  std::size_t num_samples_ = 0;
};

}  // namespace handshare::fem
