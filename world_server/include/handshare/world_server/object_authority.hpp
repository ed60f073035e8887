#pragma once
/// The world server's model of the shared world: the scene's objects built the way every haptic
/// node builds them (world::BuildSceneModels), fed with every user's contact sets. Each tick it
///   - arbitrates ownership of grasped rigid bodies (OwnershipArbiter, from the contact sets'
///     grasp claims and vanished members), follows an owned body at its owner's reported pose
///     and simulates free bodies itself (gravity, support, the users' pushes);
///   - solves every deformable with all users' fingertips on it (one FEM solve per object, the
///     same patches the haptic nodes build) and returns the changed surface nodes to publish
///     (DeformationDelta);
///   - returns the rigid bodies' states (owned, free and moving) to publish.
/// What it returns is plain (BodyState, DeformationSample, OwnershipChange, lines for the log):
/// the session turns it into events (session_events.hpp) and only the DDS publisher turns
/// those into samples. This header includes no DDS or generated message header (ctest
/// architecture.no_middleware_in_core checks it). Its one input from the wire is a user's
/// contact set, taken as it arrived (msg::ContactSet, declared here only by name): the
/// implementation hands it to session::PeerContacts, which decodes its contacts through the
/// contact codec; the poses it carries become Eigen through contact::ToPose. Models are built
/// on a loader thread, so a new world (tetgen, compliance cache) never stalls the session.
///
/// Deformation contract (what graphics nodes rely on): node ids are the vertex indices of the
/// object's scene mesh (LoadMesh order), which the tetrahedral mesh keeps as its first nodes;
/// displacements in W. An object whose tetrahedral mesh does not keep them is not published
/// (and said so).
#include <chrono>
#include <filesystem>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "handshare/common/session_clock.hpp"
#include "handshare/contact/peer_contact.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/world_server/body_state.hpp"
#include "handshare/world/scene_models.hpp"
#include "handshare/world/scripted_motion.hpp"
#include "handshare/world_server/deformation_delta.hpp"
#include "handshare/world_server/ownership_arbiter.hpp"

namespace handshare::msg {
class ContactSet;  // handshare.idl; read only in object_authority.cpp
}  // namespace handshare::msg
namespace handshare::session {
class PeerContacts;
}  // namespace handshare::session

namespace handshare::server {

struct ObjectAuthorityOptions {
  world::SceneModelsOptions models;
  double physics_dt_s = 0.001;           ///< body integration sub-step (support stiffness needs <= 2 ms)
  DeformationDeltaConfig delta;
  OwnershipConfig ownership;
  contact::PeerFade peers;  ///< how a silent user's contacts fade out (session::PeerContacts)
  /// Free bodies are published while they move more than this per tick, and once when they stop.
  double rest_tolerance_m = 1e-5;
  /// Every free body's pose is published again at least this often (0: only on a spectator's
  /// join): object states are best-effort, so a receiver that missed the last one of a body at
  /// rest (a late joiner whose reader matched after the join's re-send, a lost datagram) would
  /// otherwise draw it where the scene put it, for good.
  std::chrono::duration<double> pose_refresh_period{1.0};
  /// When set: every published deformation also goes to DIR/<object>.json (the loads of the
  /// solve, the material, the fixed nodes and the field the receivers hold) with the
  /// tetrahedral mesh in DIR/<object>.inp, so the FEM can be checked independently.
  std::filesystem::path dump_dir;
};

/// What one tick decided: plain data, in the order the session reports it.
struct TickOutput {
  std::vector<std::string> notes;               ///< lines for the server's log
  std::vector<OwnershipChange> ownership;
  std::vector<BodyState> bodies;                ///< rigid-body states to publish
  std::vector<std::pair<std::string, DeformationSample>> deformations;  ///< object id, sample
};

class ObjectAuthority {
 public:
  using Clock = std::chrono::steady_clock;
  /// Periodic motions run on the session's `clock` (the origin the world server publishes).
  ObjectAuthority(std::string session, ObjectAuthorityOptions options, common::SessionClock clock = {});
  ~ObjectAuthority();
  ObjectAuthority(const ObjectAuthority&) = delete;
  ObjectAuthority& operator=(const ObjectAuthority&) = delete;

  /// A new revision of the scene. Another world: contacts, owners and deformations start
  /// afresh. The same world (new gravity): bodies keep their poses and owners. Never waits:
  /// the models are built on a loader thread; a build still in flight for an older revision is
  /// superseded (its models are dropped when it finishes), so only the newest revision's
  /// models are ever adopted.
  void SetScene(const scene::Scene& scene);
  void OnContactSet(const msg::ContactSet& set, Clock::time_point now);
  void OnUserGone(const std::string& user, Clock::time_point now);
  /// Where a dynamic body is when the next models of this world are adopted (a resumed session:
  /// the poses its log last held). Ignored for objects the world does not have.
  /// With an owner (the log says that user held it): the body is held where it is and not
  /// published until that user's claim grants it back, or for `grace` after the models are
  /// adopted (then it is free and falls). Otherwise a restarted server simulates and publishes a held ball as free before
  /// its owner's claim arrives (33-84 ms on a busy machine), and the owner's hand follows the
  /// server's ball for that long: a held weight read 0 to 11.7 N through a restart.
  void PlaceBody(const std::string& object_id, const Eigen::Isometry3d& X_WO, const std::string& owner = "",
                 Clock::duration grace = {});
  /// A reader of deformations joined: the next tick sends keyframes.
  void RequestKeyframes();
  /// Advances to `now` (dt_s since the last tick, sub-stepped) and returns what to publish:
  /// the stages below, in this order.
  TickOutput Tick(Clock::time_point now, double dt_s);

