// The proxy must follow its fingertip from where it rests at exactly R + skin against two
// triangles that share an edge (a convex ridge, a flat or concave valley) or three that share a
// vertex (a convex apex, a concave pit), with and without friction.
//
// These are the configurations in which the proxy froze on haptic_bench's bumpy sphere: the
// proxy slides on a face up to the edge or vertex it shares with a neighbour, the sweep stops it
// where the proxy touches that edge (a tangent touch, so found only to about sqrt(2 R 1e-18)
// ~ 1e-10 m), and from there the edge sits at R + skin to round-off while its normal differs
// from the face's by ~1e-8 rad: every later move that grazed it was cut to zero, in every round
// of every step. So each case either starts there (the proxy on a face, its closest point
// delta = 0 .. 1 nm from the edge or vertex; over the edge or vertex itself; in the corner of a
// valley or pit) or slides into it (from 0.1-2.9 mm away), in three poses of the mesh (so the
// coordinates round as a real mesh's do), and the fingertip, 1 mm below the proxy (pressing),
// slides 20 mm in 200 steps (0.1 m/s) in directions the surface allows.
//
// Checked at every step: the proxy is no farther from the fingertip than the fingertip is from
// the free space (the distance D to the nearest point R + skin off the surface: for a convex
// configuration at most its depth under any one face's offset plane; for a concave one the
// distance to the intersection of the faces' offset half-spaces), plus the skin; with friction,
// D sqrt(1 + mu_s^2) (the proxy may lag inside the static cone) times 1 + mu_s sin(theta), theta
// the largest angle between two faces (the cone is tested about the frictionless contact's
// normal, while the proxy holds where it stuck, on another face or round an edge). And it has
// moved as far as the fingertip less that bound at the end and the 1 mm it started below.
// A frozen proxy ends 15-20 mm away.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "handshare/contact/mesh_collider.hpp"
#include "handshare/contact/proxy.hpp"
#include "handshare/contact/tri_mesh.hpp"

