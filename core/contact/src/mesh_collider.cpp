#include "handshare/contact/mesh_collider.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>

#include <stdexcept>
#include <vector>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_request.h>
#include <fcl/narrowphase/collision_result.h>

#include "handshare/contact/geometry.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

namespace handshare::contact {

struct MeshCollider::Impl {
  fcl::BVHModel<fcl::OBBRSSd> bvh;
  fcl::Sphered ball{1.0};
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
};

MeshCollider::MeshCollider(std::shared_ptr<const TriMesh> mesh, std::int32_t max_candidates)
    : impl_(std::make_unique<Impl>()), mesh_(std::move(mesh)), max_candidates_(max_candidates) {
  if (!mesh_) throw std::invalid_argument("MeshCollider: null mesh");
  mesh_->Validate();
  if (max_candidates_ < 1) throw std::invalid_argument("MeshCollider: max_candidates must be >= 1");
  static std::atomic<std::uint64_t> next_id{1};
  id_ = next_id.fetch_add(1, std::memory_order_relaxed);
  std::vector<fcl::Vector3d> points(mesh_->p_O_m.begin(), mesh_->p_O_m.end());
  std::vector<fcl::Triangle> tris;
  tris.reserve(mesh_->triangles.size());
  for (const auto& t : mesh_->triangles) {
    tris.emplace_back(static_cast<std::size_t>(t[0]), static_cast<std::size_t>(t[1]),
                      static_cast<std::size_t>(t[2]));
  }
  auto& bvh = impl_->bvh;
  if (bvh.beginModel(static_cast<int>(tris.size()), static_cast<int>(points.size())) != fcl::BVH_OK ||
      bvh.addSubModel(points, tris) != fcl::BVH_OK || bvh.endModel() != fcl::BVH_OK) {
    throw std::runtime_error("MeshCollider: FCL failed to build the BVH");
  }
  bvh.computeLocalAABB();
  BuildFlatTree();
  Eigen::Vector3d lo = mesh_->p_O_m[0], hi = lo;
  for (const auto& p : mesh_->p_O_m) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  bound_c_ = 0.5 * (lo + hi);
  for (const auto& p : mesh_->p_O_m) bound_r_ = std::max(bound_r_, (p - bound_c_).norm());

  // The cross-check request: boolean per triangle, up to max_candidates triangles.
  impl_->request.num_max_contacts = static_cast<std::size_t>(max_candidates_);
  impl_->request.enable_contact = false;
  impl_->request.gjk_solver_type = fcl::GST_INDEP;
}

namespace {
// Rounds a double coordinate to the float at or below (lo) / at or above (hi) it.
float FloatDown(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
// Ball (c, r^2) against an oriented box of FCL's OBBRSS (model frame): false if disjoint.
bool InObb(const fcl::OBBd& obb, const Eigen::Vector3d& c, double r2) {
  const Eigen::Vector3d local = obb.axis.transpose() * (c - obb.To);
  const Eigen::Vector3d excess = (local.cwiseAbs() - obb.extent).cwiseMax(0.0);
  return excess.squaredNorm() <= r2;
}
// The exact leaf test of both walks: triangle t joins the answer if the ball (c, r^2) reaches it.
// Returns false when the answer is full (then marked truncated).
bool AddIfReached(const SweepTriangle& tri, std::int32_t t, const Eigen::Vector3d& c, double r2,
                  std::span<std::int32_t> ids, BallQueryResult& out) {
  const Eigen::Vector3d q = ClosestPointOnTriangle(c, tri.v[0], tri.v[1], tri.v[2]);
  if ((q - c).squaredNorm() > r2) return true;
  if (out.count == static_cast<std::int32_t>(ids.size())) {
    out.truncated = true;
    return false;
  }
  ids[static_cast<std::size_t>(out.count++)] = t;
  return true;
}
float FloatUp(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}
}  // namespace

void MeshCollider::BuildFlatTree() {
  const auto& bvh = impl_->bvh;
  const TriMesh& mesh = *mesh_;
  const std::size_t nt = mesh.triangles.size();
  tri_.resize(nt);
  tri_plane_.resize(nt);
  tri_disc_.resize(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tr = mesh.triangles[t];
    tri_[t] = MakeSweepTriangle(mesh.p_O_m[tr[0]], mesh.p_O_m[tr[1]], mesh.p_O_m[tr[2]]);
    const Eigen::Vector3d& n = tri_[t].n;
    if (tri_[t].has_face && n.allFinite()) {
      tri_plane_[t] = Eigen::Vector4d(n.x(), n.y(), n.z(), n.dot(tri_[t].v[0]));
      const Eigen::Vector3d c = (tri_[t].v[0] + tri_[t].v[1] + tri_[t].v[2]) / 3.0;
      double r = 0.0;
      for (const Eigen::Vector3d& v : tri_[t].v) r = std::max(r, (v - c).norm());
      tri_disc_[t] = Eigen::Vector4d(c.x(), c.y(), c.z(), r);
    } else {
      tri_plane_[t].setConstant(std::numeric_limits<double>::quiet_NaN());
      tri_disc_[t].setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }
  // Each vertex is swept by one triangle that holds it (the first), see SweepTriangle::own_vertices.
  std::vector<std::int32_t> owner(mesh.p_O_m.size(), -1);
  for (std::size_t t = 0; t < nt; ++t) {
    std::uint8_t own = 0;
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(mesh.triangles[t][static_cast<std::size_t>(k)]);
      if (owner[v] < 0) owner[v] = static_cast<std::int32_t>(t);
      if (owner[v] == static_cast<std::int32_t>(t)) own = static_cast<std::uint8_t>(own | (1u << k));
    }
    tri_[t].own_vertices = own;
  }
  coord_scale_m_ = 0.0;
  for (const auto& p : mesh.p_O_m) coord_scale_m_ = std::max(coord_scale_m_, p.cwiseAbs().maxCoeff());
  std::vector<FlatNode> nodes;
  nodes.reserve(static_cast<std::size_t>(bvh.getNumBVs()));
  // Depth-first (left before right) copy of FCL's tree; returns the subtree's box (double).
  struct Box {
    Eigen::Vector3d lo, hi;
  };
  std::function<Box(int)> copy = [&](int fcl_id) -> Box {
    const auto& node = bvh.getBV(fcl_id);
    const auto me = static_cast<std::int32_t>(nodes.size());
    nodes.push_back(FlatNode{});
    Box box;
    if (node.isLeaf()) {
      const auto& P = tri_[static_cast<std::size_t>(node.primitiveId())].v;
      box.lo = P[0].cwiseMin(P[1]).cwiseMin(P[2]);
      box.hi = P[0].cwiseMax(P[1]).cwiseMax(P[2]);
      nodes[static_cast<std::size_t>(me)].right = -1 - node.primitiveId();
    } else {
      const Box l = copy(node.leftChild());
      nodes[static_cast<std::size_t>(me)].right = static_cast<std::int32_t>(nodes.size());
      const Box r = copy(node.rightChild());
      box.lo = l.lo.cwiseMin(r.lo);
      box.hi = l.hi.cwiseMax(r.hi);
    }
    FlatNode& f = nodes[static_cast<std::size_t>(me)];
    for (int k = 0; k < 3; ++k) {
      f.lo[k] = FloatDown(box.lo[k]);
      f.hi[k] = FloatUp(box.hi[k]);
    }
    return box;
  };
  copy(0);
  BuildWideTree(nodes);
}

void MeshCollider::BuildWideTree(const std::vector<FlatNode>& nodes) {
  wide_.clear();
  auto node = [&](std::int32_t k) -> const FlatNode& { return nodes[static_cast<std::size_t>(k)]; };
  auto size = [&](std::int32_t k) {  // the box's half perimeter
    const FlatNode& n = node(k);
    return (static_cast<double>(n.hi[0]) - n.lo[0]) + (static_cast<double>(n.hi[1]) - n.lo[1]) +
           (static_cast<double>(n.hi[2]) - n.lo[2]);
  };
  // A wide node whose children are the compact nodes `kids` after expanding, in place and so in
  // left-to-right order, the inner node with the largest box among them until there are eight
  // (or only leaves).
  std::function<std::int32_t(std::vector<std::int32_t>)> build = [&](std::vector<std::int32_t> kids) {
    const auto me = static_cast<std::int32_t>(wide_.size());
    wide_.push_back(WideNode{});
    while (kids.size() < static_cast<std::size_t>(kWide)) {
      std::size_t best = kids.size();
      for (std::size_t q = 0; q < kids.size(); ++q) {
        if (node(kids[q]).right < 0) continue;  // a leaf
        if (best == kids.size() || size(kids[q]) > size(kids[best])) best = q;
      }
      if (best == kids.size()) break;
      const std::int32_t k = kids[best];
      kids[best] = node(k).right;
      kids.insert(kids.begin() + static_cast<std::ptrdiff_t>(best), k + 1);
    }
    // The children first (wide_ may grow, so `me` is filled after).
    std::int32_t child[kWide];
    for (std::size_t q = 0; q < static_cast<std::size_t>(kWide); ++q) {
      if (q >= kids.size()) {
        child[q] = -1;
      } else {
        const FlatNode& n = node(kids[q]);
        child[q] = n.right < 0 ? n.right : build({kids[q] + 1, n.right});
      }
    }
    WideNode& w = wide_[static_cast<std::size_t>(me)];
    for (std::size_t q = 0; q < static_cast<std::size_t>(kWide); ++q) {
      for (int a = 0; a < 3; ++a) {
        w.lo[a][q] = q < kids.size() ? node(kids[q]).lo[a] : std::numeric_limits<float>::infinity();
        w.hi[a][q] = q < kids.size() ? node(kids[q]).hi[a] : -std::numeric_limits<float>::infinity();
      }
      w.child[q] = child[q];
    }
    return me;
  };
  if (nodes.empty()) return;
  // The root's children: those of the compact root, or the compact root itself when it is the
  // only triangle's leaf.
  build(nodes[0].right < 0 ? std::vector<std::int32_t>{0} : std::vector<std::int32_t>{1, nodes[0].right});
}

MeshCollider::~MeshCollider() = default;
MeshCollider::MeshCollider(MeshCollider&&) noexcept = default;
MeshCollider& MeshCollider::operator=(MeshCollider&&) noexcept = default;

BallQueryResult MeshCollider::QueryBall(const Eigen::Vector3d& c, double r_m, std::span<std::int32_t> ids,
                                        bool exact) const noexcept {
  BallQueryResult out;
  if (!c.allFinite() || !(r_m > 0.0) || !std::isfinite(r_m)) return out;
  const double r2 = r_m * r_m;
  // Float box test, conservative: the slack (1e-6 of the coordinates' size) is far above the
  // float round-off of the centre, the differences and the squares (~1e-7 relative), so a box
  // the ball reaches is never rejected; the exact test is the leaf's.
  const double slack = 1e-6 * (coord_scale_m_ + c.cwiseAbs().maxCoeff() + r_m);
  const float rf2 = FloatUp((r_m + slack) * (r_m + slack));
  const float cx = static_cast<float>(c.x()), cy = static_cast<float>(c.y()), cz = static_cast<float>(c.z());
  const WideNode* wide = wide_.data();
  // Depth-first over the wide tree, children in order (pushed last to first): the triangles
  // come out in the compact tree's leaf order. Each pop is a wide node or a triangle (< 0).
  constexpr int kStack = 128;
  std::int32_t stack[kStack];
  int top = 0;
  stack[top++] = 0;
  // A triangle whose plane or bounding disc lies beyond the ball (with a slack far above their
  // round-off) is not reached: the exact closest point is skipped for it, same answer.
  const double far = r_m + 1e-9 * (coord_scale_m_ + c.cwiseAbs().maxCoeff() + r_m);
  while (top > 0) {
    const std::int32_t item = stack[--top];
    if (item < 0) {
      const auto t = static_cast<std::size_t>(-1 - item);
      if (BeyondTriangle(tri_disc_[t], c, PlaneDistance(tri_plane_[t], c), far)) continue;
      if (exact) {
        if (!AddIfReached(tri_[t], -1 - item, c, r2, ids, out)) return out;
      } else if (out.count == static_cast<std::int32_t>(ids.size())) {
        out.truncated = true;
        return out;
      } else {
        ids[static_cast<std::size_t>(out.count++)] = -1 - item;
      }
      continue;
    }
    const WideNode& n = wide[item];
    unsigned mask = 0;
#if defined(__SSE2__)
    const __m128 zero = _mm_setzero_ps(), r2v = _mm_set1_ps(rf2);
    const __m128 cv[3] = {_mm_set1_ps(cx), _mm_set1_ps(cy), _mm_set1_ps(cz)};
    for (int h = 0; h < kWide; h += 4) {
      __m128 d2 = zero;
      for (int a = 0; a < 3; ++a) {
        const __m128 e = _mm_add_ps(_mm_max_ps(_mm_sub_ps(_mm_load_ps(n.lo[a] + h), cv[a]), zero),
                                    _mm_max_ps(_mm_sub_ps(cv[a], _mm_load_ps(n.hi[a] + h)), zero));
        d2 = _mm_add_ps(d2, _mm_mul_ps(e, e));
      }
      mask |= static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(d2, r2v))) << h;
    }
#else
    const float cc[3] = {cx, cy, cz};
    for (int q = 0; q < kWide; ++q) {
      float d2 = 0.0f;
      for (int a = 0; a < 3; ++a) {
        const float e = std::max(n.lo[a][q] - cc[a], 0.0f) + std::max(cc[a] - n.hi[a][q], 0.0f);
        d2 += e * e;
      }
      if (d2 <= rf2) mask |= 1u << q;
    }
#endif
    // Children reached, last first onto the stack.
    while (mask != 0) {
      const int q = 31 - __builtin_clz(mask);
      mask &= ~(1u << q);
      if (top == kStack) {
        out.truncated = true;
        continue;
      }
      stack[top++] = n.child[q];
    }
  }
  return out;
}

