#pragma once
/// @file
/// The ideal haptic interface point (IHIP) of one fingertip on one triangle mesh: a sphere
/// god-object proxy (Ruspini, Kolarov and Khatib 1997, "The haptic display of complex graphical
/// environments"; Zilles and Salisbury 1995 for the point version). The proxy is a sphere of the
/// fingertip's radius that never overlaps the mesh. Each step it moves from where it was toward
/// the fingertip centre as far as the surface lets it:
///   1. constraints: every triangle within R + skin (+1 nm) of the proxy gives a half-space
///      n . t >= n . c + R + skin, n = (x - c)/|x - c|, c its closest point;
///   2. target t = projection of the goal onto the intersection of those half-spaces (a QP with
///      at most 3 active planes, solved exactly by enumerating active sets);
///   3. sweep the sphere from x toward t against the nearby triangles (face, edge and vertex
///      times of impact, exact); stop at the first hit; repeat from 1 (a few iterations).
/// The swept test and the previous position are what keep it from popping through a thin plate
/// or around an edge when the fingertip moves fast. Friction (Coulomb, static and kinetic) acts
/// on the proxy (two states, as in Salisbury et al. 1995): a stuck proxy stays while the force
/// is inside the static cone about the frictionless god-object's contact normal (that god-object
/// is tracked alongside, ProxyState::x_free_O_m); once it slips it slides, keeping the force on
/// the kinetic cone's boundary, until the force falls inside the kinetic cone (the fingertip
/// slows or stops). Real-time: noexcept, no allocation after construction.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "handshare/contact/mesh_collider.hpp"

namespace handshare::contact {

/// Geometry of the proxy (all in the mesh frame O).
struct ProxyParams {
  double radius_m = 0.008;       ///< fingertip (and proxy) radius R.
  double skin_m = 1e-6;          ///< gap kept between proxy sphere and surface (1 um: at 1e4 N/m
                                 ///< a 10 mN error, below what HIRO II resolves).
  double max_step_m = 2e-3;      ///< most the proxy moves per round while near a surface (2 m/s at
                                 ///< 1 kHz, four times HIRO II's fastest fingertip; up to
                                 ///< max_iterations rounds a step).
  std::int32_t max_iterations = 4;  ///< constrain-project-sweep rounds per move (a proxy that
                                    ///< has not converged goes on next step; every round is a
                                    ///< swept, feasible move, so fewer rounds never tunnel).
};

/// Coulomb friction on the proxy (mu_kinetic <= mu_static; 0 = frictionless).
struct FrictionParams {
  double mu_static = 0.0;
  double mu_kinetic = 0.0;
};

/// Per finger and object: where the proxy is. Plain data.
struct ProxyState {
  Eigen::Vector3d x_O_m = Eigen::Vector3d::Zero();  ///< proxy centre in O.
  /// The frictionless god-object, tracked alongside while in contact with friction (equal to
  /// x_O_m otherwise): the friction cone is tested about it. Tracked from where it was, not
  /// restarted from the (lagging) proxy each step, so it converges however far the proxy is held.
  Eigen::Vector3d x_free_O_m = Eigen::Vector3d::Zero();
  bool free_tracked = false;  ///< x_free_O_m holds the tracked god-object (else: start from x_O_m).
  bool initialized = false;                         ///< false: next step starts at the goal.
  bool in_contact = false;                          ///< touched the surface last step.
  bool sliding = false;  ///< slipped last step: stays slipping while outside the kinetic cone.
};

/// What a proxy step found (in O).
struct ProxyContact {
  bool touching = false;       ///< a surface is within R + skin and the fingertip presses on it.
  bool sticking = false;       ///< inside the static friction cone (proxy held still).
  bool truncated = false;      ///< the candidate buffer overflowed (some triangles unseen).
  Eigen::Vector3d x_O_m = Eigen::Vector3d::Zero();  ///< new proxy centre.
  Eigen::Vector3d p_O_m = Eigen::Vector3d::Zero();  ///< contact point: closest surface point.
  Eigen::Vector3d n_O = Eigen::Vector3d::Zero();    ///< unit outward normal at p (from p to x).
  std::int32_t triangle = -1;                       ///< triangle that holds p.
  double depth_m = 0.0;        ///< fingertip sphere below the surface: n . (x - goal) - skin.
  std::int32_t iterations = 0;
};

/// Scratch and algorithm; one per haptic thread (shared by all fingers and meshes).
class ProxySolver {
 public:
  /// @param max_candidates  triangles one ball query may return (buffers sized here).
  explicit ProxySolver(std::int32_t max_candidates = 512);

