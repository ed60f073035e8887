#include "handshare/hiro/hiro_model.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace handshare::hiro {

namespace {

using nlohmann::json;
constexpr double kDeg = M_PI / 180.0;

// Reads fields by JSON pointer and names file and field in every error.
class Reader {
 public:
  Reader(const json& root, std::string origin) : root_(root), origin_(std::move(origin)) {}

  [[noreturn]] void Fail(const std::string& field, const std::string& what) const {
    throw ConfigError(origin_ + ": " + field + ": " + what);
  }
  const json& At(const std::string& field) const {
    const json::json_pointer ptr(field);
    if (!root_.contains(ptr)) Fail(field, "missing");
    return root_.at(ptr);
  }
  double Number(const std::string& field, double min, double max) const {
    const json& v = At(field);
    if (!v.is_number()) Fail(field, "expected a number, got " + v.dump());
    const double x = v.get<double>();
    if (!std::isfinite(x) || x < min || x > max) {
      std::ostringstream s;
      s << x << " is outside [" << min << ", " << max << "]";
      Fail(field, s.str());
    }
    return x;
  }
  template <int N>
  Eigen::Matrix<double, N, 1> Vector(const std::string& field, double min, double max) const {
    const json& v = At(field);
    if (!v.is_array() || v.size() != static_cast<std::size_t>(N)) {
      Fail(field, "expected an array of " + std::to_string(N) + " numbers, got " + v.dump());
    }
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i) out[i] = Number(field + "/" + std::to_string(i), min, max);
    return out;
  }
  // A [min, max] range in degrees, returned in radians.
  std::pair<double, double> RangeDeg(const std::string& field) const {
    const auto r = Vector<2>(field, -360.0, 360.0);
    if (!(r[0] < r[1])) Fail(field, "range minimum must be below its maximum");
    return {r[0] * kDeg, r[1] * kDeg};
  }
  std::size_t Size(const std::string& field) const {
    const json& v = At(field);
    if (!v.is_array()) Fail(field, "expected an array");
    return v.size();
  }

 private:
  const json& root_;
  std::string origin_;
};

Eigen::Matrix3d Rz(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

// Rotation about a unit axis by angle (Rodrigues), without Eigen's AngleAxis normalisation.
Eigen::Matrix3d AxisRotation(const Eigen::Vector3d& a, double angle) noexcept {
  const double c = std::cos(angle), s = std::sin(angle), t = 1.0 - c;
  Eigen::Matrix3d R;
  R << t * a.x() * a.x() + c, t * a.x() * a.y() - s * a.z(), t * a.x() * a.z() + s * a.y(),
      t * a.x() * a.y() + s * a.z(), t * a.y() * a.y() + c, t * a.y() * a.z() - s * a.x(),
      t * a.x() * a.z() - s * a.y(), t * a.y() * a.z() + s * a.x(), t * a.z() * a.z() + c;
  return R;
}

Eigen::Matrix3d Rx(double a) noexcept {
  const double c = std::cos(a), s = std::sin(a);
  Eigen::Matrix3d R;
  R << 1, 0, 0, 0, c, -s, 0, s, c;
  return R;
}

Eigen::Matrix3d RzFast(double a) noexcept {
  const double c = std::cos(a), s = std::sin(a);
  Eigen::Matrix3d R;
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  return R;
}

const Eigen::Vector3d kGravity_B(0.0, 0.0, -kGravity_m_per_s2);

}  // namespace

HiroModel HiroModel::Load(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ConfigError(file.string() + ": cannot open HIRO config file");
  std::stringstream text;
  text << in.rdbuf();
  return Parse(text.str(), file.string());
}