BallQueryResult MeshCollider::QueryBallObb(const Eigen::Vector3d& c, double r_m,
                                        std::span<std::int32_t> ids) const noexcept {
  BallQueryResult out;
  if (!c.allFinite() || !(r_m > 0.0) || !std::isfinite(r_m)) return out;
  const auto& bvh = impl_->bvh;
  const double r2 = r_m * r_m;
  // Depth-first walk with a fixed stack (FCL's top-down build keeps the depth near
  // log2(triangles) + a few; a deeper tree is reported as truncated, never overrun).
  constexpr int kStack = 128;
  int stack[kStack];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const auto& node = bvh.getBV(stack[--top]);
    // Ball against the node's oriented box (OBB part of OBBRSS, model frame).
    if (!InObb(node.bv.obb, c, r2)) continue;
    if (node.isLeaf()) {
      const int t = node.primitiveId();
      if (!AddIfReached(tri_[static_cast<std::size_t>(t)], t, c, r2, ids, out)) return out;
      continue;
    }
    if (top + 2 > kStack) {
      out.truncated = true;
      continue;
    }
    stack[top++] = node.rightChild();
    stack[top++] = node.leftChild();
  }
  return out;
}

BallQueryResult MeshCollider::QueryBallFcl(const Eigen::Vector3d& c_O_m, double r_m,
                                           std::span<std::int32_t> triangle_ids) {
  BallQueryResult out;
  if (!c_O_m.allFinite() || !(r_m > 0.0) || !std::isfinite(r_m)) return out;
  Impl& im = *impl_;
  im.ball.radius = r_m;
  im.result.clear();
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() = c_O_m;
  fcl::collide(&im.bvh, fcl::Transform3d::Identity(), &im.ball, tf, im.request, im.result);
  const std::size_t n = im.result.numContacts();
  for (std::size_t i = 0; i < n; ++i) {
    if (out.count == static_cast<std::int32_t>(triangle_ids.size())) {
      out.truncated = true;
      break;
    }
    triangle_ids[static_cast<std::size_t>(out.count++)] = static_cast<std::int32_t>(im.result.getContact(i).b1);
  }
  if (n >= static_cast<std::size_t>(max_candidates_)) out.truncated = true;
  return out;
}

}  // namespace handshare::contact
