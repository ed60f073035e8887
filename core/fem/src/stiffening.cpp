#include "handshare/fem/stiffening.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "handshare/fem/error.hpp"

namespace handshare::fem {
namespace {

constexpr const char* kColumns[] = {"x_m",         "y_m",          "z_m",       "nx",         "ny",
                                    "nz",          "ax",           "ay",        "az",         "g_normal_4mm",
                                    "g_normal_10mm", "g_t1_4mm",   "g_t1_10mm", "g_t2_4mm",   "g_t2_10mm"};
constexpr std::size_t kNumColumns = sizeof kColumns / sizeof kColumns[0];

// Gain at depth d [m] from its values at kStiffeningDepths_m: 1 at 0, linear between, the
// deepest value beyond.
double GainAt(const float (&g)[2], double d) noexcept {
  const double d0 = kStiffeningDepths_m[0], d1 = kStiffeningDepths_m[1];
  if (d <= 0.0) return 1.0;
  if (d <= d0) return 1.0 + (g[0] - 1.0) * d / d0;
  if (d <= d1) return g[0] + (g[1] - g[0]) * (d - d0) / (d1 - d0);
  return g[1];
}

}  // namespace

Eigen::Vector3d StiffeningTangent(const Eigen::Vector3d& axis, const Eigen::Vector3d& n) {
  Eigen::Vector3d a = axis;
  for (int tries = 0; tries < 3; ++tries) {
    const Eigen::Vector3d t = a - a.dot(n) * n;
    if (t.norm() > 0.3 * a.norm()) return t.normalized();
    a = tries == 0 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  }
  return (Eigen::Vector3d::UnitX() - n.x() * n).normalized();
}

std::vector<StiffeningSample> ReadStiffeningSamples(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), 0, "file", std::string("cannot open: ") + std::strerror(errno));
  std::vector<StiffeningSample> out;
  std::string line;
  std::size_t n = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string item;
    while (std::getline(ss, item, ',')) f.push_back(item);
    if (!header) {
      for (std::size_t k = 0; k < kNumColumns; ++k) {
        if (f.size() != kNumColumns || f[k] != kColumns[k]) {
          throw InputError(file.string(), n, "header",
                           "expected the columns x_m,y_m,z_m,nx,ny,nz,ax,ay,az,g_normal_4mm,g_normal_10mm,"
                           "g_t1_4mm,g_t1_10mm,g_t2_4mm,g_t2_10mm");
        }
      }
      header = true;
      continue;
    }
    if (f.size() != kNumColumns) {
      throw InputError(file.string(), n, "", std::to_string(f.size()) + " fields, expected " + std::to_string(kNumColumns));
    }
    double v[kNumColumns];
    for (std::size_t k = 0; k < kNumColumns; ++k) {
      std::size_t used = 0;
      try {
        v[k] = std::stod(f[k], &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != f[k].size() || !std::isfinite(v[k])) throw InputError(file.string(), n, kColumns[k], "not a finite number: '" + f[k] + "'");
      if (k >= 9 && !(v[k] >= 0.2 && v[k] <= 5.0)) {
        throw InputError(file.string(), n, kColumns[k], "a gain outside [0.2, 5]: " + f[k]);
      }
    }
    StiffeningSample s;
    s.p_m = {v[0], v[1], v[2]};
    s.n_out = {v[3], v[4], v[5]};
    s.axis = {v[6], v[7], v[8]};
    if (std::abs(s.n_out.norm() - 1.0) > 1e-3) throw InputError(file.string(), n, "nx", "the normal is not a unit vector");
    if (!(s.axis.norm() > 0.5)) throw InputError(file.string(), n, "ax", "the axis is not a unit vector");
    s.g_normal = {v[9], v[10]};
    s.g_t1 = {v[11], v[12]};
    s.g_t2 = {v[13], v[14]};
    out.push_back(s);
  }
  if (!header) throw InputError(file.string(), n, "header", "no header line");
  if (out.empty()) throw InputError(file.string(), n, "", "no samples");
  return out;
}

void WriteStiffeningSamples(const std::filesystem::path& file, std::span<const StiffeningSample> samples,
                            const std::string& comment) {
  std::ofstream out(file);
  if (!out) throw InputError(file.string(), 0, "file", std::string("cannot write: ") + std::strerror(errno));
  std::stringstream c(comment);
  std::string line;
  while (std::getline(c, line)) out << "# " << line << "\n";
  for (std::size_t k = 0; k < kNumColumns; ++k) out << (k ? "," : "") << kColumns[k];
  out << "\n";
  char b[512];
  for (const auto& s : samples) {
    std::snprintf(b, sizeof b, "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f,%.5f,%.5f,%.5f\n", s.p_m.x(),
                  s.p_m.y(), s.p_m.z(), s.n_out.x(), s.n_out.y(), s.n_out.z(), s.axis.x(), s.axis.y(), s.axis.z(),
                  s.g_normal[0], s.g_normal[1], s.g_t1[0], s.g_t1[1], s.g_t2[0], s.g_t2[1]);
    out << b;
  }
  if (!out) throw InputError(file.string(), 0, "file", "write failed");
}