HiroModel HiroModel::Parse(const std::string& json_text, const std::string& origin) {
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number too large
    throw ConfigError(origin + ": not valid JSON: " + e.what());
  }
  const Reader r(root, origin);
  if (!root.is_object()) r.Fail("/", "expected a JSON object");
  if (r.At("/format") != "handshare-hiro-v1") r.Fail("/format", "expected \"handshare-hiro-v1\"");

  HiroModel m;
  m.control_rate_Hz = r.Number("/sourced/control_rate_Hz", 100.0, 100000.0);
  m.max_fingertip_force_N = r.Number("/sourced/hand/max_fingertip_force_N", 0.1, 100.0);
  m.force_sensor_noise_N = r.Number("/assumed/hand/force_sensor_noise_N", 0.0, 10.0);

  // Arm: sourced lengths and ranges, assumed axes, masses and drives.
  ArmSpec& a = m.arm;
  a.upper_arm_m = r.Number("/sourced/arm/upper_arm_m", 0.05, 2.0);
  a.forearm_m = r.Number("/sourced/arm/forearm_m", 0.05, 2.0);
  a.wrist_to_hand_m = r.Number("/assumed/arm/wrist_to_hand_m", 0.0, 1.0);
  a.max_hand_force_N = r.Number("/sourced/arm/max_hand_force_N", 0.1, 1000.0);
  a.max_hand_moment_N_m = r.Number("/sourced/arm/max_hand_moment_N_m", 0.01, 100.0);
  a.max_hand_speed_m_per_s = r.Number("/sourced/arm/max_hand_speed_m_per_s", 0.001, 10.0);
  a.max_hand_rate_rad_per_s = r.Number("/sourced/arm/max_hand_rate_rad_per_s", 0.001, 100.0);
  if (r.Size("/sourced/arm/joint_range_deg") != kArmJoints) {
    r.Fail("/sourced/arm/joint_range_deg", "expected 6 ranges");
  }
  // Zero pose (assumed): upper arm hangs from the shoulder S at the origin of B, forearm
  // forward; joints 1-2 at S, 3 at the elbow, 4 along the forearm, 5-6 at the wrist.
  const Eigen::Vector3d p_elbow(0, 0, -a.upper_arm_m);
  const Eigen::Vector3d p_wrist(0, a.forearm_m, -a.upper_arm_m);
  const std::array<Eigen::Vector3d, kArmJoints> points = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                          p_elbow, p_elbow, p_wrist, p_wrist};
  a.p_BH0 = p_wrist + Eigen::Vector3d(0, a.wrist_to_hand_m, 0);
  const double arm_counts = r.Number("/assumed/arm/encoder_counts_per_rev", 16.0, 1e9);
  for (int i = 0; i < kArmJoints; ++i) {
    const std::string n = std::to_string(i);
    const Eigen::Vector3d axis = r.Vector<3>("/assumed/arm/joint_axis_B/" + n, -1.0, 1.0);
    if (std::abs(axis.norm() - 1.0) > 1e-9) r.Fail("/assumed/arm/joint_axis_B/" + n, "not a unit vector");
    a.axis_B[i] = axis;
    a.point_B[i] = points[i];
    JointSpec& j = a.joint[i];
    std::tie(j.min_rad, j.max_rad) = r.RangeDeg("/sourced/arm/joint_range_deg/" + n);
    j.max_torque_N_m = r.Number("/assumed/arm/max_joint_torque_N_m/" + n, 0.01, 1000.0);
    j.max_speed_rad_per_s = r.Number("/assumed/arm/max_joint_speed_rad_per_s/" + n, 0.01, 100.0);
    j.inertia_kg_m2 = r.Number("/assumed/arm/reflected_inertia_kg_m2/" + n, 1e-6, 100.0);
    j.viscous_N_m_s_per_rad = r.Number("/assumed/arm/viscous_friction_N_m_s_per_rad/" + n, 0.0, 1000.0);
    j.encoder_rad = 2.0 * M_PI / arm_counts;
    a.q_home_rad[i] = r.Number("/assumed/arm/home_deg/" + n, -360.0, 360.0) * kDeg;
    if (a.q_home_rad[i] < j.min_rad || a.q_home_rad[i] > j.max_rad) {
      r.Fail("/assumed/arm/home_deg/" + n, "outside the joint range");
    }
  }
  a.upper_arm_mass_kg = r.Number("/assumed/arm/link_mass_kg/upper_arm", 0.0, 50.0);
  a.forearm_mass_kg = r.Number("/assumed/arm/link_mass_kg/forearm", 0.0, 50.0);
  a.wrist_mass_kg = r.Number("/assumed/arm/link_mass_kg/wrist", 0.0, 50.0);

  // Hand and fingers.
  const double hand_mass = r.Number("/sourced/hand/mass_kg", 0.0, 10.0);
  const double finger_mass = r.Number("/sourced/hand/finger_mass_kg", 0.0, 10.0);
  m.palm_mass_kg = r.Number("/assumed/hand/palm_mass_kg", 0.0, 10.0);
  m.palm_com_H = r.Vector<3>("/assumed/hand/palm_com_H_m", -1.0, 1.0);
  const auto link_m = r.Vector<3>("/assumed/hand/finger_link_m", 0.0, 0.5);
  const auto link_mass = r.Vector<3>("/assumed/hand/finger_link_mass_kg", 0.0, 1.0);
  if (std::abs(link_mass.sum() - finger_mass) > 1e-6) {
    r.Fail("/assumed/hand/finger_link_mass_kg", "must add up to /sourced/hand/finger_mass_kg");
  }
  if (std::abs(m.palm_mass_kg + kFingers * finger_mass - hand_mass) > 1e-6) {
    r.Fail("/assumed/hand/palm_mass_kg", "palm plus five fingers must add up to /sourced/hand/mass_kg");
  }
  const Eigen::Vector3d q_opt = r.Vector<3>("/assumed/hand/optimum_pose_deg", -180.0, 180.0) * kDeg;
  const double hand_counts = r.Number("/assumed/hand/encoder_counts_per_rev", 16.0, 1e9);
  if (r.Size("/assumed/hand/finger_bases") != kFingers) r.Fail("/assumed/hand/finger_bases", "expected 5 fingers");
  for (int f = 0; f < kFingers; ++f) {
    FingerSpec& fs = m.finger[f];
    const std::string base = "/assumed/hand/finger_bases/" + std::to_string(f);
    fs.p_HF = r.Vector<3>(base + "/p_HF_m", -0.5, 0.5);
    fs.R_HF = Rz(r.Number(base + "/yaw_deg", -180.0, 180.0) * kDeg);
    const char* ranges = f == 0 ? "/sourced/hand/thumb_joint_range_deg/" : "/sourced/hand/finger_joint_range_deg/";
    for (int j = 0; j < kFingerJoints; ++j) {
      const std::string n = std::to_string(j);
      JointSpec& js = fs.joint[j];
      std::tie(js.min_rad, js.max_rad) = r.RangeDeg(ranges + n);
      js.max_torque_N_m = r.Number("/sourced/hand/max_joint_torque_N_m/" + n, 0.001, 100.0);
      js.max_speed_rad_per_s = r.Number("/sourced/hand/max_joint_speed_rad_per_s/" + n, 0.01, 100.0);
      js.inertia_kg_m2 = r.Number("/assumed/hand/reflected_inertia_kg_m2/" + n, 1e-9, 1.0);
      js.viscous_N_m_s_per_rad = r.Number("/assumed/hand/viscous_friction_N_m_s_per_rad/" + n, 0.0, 10.0);
      js.encoder_rad = 2.0 * M_PI / hand_counts;
      fs.link_m[j] = link_m[j];
      fs.link_mass_kg[j] = link_mass[j];
      if (q_opt[j] < js.min_rad || q_opt[j] > js.max_rad) {
        r.Fail("/assumed/hand/optimum_pose_deg/" + n, "outside the joint range of finger " + std::to_string(f));
      }
    }
    fs.q_optimum_rad = q_opt;
  }

  // Arm following (assumed).
  ArmFollowSpec& fo = m.follow;
  const std::string af = "/assumed/arm_following/";
  double weight_sum = 0.0;
  for (int f = 0; f < kFingers; ++f) {
    fo.finger_weight[f] = r.Number(af + "finger_weight/" + std::to_string(f), 0.0, 100.0);
    weight_sum += fo.finger_weight[f];
  }
  if (!(weight_sum > 0.0)) r.Fail(af + "finger_weight", "at least one weight must be positive");
  fo.user_finger_stiffness_N_per_m = r.Number(af + "user_finger_stiffness_N_per_m", 1.0, 1e6);
  fo.max_user_offset_m = r.Number(af + "max_user_offset_m", 0.0, 0.2);
  fo.rate_per_s = r.Number(af + "rate_per_s", 0.01, 100.0);
  fo.max_accel_m_per_s2 = r.Number(af + "max_accel_m_per_s2", 0.01, 100.0);
  fo.max_angular_accel_rad_per_s2 = r.Number(af + "max_angular_accel_rad_per_s2", 0.01, 1000.0);
  fo.dls_damping_m = r.Number(af + "dls_damping_m", 0.0, 1.0);
  fo.dls_length_m = r.Number(af + "dls_length_m", 0.001, 10.0);
  fo.limit_margin_rad = r.Number(af + "limit_margin_deg", 0.0, 45.0) * kDeg;
  fo.limit_rate_per_s = r.Number(af + "limit_rate_per_s", 0.1, 0.5 * m.control_rate_Hz);
  fo.servo_bandwidth_Hz = r.Number(af + "servo_bandwidth_Hz", 0.1, 0.1 * m.control_rate_Hz);
  fo.servo_damping_ratio = r.Number(af + "servo_damping_ratio", 0.1, 10.0);
  for (int i = 0; i < kArmJoints; ++i) {
    if (a.joint[i].max_rad - a.joint[i].min_rad <= 2.0 * fo.limit_margin_rad) {
      r.Fail(af + "limit_margin_deg", "leaves no room in /sourced/arm/joint_range_deg/" + std::to_string(i));
    }
  }
  return m;
}