  /// One haptic step of the proxy on `collider` toward the fingertip centre goal_O (O frame).
  /// Updates state; returns the contact. Non-finite goal: state unchanged, touching = false.
  ProxyContact Step(const MeshCollider& collider, const ProxyParams& params,
                    const FrictionParams& friction, const Eigen::Vector3d& goal_O_m,
                    ProxyState& state) noexcept;

  /// Tests: true runs the previous exact path (FCL's oriented boxes in the walk, the exact
  /// closest point and sweep for every candidate, a fresh gather at every start) that the
  /// shortcuts (compact float tree, plane-distance skips, reuse of the constraints at the point
  /// where the last move ended) must reproduce bit for bit.
  void set_reference_path(bool on) noexcept { reference_ = on; }
  /// Tests: false culls the neighbourhoods' triangles and sweeps them one at a time (the path of
  /// processors without AVX-512) where the vector passes would run.
  void set_vector_cull(bool on) noexcept { vector_cull_ = on; }

  /// The frictionless constrained motion from x0 toward goal (the core of Step; public for
  /// tests). Returns the final proxy centre.
  Eigen::Vector3d Move(const MeshCollider& collider, const ProxyParams& params,
                       const Eigen::Vector3d& x0_O_m, const Eigen::Vector3d& goal_O_m,
                       bool* truncated = nullptr, std::int32_t* iterations = nullptr) noexcept;

 private:
  static constexpr int kMaxConstraints = 8;
  // Triangles within the touch band of the proxy (the constraints' own triangles, merged ones
  // included): the projection keeps the move outside each of them, so the sweep skips them.
  static constexpr int kMaxTouching = 32;
  struct Touching {
    int n = 0;
    std::array<std::int32_t, kMaxTouching> tri{};
    std::array<std::int8_t, kMaxTouching> con{};  // the constraint (index in cons_) that holds it
    bool Has(std::int32_t t) const noexcept {
      for (int i = 0; i < n; ++i) {
        if (tri[static_cast<std::size_t>(i)] == t) return true;
      }
      return false;
    }
    void Add(std::int32_t t, int c) noexcept {  // a full list sweeps the rest (conservative)
      if (n == kMaxTouching) return;
      tri[static_cast<std::size_t>(n)] = t;
      con[static_cast<std::size_t>(n++)] = static_cast<std::int8_t>(c);
    }
    void DropConstraint(int c) noexcept {  // its triangles are no longer held by a plane
      int k = 0;
      for (int i = 0; i < n; ++i) {
        if (con[static_cast<std::size_t>(i)] == c) continue;
        tri[static_cast<std::size_t>(k)] = tri[static_cast<std::size_t>(i)];
        con[static_cast<std::size_t>(k++)] = con[static_cast<std::size_t>(i)];
      }
      n = k;
    }
  };
  struct Constraint {
    Eigen::Vector3d n;   // unit, outward
    Eigen::Vector3d c;   // closest surface point
    double b = 0.0;      // n . t >= b
    double dist = 0.0;
    std::int32_t tri = -1;
  };
  // Candidate triangles near the segment x + s d, s in [0, 1] (d = 0: the point x): at least
  // every one within the touch band of it (culled_: only those, up to the cull's float slack), else every one
  // in the ball around it grown by R + skin and a margin. Returns false if none.
  bool Gather(const MeshCollider& collider, const ProxyParams& params, const Eigen::Vector3d& x,
              const Eigen::Vector3d& d) noexcept;
  int CollectConstraints(const MeshCollider& collider, const ProxyParams& params,
                         const Eigen::Vector3d& x) noexcept;
  Eigen::Vector3d Project(const Eigen::Vector3d& goal, const Eigen::Vector3d& x, int m) const noexcept;
  // Move, reusing the constraints at x0 when the last collection in this Step was there.
  Eigen::Vector3d MoveFrom(const MeshCollider& collider, const ProxyParams& params,
                           const Eigen::Vector3d& x0_O_m, const Eigen::Vector3d& goal_O_m,
                           bool* truncated, std::int32_t* iterations) noexcept;
  // The constraints at x (cons_, m returned): the ones at hand when they were collected there
  // for this collider and params from an untruncated gather, else a fresh gather and collection.
  int ConstraintsAt(const MeshCollider& collider, const ProxyParams& params, const Eigen::Vector3d& x) noexcept;
  // The constraints where an earlier Step ended at x, if the end table holds them (fast path).
  void LoadEnd(const MeshCollider& collider, const ProxyParams& params, const Eigen::Vector3d& x) noexcept;
  // Remembers the constraints at hand for a later Step starting where they were collected.
  void StoreEnd() noexcept;