namespace handshare::contact {
namespace {

constexpr double kR = 0.008;
constexpr double kSkin = 1e-6;
constexpr double kRs = kR + kSkin;
constexpr double kL = 0.05;       // triangles 5 cm across: no other feature nearby
constexpr double kDepth = 1e-3;   // fingertip 1 mm below the proxy
constexpr double kSlide = 0.02;   // 20 mm in 200 steps
constexpr int kSteps = 200;

// A local configuration: triangles, where the proxy rests (at R + skin, in the local frame), the
// surface normal there (into the free side), the directions the fingertip slides in, and the
// faces' offset planes n . p >= b (to bound the fingertip's distance from the free space).
struct Config {
  std::string kind;  // the configuration without its numbers
  std::string name;
  bool concave = false;
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<std::int32_t, 3>> tri;
  Eigen::Vector3d rest;
  Eigen::Vector3d normal;
  std::vector<Eigen::Vector3d> slides;  // unit, tangent: the fingertip slides 20 mm straight
  // Or the fingertip's path as waypoints (local frame) after it starts 1 mm below `rest`.
  std::vector<std::vector<Eigen::Vector3d>> paths;
};

Eigen::Vector3d FaceNormal(const Config& c, int t) {
  const auto& T = c.tri[static_cast<std::size_t>(t)];
  const Eigen::Vector3d& a = c.v[static_cast<std::size_t>(T[0])];
  const Eigen::Vector3d& b = c.v[static_cast<std::size_t>(T[1])];
  const Eigen::Vector3d& d = c.v[static_cast<std::size_t>(T[2])];
  return (b - a).cross(d - a).normalized();
}

// Distance from g to the free space of the configuration (an upper bound): convex, the free
// space holds each face's offset half-space (the surface lies under every face's plane), so the
// smallest depth under one of them; concave, it holds their intersection, so the distance to
// that (the projection onto at most three planes, enumerated).
double FreeDistance(const Config& c, const Eigen::Vector3d& g) {
  int m = static_cast<int>(c.tri.size());
  std::vector<Eigen::Vector3d> n(static_cast<std::size_t>(m));
  std::vector<double> b(static_cast<std::size_t>(m));
  for (int t = 0; t < m; ++t) {
    n[static_cast<std::size_t>(t)] = FaceNormal(c, t);
    b[static_cast<std::size_t>(t)] = n[static_cast<std::size_t>(t)].dot(c.v[static_cast<std::size_t>(c.tri[static_cast<std::size_t>(t)][0])]) + kRs;
  }
  for (int t = m - 1; t > 0; --t) {  // coplanar triangles: one plane
    for (int u = 0; u < t; ++u) {
      if (n[static_cast<std::size_t>(t)].dot(n[static_cast<std::size_t>(u)]) > 1.0 - 1e-12 &&
          std::abs(b[static_cast<std::size_t>(t)] - b[static_cast<std::size_t>(u)]) < 1e-12) {
        n.erase(n.begin() + t);
        b.erase(b.begin() + t);
        --m;
        break;
      }
    }
  }
  if (!c.concave) {
    double best = 1e9;
    for (int t = 0; t < m; ++t) best = std::min(best, std::max(0.0, b[static_cast<std::size_t>(t)] - n[static_cast<std::size_t>(t)].dot(g)));
    return best;
  }
  auto feasible = [&](const Eigen::Vector3d& p) {
    for (int t = 0; t < m; ++t) {
      if (n[static_cast<std::size_t>(t)].dot(p) < b[static_cast<std::size_t>(t)] - 1e-12) return false;
    }
    return true;
  };
  double best = feasible(g) ? 0.0 : 1e9;
  for (int mask = 1; mask < (1 << m); ++mask) {  // every active set
    Eigen::MatrixXd N(0, 3);
    Eigen::VectorXd r(0);
    for (int t = 0; t < m; ++t) {
      if (!(mask & (1 << t))) continue;
      N.conservativeResize(N.rows() + 1, 3);
      r.conservativeResize(r.size() + 1);
      N.row(N.rows() - 1) = n[static_cast<std::size_t>(t)].transpose();
      r(r.size() - 1) = b[static_cast<std::size_t>(t)] - n[static_cast<std::size_t>(t)].dot(g);
    }
    const Eigen::MatrixXd G = N * N.transpose();
    if (std::abs(G.determinant()) < 1e-12) continue;
    const Eigen::Vector3d p = g + N.transpose() * G.inverse() * r;  // onto those planes
    if (feasible(p)) best = std::min(best, (p - g).norm());
  }
  return best;
}

// Two triangles sharing the edge (0, -L, 0)-(0, L, 0): A in z = 0 on x < 0, B on x > 0 tilted by
// beta: down (convex ridge) or up (concave valley); beta = 0 is a flat shared edge. Normals +z.
// split: each face cut in two coplanar triangles by the plane y = 0, so that flat edges cross
// the crease at the vertex (0, 0, 0), as on any triangulated valley.
Config Crease(bool convex, double beta, bool split = false) {
  Config c;
  const double s = convex ? 1.0 : -1.0;
  c.concave = !convex;
  c.v = {{0, -kL, 0}, {0, kL, 0}, {-kL, 0, 0}, {kL * std::cos(beta), 0, -s * kL * std::sin(beta)}, {0, 0, 0}};
  c.tri = split ? std::vector<std::array<std::int32_t, 3>>{{0, 4, 2}, {4, 1, 2}, {4, 0, 3}, {1, 4, 3}}
                : std::vector<std::array<std::int32_t, 3>>{{0, 1, 2}, {1, 0, 3}};
  if (!split) c.v.pop_back();
  return c;
}

// Three triangles round the vertex (0, 0, 0), their rims at radius L, sloping down by gamma
// (convex apex) or up (concave pit).
// split: each face cut in two coplanar triangles from the vertex to the point `at` of the way
// along its rim (six triangles round the vertex; at 0.5, the proxy in a pit's corner touches the
// faces on those flat edges; a little off it, a round-off distance beside them).
Config Vertex(bool convex, double gamma, bool split = false, double at = 0.5) {
  Config c;
  const double s = convex ? 1.0 : -1.0;
  c.concave = !convex;
  c.v = {{0, 0, 0}};
  for (int k = 0; k < 3; ++k) {
    const double a = 2.0 * M_PI * k / 3.0 + 0.3;
    c.v.emplace_back(kL * std::cos(a), kL * std::sin(a), -s * kL * std::tan(gamma));
  }
  c.tri = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}};
  if (split) {
    const std::vector<std::array<std::int32_t, 3>> whole = c.tri;
    c.tri.clear();
    for (const auto& t : whole) {
      const auto m = static_cast<std::int32_t>(c.v.size());
      c.v.push_back((1.0 - at) * c.v[static_cast<std::size_t>(t[1])] + at * c.v[static_cast<std::size_t>(t[2])]);
      c.tri.push_back({t[0], t[1], m});
      c.tri.push_back({t[0], m, t[2]});
    }
  }
  return c;
}

