#include "handshare/contact/mesh_collider.hpp"

#include <algorithm>
#include <cmath>

#include <stdexcept>
#include <vector>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_request.h>
#include <fcl/narrowphase/collision_result.h>

#include "handshare/contact/geometry.hpp"

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

MeshCollider::~MeshCollider() = default;
MeshCollider::MeshCollider(MeshCollider&&) noexcept = default;
MeshCollider& MeshCollider::operator=(MeshCollider&&) noexcept = default;

BallQueryResult MeshCollider::QueryBall(const Eigen::Vector3d& c, double r_m,
                                        std::span<std::int32_t> ids) const noexcept {
  BallQueryResult out;
  if (!c.allFinite() || !(r_m > 0.0) || !std::isfinite(r_m)) return out;
  const auto& bvh = impl_->bvh;
  const TriMesh& mesh = *mesh_;
  const double r2 = r_m * r_m;
  // Depth-first walk with a fixed stack (FCL's top-down build keeps the depth near
  // log2(triangles) + a few; a deeper tree is reported as truncated, never overrun).
  constexpr int kStack = 128;
  int stack[kStack];
  int top = 0;
  stack[top++] = 0;
  const auto cap = static_cast<std::int32_t>(ids.size());
  while (top > 0) {
    const auto& node = bvh.getBV(stack[--top]);
    // Ball against the node's oriented box (OBB part of OBBRSS, model frame).
    const auto& obb = node.bv.obb;
    const Eigen::Vector3d local = obb.axis.transpose() * (c - obb.To);
    const Eigen::Vector3d excess = (local.cwiseAbs() - obb.extent).cwiseMax(0.0);
    if (excess.squaredNorm() > r2) continue;
    if (node.isLeaf()) {
      const int t = node.primitiveId();
      const auto& tr = mesh.triangles[static_cast<std::size_t>(t)];
      const Eigen::Vector3d q = ClosestPointOnTriangle(c, mesh.p_O_m[tr[0]], mesh.p_O_m[tr[1]], mesh.p_O_m[tr[2]]);
      if ((q - c).squaredNorm() > r2) continue;
      if (out.count == cap) {
        out.truncated = true;
        return out;
      }
      ids[static_cast<std::size_t>(out.count++)] = t;
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