ArmKinematics ArmFk(const ArmSpec& arm, const ArmVector& q_rad) noexcept {
  // Product of exponentials in the space frame (Murray, Li and Sastry 1994, ch. 3):
  //   X_BH(q) = e^{xi_1 q_1} ... e^{xi_6 q_6} X_BH(0),
  // each revolute joint a rotation R about axis a through point r: [R, (I - R) r].
  ArmKinematics k;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < kArmJoints; ++i) {
    // Joint i's axis and point as moved by joints 0..i-1.
    k.axis_B[i] = R * arm.axis_B[i];
    k.point_B[i] = R * arm.point_B[i] + p;
    const Eigen::Matrix3d Ri = AxisRotation(arm.axis_B[i], q_rad[i]);
    p += R * (arm.point_B[i] - Ri * arm.point_B[i]);
    R = R * Ri;
  }
  k.X_BH.linear() = R;
  k.X_BH.translation() = R * arm.p_BH0 + p;
  k.p_B_elbow = k.point_B[2];
  k.p_B_wrist = k.point_B[4];
  return k;
}

ArmJacobian ArmHandJacobian(const ArmKinematics& k) noexcept {
  ArmJacobian J;
  const Eigen::Vector3d p = k.X_BH.translation();
  for (int i = 0; i < kArmJoints; ++i) {
    J.block<3, 1>(0, i) = k.axis_B[i];
    J.block<3, 1>(3, i) = k.axis_B[i].cross(p - k.point_B[i]);
  }
  return J;
}