  std::vector<std::int32_t> candidates_;
  std::vector<std::int32_t> sweep_ids_;  // the candidates a move sweeps (touching ones left out)
  std::int32_t num_candidates_ = 0;
  bool truncated_ = false;
  bool last_gather_truncated_ = false;
  bool reference_ = false;
  bool vector_cull_ = true;
  bool culled_ = false;  // the last gather came from a neighbourhood, culled to the touch band
  std::array<Constraint, kMaxConstraints> cons_{};
  Touching touching_;  // at the point cons_ were collected
  // Where a set of constraints was collected: they are a function of (mesh, x, R, skin) alone
  // when the gather was not truncated. collider_id 0: none.
  struct Site {
    std::uint64_t collider_id = 0;
    double radius_m = 0.0;
    double skin_m = 0.0;
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    bool Is(const MeshCollider& collider, const ProxyParams& params, const Eigen::Vector3d& at) const noexcept;
  };
  Site cons_site_;  // of cons_ (its first cons_m_)
  int cons_m_ = 0;
  // Constraints where earlier Steps ended (the next Step of that proxy starts there),
  // direct-mapped by the point (a pure function of the site, so any entry whose site matches is
  // right whichever finger wrote it).
  struct EndEntry {
    Site site;
    int m = 0;
    std::array<Constraint, kMaxConstraints> cons{};
    Touching touching;
  };
  static constexpr std::size_t kEndEntries = 64;
  std::vector<EndEntry> ends_;
  static std::size_t EndSlot(const Eigen::Vector3d& x) noexcept;
  // Neighbourhoods: the triangles within a ball (at least: an untruncated QueryBall without the
  // leaves' exact distance, in its order) with
  // their planes and bounding discs. A gather whose ball lies inside one is served from it: the
  // triangles whose plane-and-disc bound (SegmentDiscBound2) comes within the gather's radius of
  // its segment, a superset of what the sweep can hit and of what lies within the touch band of
  // any point of the segment, in the query's order, so the sweep and the constraint collection
  // reduce it to the same results bit for bit. The answer is a function of the mesh and the
  // ball alone, so an entry serves any finger. Slots are reused least recently used.
  struct Neighbourhood {
    std::uint64_t collider_id = 0;  // 0: empty
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    double r = 0.0;
    double slack = 0.0;  // of the cull: covers the float round-off at this neighbourhood's sizes
    std::int32_t n = 0;
    std::uint64_t used = 0;
    std::vector<std::int32_t> ids;  // capacity: the candidate buffer's
    // ids[i]'s plane (unit normal, offset) and bounding disc (centre, radius), one array each,
    // in float relative to c
    std::array<std::vector<float>, 8> soa;
  };
  static constexpr int kNeighbourhoods = 8;
  std::array<Neighbourhood, kNeighbourhoods> hoods_;
  std::uint64_t hood_clock_ = 0;
  // The candidates within r of the segment x + s d, s in [0, 1], from a neighbourhood that holds
  // the ball around its midpoint of radius r_ball; false: none holds it.
  bool GatherFromNeighbourhood(const MeshCollider& collider, const Eigen::Vector3d& x, const Eigen::Vector3d& d,
                               double r_ball, double r) noexcept;
  // A new neighbourhood (c, r + kNeighbourSlack) in the least recently used slot; false when its
  // query overflowed (nothing kept).
  bool FillNeighbourhood(const MeshCollider& collider, const Eigen::Vector3d& c, double r) noexcept;
};

}  // namespace handshare::contact