std::string Num(double x) {
  std::ostringstream os;
  os << x;
  return os.str();
}

// Two triangles sharing an edge. Convex: a ridge (beta > 0) or flat (beta = 0).
std::vector<Config> EdgeConfigs(bool convex) {
  std::vector<Config> out;
  const Eigen::Vector3d ex(1, 0, 0), ey(0, 1, 0), ez(0, 0, 1);
  for (double beta : convex ? std::vector<double>{0.0, 0.003, 0.03, 0.3} : std::vector<double>{0.003, 0.03, 0.3}) {
    const std::string what = (convex ? (beta > 0 ? "convex ridge" : "flat edge") : "concave valley") + std::string(" beta ") + Num(beta);
    if (convex) {
      // On A, its closest point delta from the shared edge (the edge at sqrt(Rs^2 + delta^2) =
      // Rs to round-off), or D before it: across the edge, along it, diagonally.
      for (double delta : {0.0, 1e-12, 1e-11, 1e-10, 1e-9, 1e-4, 3e-4, 1e-3, 2.9e-3}) {
        Config c = Crease(true, beta);
        c.kind = delta < 1e-6 ? "on A at the edge" : "sliding on A onto the edge";
        c.name = what + ", on A " + Num(delta * 1e3) + " mm from the edge";
        c.rest = Eigen::Vector3d(-delta, 0.003, kRs);
        c.normal = ez;
        c.slides = {ex, Eigen::Vector3d(1, 0.2, 0).normalized(), Eigen::Vector3d(1, 1, 0).normalized(),
                    Eigen::Vector3d(1, -1, 0).normalized(), ey, -ey};
        out.push_back(c);
      }
      // Over the edge itself (the closest point of both on the edge), the normal inside the
      // edge's normal cone: across both ways and along.
      for (double frac : {0.0, 0.5, 1.0}) {
        Config c = Crease(true, beta);
        c.kind = "over the edge";
        c.name = what + ", over the edge at " + Num(frac) + " of its normal cone";
        const double a = frac * beta;
        c.normal = Eigen::Vector3d(std::sin(a), 0, std::cos(a));
        c.rest = Eigen::Vector3d(0, -0.002, 0) + kRs * c.normal;
        const Eigen::Vector3d across = ey.cross(c.normal).normalized();
        c.slides = {across, -across, ey, -ey};
        out.push_back(c);
      }
    } else {
      // In the corner of a triangulated valley, delta or D before the flat edges that cross it:
      // along the crease over them, away from B beside them.
      for (double delta : {0.0, 1e-12, 1e-10, 1e-9, 1e-4, 1e-3, 2.9e-3}) {
        Config c = Crease(false, beta, true);
        c.kind = delta < 1e-6 ? "in the corner at a flat edge" : "sliding in the corner onto a flat edge";
        c.name = what + ", touching both faces " + Num(delta * 1e3) + " mm before the flat edges";
        c.normal = Eigen::Vector3d(-std::sin(0.5 * beta), 0, std::cos(0.5 * beta));
        c.rest = Eigen::Vector3d(0, -delta, 0) + (kRs / std::cos(0.5 * beta)) * c.normal;
        c.slides = {ey, Eigen::Vector3d(-0.2, 1, 0).normalized(), Eigen::Vector3d(-1, 1, 0).normalized(), -ex};
        out.push_back(c);
      }
      // In the corner, touching both faces: along the crease, up A away from B.
      {
        Config c = Crease(false, beta);
        c.kind = "in the corner";
        c.name = what + ", touching both faces";
        c.normal = Eigen::Vector3d(-std::sin(0.5 * beta), 0, std::cos(0.5 * beta));  // bisector
        c.rest = Eigen::Vector3d(0, 0.001, 0) + (kRs / std::cos(0.5 * beta)) * c.normal;
        c.slides = {ey, -ey, -ex, Eigen::Vector3d(-1, 1, 0).normalized()};
        out.push_back(c);
      }
      // On A, delta short of touching B too, or D short of it: along the crease, into the
      // corner and then along it, away.
      for (double delta : {1e-12, 1e-10, 1e-4, 3e-4, 1e-3, 2.9e-3}) {
        Config c = Crease(false, beta);
        c.kind = delta < 1e-6 ? "on A at the corner" : "sliding on A into the corner";
        c.name = what + ", on A " + Num(delta * 1e3) + " mm short of B";
        c.normal = ez;
        c.rest = Eigen::Vector3d(-kRs * std::tan(0.5 * beta) - delta, 0.003, kRs);
        c.slides = {ey, -ey, Eigen::Vector3d(0.1, 1, 0).normalized(), Eigen::Vector3d(0.1, -1, 0).normalized(),
                    Eigen::Vector3d(0.3, 1, 0).normalized(), -ex, Eigen::Vector3d(-1, 1, 0).normalized()};
        out.push_back(c);
      }
    }
  }
  return out;
}