StiffeningTable::StiffeningTable(const TetMesh& mesh, const Surface& surface, std::span<const StiffeningSample> samples)
    : gains_(static_cast<std::size_t>(mesh.num_nodes()), Gains{{1, 1}, {1, 1}, {1, 1}, false}),
      num_samples_(samples.size()) {
  if (!samples.empty()) axis_ = samples.front().axis.normalized();
  // The samples' spacing: the median distance from a sample to its nearest other one. A node
  // farther than 1.5 spacings from every sample facing its way is not covered (gain 1): a
  // table may sample only where a part is pressed.
  std::vector<double> spacing;
  for (std::size_t s = 0; s < samples.size(); ++s) {
    double best = 1e300;
    for (std::size_t t = 0; t < samples.size(); ++t) {
      if (t != s) best = std::min(best, (samples[s].p_m - samples[t].p_m).squaredNorm());
    }
    if (best < 1e300) spacing.push_back(std::sqrt(best));
  }
  double reach2 = 1e300;
  if (!spacing.empty()) {
    std::nth_element(spacing.begin(), spacing.begin() + static_cast<std::ptrdiff_t>(spacing.size() / 2), spacing.end());
    reach2 = std::pow(1.5 * spacing[spacing.size() / 2], 2);
  }
  constexpr std::size_t kNearest = 4;
  const double cos_max = std::cos(60.0 * M_PI / 180.0);
  std::vector<std::pair<double, std::size_t>> near;
  for (std::size_t i = 0; i < surface.nodes.size(); ++i) {
    const auto node = static_cast<std::size_t>(surface.nodes[i]);
    const Eigen::Vector3d& p = mesh.positions_m()[node];
    near.clear();
    for (std::size_t s = 0; s < samples.size(); ++s) {
      if (samples[s].n_out.dot(surface.normals[i]) < cos_max) continue;
      near.emplace_back((samples[s].p_m - p).squaredNorm(), s);
    }
    if (near.empty()) continue;
    const std::size_t k = std::min(kNearest, near.size());
    std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(k), near.end());
    if (near[0].first > reach2) continue;
    double w_sum = 0.0, gn[2] = {0, 0}, g1[2] = {0, 0}, g2[2] = {0, 0};
    for (std::size_t j = 0; j < k; ++j) {
      const StiffeningSample& s = samples[near[j].second];
      if (near[j].first < 1e-18) {  // the sample itself
        w_sum = 1.0;
        for (int d = 0; d < 2; ++d) gn[d] = s.g_normal[d], g1[d] = s.g_t1[d], g2[d] = s.g_t2[d];
        break;
      }
      const double w = 1.0 / near[j].first;
      w_sum += w;
      for (int d = 0; d < 2; ++d) {
        gn[d] += w * s.g_normal[d];
        g1[d] += w * s.g_t1[d];
        g2[d] += w * s.g_t2[d];
      }
    }
    Gains& g = gains_[node];
    for (int d = 0; d < 2; ++d) {
      const double inv = near[0].first < 1e-18 ? 1.0 : 1.0 / w_sum;
      g.g_normal[d] = static_cast<float>(gn[d] * inv);
      g.g_t1[d] = static_cast<float>(g1[d] * inv);
      g.g_t2[d] = static_cast<float>(g2[d] * inv);
    }
    g.covered = true;
    ++covered_;
  }
}

double StiffeningTable::NodeGain(std::int32_t node, const Eigen::Vector3d& u_m, const Eigen::Vector3d& n_out) const noexcept {
  return NodeGain(node, u_m, n_out, StiffeningTangent(axis_, n_out));
}

double StiffeningTable::NodeGain(std::int32_t node, const Eigen::Vector3d& u_m, const Eigen::Vector3d& n_out,
                                 const Eigen::Vector3d& t1) const noexcept {
  if (node < 0 || static_cast<std::size_t>(node) >= gains_.size()) return 1.0;
  const Gains& g = gains_[static_cast<std::size_t>(node)];
  if (!g.covered) return 1.0;
  const double depth = -u_m.dot(n_out);
  if (!(depth > 0.0)) return 1.0;
  const double normal = GainAt(g.g_normal, depth);
  const Eigen::Vector3d ut = u_m + depth * n_out;
  const double lean = std::min(1.0, ut.norm() / (depth * std::tan(kStiffeningObliqueRad)));
  if (!(lean > 0.0)) return normal;
  const double c = ut.dot(t1) / ut.norm();
  const double oblique = c * c * GainAt(g.g_t1, depth) + (1.0 - c * c) * GainAt(g.g_t2, depth);
  return (1.0 - lean) * normal + lean * oblique;
}

double StiffeningTable::PatchGain(std::span<const ContactInput> inputs, std::span<const Eigen::Vector3d> forces,
                                  const Eigen::Vector3d& n_out, const Eigen::Vector3d& stick_m) const noexcept {
  const Eigen::Vector3d t1 = StiffeningTangent(axis_, n_out);  // one tangent for the patch
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < inputs.size() && i < forces.size(); ++i) {
    const double push = -forces[i].dot(n_out);
    if (!(push > 0.0)) continue;
    num += push * NodeGain(inputs[i].node, inputs[i].u_m + stick_m, n_out, t1);
    den += push;
  }
  return den > 0.0 ? num / den : 1.0;
}

}  // namespace handshare::fem