  bool ready() const { return models_ != nullptr; }
  /// The scene whose models are adopted ("" before the first is ready).
  const std::string& ready_scene() const { return ready_scene_; }
  /// Builds superseded by a newer revision and not finished yet.
  std::size_t superseded_builds() const { return superseded_.size(); }
  std::string owner(const std::string& object_id) const { return arbiter_.owner(object_id); }

 private:
  struct Deformable {
    contact::ObjectId object = -1;
    std::string id;
    std::int32_t vertex_count = 0;              // published field size
    std::vector<std::int32_t> vertex_of_slot;   // compliance slot -> vertex (-1: not published)
    std::unique_ptr<DeformationDelta> delta;
    std::vector<Eigen::Vector3d> u_slots;
    std::vector<double> u_W;                     // 3 per vertex
    std::vector<Eigen::Vector3d> u_O;            // per vertex, frame O (the beat's, then the contacts')
    std::optional<scene::Beat> beat;             // a beating body's beat (a copy: scene_ is reassigned)
    bool touched_before = false;
    const world::PreparedDeformable* prepared = nullptr;
    double E_Pa = 0.0, nu = 0.0;
  };
  // Who moves each dynamic body this tick (PlanBodies): its owner, or nobody (held at rest).
  // Defined in object_authority.cpp (it points at the owners' newest contact sets).
  struct BodyPlan;

  // ---- the stages of a tick ----
  /// Drops finished superseded builds and adopts the current world's models once built.
  void AdoptModels(TickOutput& out);
  /// Expires silent peers and arbitrates ownership; notes which bodies are being handed over.
  void ArbitrateOwnership(Clock::time_point now, TickOutput& out);
  /// Who simulates what (owners, reservations of a resumed session, hand-overs).
  BodyPlan PlanBodies(Clock::time_point now, TickOutput& out);
  /// The peers' fingertips on deformables, faded, into remote_; returns how many.
  std::size_t GatherPeerContacts(Clock::time_point now, double dt_s);
  /// Scripted motions and beats at the session clock's time.
  void MoveScriptedObjects(Clock::time_point now);
  /// Sub-steps the world over dt_s: owned bodies at their owner's pose, held ones at rest, the
  /// deformables' solve once (the last sub-step) with the `remote` gathered contacts.
  void StepWorld(const BodyPlan& plan, Clock::time_point now, double dt_s, std::size_t remote);
  /// The rigid bodies' states to publish.
  void PublishBodies(const BodyPlan& plan, Clock::time_point now, TickOutput& out);
  /// The deformables' changed surface fields to publish.
  void PublishFields(Clock::time_point now, TickOutput& out);

  void Adopt(world::SceneModels models, TickOutput& out);
  void ReapSuperseded(TickOutput& out);
  struct SupersededBuild {
    std::string scene;
    std::future<world::SceneModels> future;
  };
  void Dump(const Deformable& d, std::uint32_t revision, Clock::time_point now) const;

  std::string session_;
  ObjectAuthorityOptions options_;
  common::SessionClock clock_;
  scene::Scene scene_;
  std::unique_ptr<world::SceneModels> models_;
  std::future<world::SceneModels> loading_;
  std::vector<SupersededBuild> superseded_;
  std::string ready_scene_;
  std::map<std::string, Eigen::Isometry3d> placed_;  // PlaceBody: applied at the next Adopt
  struct Reservation {
    std::string owner;
    Clock::duration grace{};
    Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
    std::optional<Clock::time_point> until;  // set at the first tick with models
  };
  std::map<std::string, Reservation> reserved_;  // PlaceBody with an owner: held for its claim
  std::string loading_scene_;
  Clock::time_point loading_since_{};
  std::unique_ptr<session::PeerContacts> peers_;  // the users' newest contact sets
  OwnershipArbiter arbiter_;
  std::map<std::string, std::string> claims_;   // user -> object it claims ("" none)
  // Bodies handed from one owner to another (OwnershipReason::kHandedOver): held still where the
  // last owner left them (its newest set's pose) until the new owner's sets simulate them, not
  // dropped for that round trip.
  struct HandOver {
    std::string from;                       // the last owner
    std::optional<Eigen::Isometry3d> X_WO;  // where it left the body (found at the next tick)
  };
  std::map<std::string, HandOver> handing_over_;
  std::vector<Deformable> deformables_;
  world::ScriptedMotion scripted_;  // motions and beats on the session clock
  std::map<contact::ObjectId, Eigen::Vector3d> last_published_;     // free bodies
  std::vector<contact::PeerContact> received_;  // the peers' contacts on deformables, this tick
  std::vector<contact::FingerContact> remote_;   // faded, as the solve takes them
  contact::PeerFadeStage peer_fade_;
  bool keyframes_requested_ = false;
  Clock::time_point next_pose_refresh_{};  // ObjectAuthorityOptions::pose_refresh_period
};

}  // namespace handshare::server