// Three triangles sharing a vertex.
std::vector<Config> VertexConfigs(bool convex) {
  std::vector<Config> out;
  const Eigen::Vector3d ez(0, 0, 1);
  struct Mesh {
    double gamma;
    bool split;
    double at;
  };
  std::vector<Mesh> meshes;
  for (double gamma : {0.003, 0.03, 0.3}) {
    meshes.push_back({gamma, false, 0.5});
    // The convex apex with flat edges is the flat-edge case.
    if (!convex) {
      for (double at : {0.5 + 1e-9, 0.5 - 1e-8, 0.5 + 1e-7}) meshes.push_back({gamma, true, at});
    }
  }
  for (const auto& [gamma, split, at] : meshes) {
    const std::string what = (convex ? "convex apex" : std::string(split ? "triangulated " : "") + "concave pit") +
                             std::string(" gamma ") + Num(gamma) + (split ? " split at 0.5 + " + Num(at - 0.5) + " of the rim" : std::string());
    const Config base = Vertex(convex, gamma, split, at);
    const Eigen::Vector3d n1 = FaceNormal(base, 0);
    const Eigen::Vector3d into1 = ((base.v[1] + base.v[2]) / 2.0 - base.v[0]).normalized();  // in face 0
    const Eigen::Vector3d side = n1.cross(into1).normalized();
    if (convex) {
      // On face 0, its closest point delta from the vertex (inside the face, on its bisector),
      // or D before it: over the apex and past it, and beside it.
      for (double delta : {0.0, 1e-12, 1e-11, 1e-10, 1e-9, 1e-4, 3e-4, 1e-3, 2.9e-3}) {
        Config c = base;
        c.kind = delta < 1e-6 ? "on a face at the vertex" : "sliding on a face onto the vertex";
        c.name = what + ", on a face " + Num(delta * 1e3) + " mm from the vertex";
        c.normal = n1;
        c.rest = delta * into1 + kRs * n1;
        const Eigen::Vector3d over = -into1;
        c.slides = {over, (over + 0.1 * side).normalized(), (over - 0.1 * side).normalized(), (over + side).normalized(),
                    (over - side).normalized(), side};
        out.push_back(c);
      }
      // Straight over the vertex.
      Config c = base;
      c.kind = "over the vertex";
      c.name = what + ", over the vertex";
      c.normal = ez;
      c.rest = kRs * ez;
      for (int k = 0; k < 6; ++k) {
        const double a = M_PI * k / 3.0 + 0.1;
        c.slides.emplace_back(std::cos(a), std::sin(a), 0.0);
      }
      out.push_back(c);
    } else {
      // Touching all three faces (the vertex of their offset planes): out up each face.
      Eigen::Matrix3d N;
      Eigen::Vector3d b;
      const int per_face = split ? 2 : 1;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d n = FaceNormal(base, per_face * k);
        N.row(k) = n.transpose();
        b(k) = n.dot(base.v[0]) + kRs;
      }
      Config c = base;
      c.kind = std::string(split ? "triangulated, " : "") + "in the corner";
      c.name = what + ", touching all three faces";
      c.rest = N.inverse() * b;
      c.normal = ez;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d n = N.row(k).transpose();
        // Toward the middle of its rim (along the flat edge when split).
        Eigen::Vector3d up = 0.5 * (base.v[static_cast<std::size_t>(1 + k)] + base.v[static_cast<std::size_t>(1 + (k + 1) % 3)]) - base.v[0];
        up -= up.dot(n) * n;
        c.slides.push_back(up.normalized());
        c.slides.push_back((up.normalized() + 0.5 * n.cross(up).normalized()).normalized());
      }
      out.push_back(c);
      // On face 0, delta or D short of the corner (touching face 0 only): down into the corner
      // and round it, across it, up again.
      const Eigen::Vector3d corner = c.rest;
      for (double delta : {1e-12, 1e-10, 1e-4, 1e-3, 2.9e-3}) {
        Config d = base;
        d.kind = std::string(split ? "triangulated, " : "") + (delta < 1e-6 ? "on a face at the corner" : "sliding on a face into the corner");
        d.name = what + ", on a face " + Num(delta * 1e3) + " mm short of the corner";
        // Up face 0 from the corner along its bisector, delta beyond where it leaves the others.
        d.rest = corner + delta * into1;
        d.normal = n1;
        // Along face 0 (past the corner, then up the valley edges it shares with faces 1 and 2).
        d.slides = {side, -side, (side - 0.2 * into1).normalized(), (-side - 0.2 * into1).normalized()};
        // Down into the corner (1 mm below it), then 20 mm up face 1 or 2, or along face 0 again.
        const Eigen::Vector3d low = corner - kDepth * ez;
        for (int k = 0; k < 3; ++k) {
          d.paths.push_back({low, low + kSlide * c.slides[static_cast<std::size_t>(2 * k)]});
        }
        out.push_back(d);
      }
    }
  }
  return out;
}