ArmPointJacobian ArmPointJacobianAt(const ArmKinematics& k, const Eigen::Vector3d& p_B, int joints) noexcept {
  ArmPointJacobian J = ArmPointJacobian::Zero();
  for (int i = 0; i < joints && i < kArmJoints; ++i) J.col(i) = k.axis_B[i].cross(p_B - k.point_B[i]);
  return J;
}

HandWrench ArmHandWrench(const ArmJacobian& J_H, const ArmVector& tau_N_m) noexcept {
  // Fixed-size SVD: no allocation. Singular values below 1e-9 of the largest count as zero.
  Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>> svd(J_H.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  svd.setThreshold(1e-9);
  return svd.solve(tau_N_m);
}

double LimitHandWrench(const ArmJacobian& J_H, double max_force_N, double max_moment_N_m,
                       ArmVector& tau_N_m) noexcept {
  const HandWrench w = ArmHandWrench(J_H, tau_N_m);
  if (!w.allFinite() || !tau_N_m.allFinite()) {  // nothing to scale: no task torque at all
    tau_N_m.setZero();
    return 0.0;
  }
  const double f = w.tail<3>().norm(), m = w.head<3>().norm();
  double s = 1.0;
  if (f > max_force_N) s = std::min(s, max_force_N / f);
  if (m > max_moment_N_m) s = std::min(s, max_moment_N_m / m);
  tau_N_m *= s;
  return s;
}

FingerKinematics FingerFk(const FingerSpec& f, const FingerVector& q_rad) noexcept {
  // In the finger frame F: joint 1 about z, joints 2 and 3 about x (after joint 1), links
  // along y at zero angles. Positive flexion lifts the fingertip toward +z.
  const Eigen::Matrix3d R1 = RzFast(q_rad[0]);
  const Eigen::Matrix3d R2 = R1 * Rx(q_rad[1]);
  const Eigen::Matrix3d R3 = R2 * Rx(q_rad[2]);
  const Eigen::Vector3d j2 = R1.col(1) * f.link_m[0];
  const Eigen::Vector3d j3 = j2 + R2.col(1) * f.link_m[1];
  const Eigen::Vector3d tip = j3 + R3.col(1) * f.link_m[2];
  const Eigen::Vector3d a1 = Eigen::Vector3d::UnitZ(), a23 = R1.col(0);

  FingerKinematics k;
  const Eigen::Matrix3d& R_HF = f.R_HF;
  k.p_HE = f.p_HF + R_HF * tip;
  k.R_HS = R_HF * R3;
  k.axis_H = {R_HF * a1, R_HF * a23, R_HF * a23};
  k.point_H = {f.p_HF, f.p_HF + R_HF * j2, f.p_HF + R_HF * j3};
  // Link masses: link 1 (the joint 1-2 block) at joint 2, links 2 and 3 at their midpoints.
  k.com_H = {k.point_H[1], f.p_HF + R_HF * (0.5 * (j2 + j3)), f.p_HF + R_HF * (0.5 * (j3 + tip))};
  for (int j = 0; j < kFingerJoints; ++j) k.J_HE.col(j) = k.axis_H[j].cross(k.p_HE - k.point_H[j]);
  return k;
}

ArmVector ArmGravityTorque(const HiroModel& m, const ArmKinematics& arm,
                           const std::array<FingerKinematics, kFingers>& fingers) noexcept {
  // tau = -sum_i J_i^T m_i g: the torque the motors must add to hold still (J_i of the mass
  // centre, only the joints that move it).
  ArmVector tau = ArmVector::Zero();
  auto add = [&](const Eigen::Vector3d& p_B, double mass, int joints) {
    tau.noalias() -= ArmPointJacobianAt(arm, p_B, joints).transpose() * (mass * kGravity_B);
  };
  const Eigen::Vector3d p_B_shoulder = Eigen::Vector3d::Zero();
  add(0.5 * (p_B_shoulder + arm.p_B_elbow), m.arm.upper_arm_mass_kg, 2);
  add(0.5 * (arm.p_B_elbow + arm.p_B_wrist), m.arm.forearm_mass_kg, 3);
  add(arm.p_B_wrist, m.arm.wrist_mass_kg, 4);
  const Eigen::Isometry3d& X_BH = arm.X_BH;
  add(X_BH * m.palm_com_H, m.palm_mass_kg, kArmJoints);
  for (int f = 0; f < kFingers; ++f) {
    for (int j = 0; j < kFingerJoints; ++j) add(X_BH * fingers[f].com_H[j], m.finger[f].link_mass_kg[j], kArmJoints);
  }
  return tau;
}

FingerVector FingerGravityTorque(const FingerSpec& finger, const FingerKinematics& k,
                                 const Eigen::Matrix3d& R_BH) noexcept {
  const Eigen::Vector3d g_H = R_BH.transpose() * kGravity_B;
  FingerVector tau = FingerVector::Zero();
  for (int link = 0; link < kFingerJoints; ++link) {
    // Link `link` is moved by joints 0..link.
    for (int j = 0; j <= link; ++j) {
      tau[j] -= k.axis_H[j].cross(k.com_H[link] - k.point_H[j]).dot(finger.link_mass_kg[link] * g_H);
    }
  }
  return tau;
}

double GravityPotential(const HiroModel& m, const ArmKinematics& arm,
                        const std::array<FingerKinematics, kFingers>& fingers) noexcept {
  // V = sum m g z over every mass centre.
  double V = 0.0;
  auto add = [&](const Eigen::Vector3d& p_B, double mass) { V += mass * kGravity_m_per_s2 * p_B.z(); };
  add(0.5 * arm.p_B_elbow, m.arm.upper_arm_mass_kg);
  add(0.5 * (arm.p_B_elbow + arm.p_B_wrist), m.arm.forearm_mass_kg);
  add(arm.p_B_wrist, m.arm.wrist_mass_kg);
  add(arm.X_BH * m.palm_com_H, m.palm_mass_kg);
  for (int f = 0; f < kFingers; ++f) {
    for (int j = 0; j < kFingerJoints; ++j) add(arm.X_BH * fingers[f].com_H[j], m.finger[f].link_mass_kg[j]);
  }
  return V;
}

}  // namespace handshare::hiro