struct Outcome {
  int checked = 0;
  int failed = 0;
  std::string first_failures;
  std::map<std::string, std::pair<int, int>> by_kind;  // kind -> (failed, checked)
  std::string Summary() const {
    std::ostringstream os;
    os << failed << " of " << checked << " slides did not follow (";
    for (const auto& [kind, fc] : by_kind) os << kind << ": " << fc.first << "/" << fc.second << "; ";
    os << "), e.g.\n" << first_failures;
    return os.str();
  }
};

// Runs every configuration in three poses, every slide direction, with the given friction.
Outcome RunAll(const std::vector<Config>& configs, const FrictionParams& friction) {
  const double mu = friction.mu_static;
  const double cone = std::sqrt(1.0 + mu * mu);
  Outcome out;
  const Eigen::Isometry3d poses[] = {
      Eigen::Isometry3d::Identity(),
      Eigen::Translation3d(0.011, -0.023, 0.037) * Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()),
      Eigen::Translation3d(-0.031, 0.005, 0.052) * Eigen::AngleAxisd(2.1, Eigen::Vector3d(-3, 1, 0.5).normalized()),
  };
  for (const Config& c : configs) {
    // The static cone is tested about the frictionless contact's normal, but the proxy holds
    // where it stuck: on another face, or on the same one round an edge, its height over the
    // plane of that normal differs by up to the lag (mu_s times the gap) times the sine of the
    // largest angle between two faces.
    double sin_max = 0.0;
    for (std::size_t i = 0; i < c.tri.size(); ++i) {
      for (std::size_t j = 0; j < i; ++j) {
        sin_max = std::max(sin_max, FaceNormal(c, static_cast<int>(i)).cross(FaceNormal(c, static_cast<int>(j))).norm());
      }
    }
    const double factor = cone * (1.0 + mu * sin_max);
    for (const Eigen::Isometry3d& X : poses) {
      auto mesh = std::make_shared<TriMesh>();
      for (const Eigen::Vector3d& p : c.v) mesh->p_O_m.push_back(X * p);
      mesh->triangles = c.tri;
      MeshCollider collider(mesh, 64);
      ProxySolver solver(64);
      ProxyParams params;
      params.radius_m = kR;
      params.skin_m = kSkin;
      const Eigen::Vector3d rest = X * c.rest;
      const Eigen::Vector3d n = X.linear() * c.normal;
      // Every path in this pose: the fingertip starts 1 mm below the proxy and moves 0.1 mm a
      // step along the waypoints.
      const Eigen::Vector3d g0_local = c.rest - kDepth * c.normal;
      std::vector<std::vector<Eigen::Vector3d>> paths;
      for (const Eigen::Vector3d& s : c.slides) paths.push_back({g0_local, g0_local + kSlide * s});
      for (const auto& p : c.paths) {
        paths.push_back({g0_local});
        paths.back().insert(paths.back().end(), p.begin(), p.end());
      }
      (void)n;
      for (const auto& path : paths) {
        ProxyState st;
        st.x_O_m = rest;
        st.initialized = true;
        st.in_contact = true;
        double worst = 0.0, worst_bound = 0.0;  // the gap that most exceeds its bound
        int worst_step = -1, k = 0;
        double final_bound = 0.0;
        for (std::size_t leg = 1; leg < path.size(); ++leg) {
          const Eigen::Vector3d a = X * path[leg - 1], b = X * path[leg];
          const int steps = std::max(1, static_cast<int>(std::lround((b - a).norm() / (kSlide / kSteps))));
          for (int j = 1; j <= steps; ++j, ++k) {
            const Eigen::Vector3d goal = a + (b - a) * (static_cast<double>(j) / steps);
            solver.Step(collider, params, friction, goal, st);
            const double bound = FreeDistance(c, X.inverse() * goal) * factor + kSkin + 1e-9;
            const double gap = (st.x_O_m - goal).norm();
            final_bound = bound;
            if (worst_step < 0 || gap - bound > worst - worst_bound) {
              worst = gap;
              worst_bound = bound;
              worst_step = k;
            }
          }
        }
        const Eigen::Vector3d slide_local = path.back() - path[path.size() - 2];
        const double moved = (st.x_O_m - rest).norm();
        ++out.checked;
        auto& kind = out.by_kind[c.kind];
        ++kind.second;
        // Moved at least as far as the fingertip did, less what the surface holds back at the end.
        const double must_move = (X * path.back() - X * path.front()).norm() - final_bound - kDepth;
        if (moved < must_move || worst > worst_bound) {
          ++out.failed;
          ++kind.first;
          if (out.failed <= 8) {
            std::ostringstream os;
            os << "  " << c.name << ", last leg (" << (1e3 * slide_local).transpose() << ") mm, pose " << (&X - poses) << ": moved "
               << moved * 1e3 << " mm (at least " << must_move * 1e3 << "); at step " << worst_step << " the proxy was " << worst * 1e3
               << " mm from the fingertip (bound " << worst_bound * 1e3 << " mm)\n";
            out.first_failures += os.str();
          }
        }
      }
    }
  }
  return out;
}

const FrictionParams kFrictionless{0.0, 0.0};
const FrictionParams kFriction{0.6, 0.5};  // haptic_bench's rigid_mesh_20k

TEST(ProxyFollows, FromTwoTrianglesSharingAConvexOrFlatEdge) {
  for (const FrictionParams& f : {kFrictionless, kFriction}) {
    const Outcome o = RunAll(EdgeConfigs(true), f);
    EXPECT_GT(o.checked, 500);
    EXPECT_EQ(o.failed, 0) << "mu_s " << f.mu_static << ": " << o.Summary();
  }
}

TEST(ProxyFollows, FromTwoTrianglesSharingAConcaveEdge) {
  for (const FrictionParams& f : {kFrictionless, kFriction}) {
    const Outcome o = RunAll(EdgeConfigs(false), f);
    EXPECT_GT(o.checked, 300);
    EXPECT_EQ(o.failed, 0) << "mu_s " << f.mu_static << ": " << o.Summary();
  }
}

TEST(ProxyFollows, FromThreeTrianglesSharingAConvexVertex) {
  for (const FrictionParams& f : {kFrictionless, kFriction}) {
    const Outcome o = RunAll(VertexConfigs(true), f);
    EXPECT_GT(o.checked, 400);
    EXPECT_EQ(o.failed, 0) << "mu_s " << f.mu_static << ": " << o.Summary();
  }
}

TEST(ProxyFollows, FromThreeTrianglesSharingAConcaveVertex) {
  for (const FrictionParams& f : {kFrictionless, kFriction}) {
    const Outcome o = RunAll(VertexConfigs(false), f);
    EXPECT_GT(o.checked, 250);
    EXPECT_EQ(o.failed, 0) << "mu_s " << f.mu_static << ": " << o.Summary();
  }
}

}  // namespace
}  // namespace handshare::contact
