#pragma once
/// The world server's model of the shared world: the scene's objects built the way every haptic
/// node builds them (world::BuildSceneWorld), fed with every user's contact sets. Each tick it
///   - arbitrates ownership of grasped rigid bodies (OwnershipArbiter, from the contact sets'
///     grasp claims and vanished members), follows an owned body at its owner's reported pose
///     and simulates free bodies itself (gravity, support, the users' pushes);
///   - solves every deformable with all users' fingertips on it (one FEM solve per object, the
///     same patches the haptic nodes build) and returns the changed surface nodes to publish
///     (DeformationDelta);
///   - returns the rigid bodies' states (owned, free and moving) to publish.
/// No DDS: the world server turns the inputs and outputs into samples. Models are built on a
/// loader thread, so a new world (tetgen, compliance cache) never stalls the session.
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
#include <string>
#include <vector>

#include "handshare/dds/messages.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/session/peer_contacts.hpp"
#include "handshare/world/scene_world.hpp"
#include "handshare/world_server/deformation_delta.hpp"
#include "handshare/world_server/ownership_arbiter.hpp"

namespace handshare::world {

struct SharedWorldOptions {
  SceneWorldOptions models;
  double physics_dt_s = 0.001;           ///< body integration sub-step (support stiffness needs <= 2 ms)
  DeformationDeltaConfig delta;
  OwnershipConfig ownership;
  session::PeerContactsConfig peers;
  /// Free bodies are published while they move more than this per tick, and once when they stop.
  double rest_tolerance_m = 1e-5;
  /// When set: every published deformation also goes to DIR/<object>.json (the loads of the
  /// solve, the material, the fixed nodes and the field the receivers hold) with the
  /// tetrahedral mesh in DIR/<object>.inp, so the FEM can be checked independently.
  std::filesystem::path dump_dir;
};

struct TickOutput {
  std::vector<std::string> notes;               ///< lines for the server's log
  std::vector<OwnershipChange> ownership;
  std::vector<msg::ObjectState> states;
  std::vector<std::pair<std::string, DeformationSample>> deformations;  ///< object id, sample
};

class SharedWorld {
 public:
  using Clock = std::chrono::steady_clock;
  SharedWorld(std::string session, SharedWorldOptions options);
  ~SharedWorld();
  SharedWorld(const SharedWorld&) = delete;
  SharedWorld& operator=(const SharedWorld&) = delete;

  /// A new revision of the scene. Another world: contacts, owners and deformations start
  /// afresh. The same world (new gravity): bodies keep their poses and owners.
  void SetScene(const scene::Scene& scene);
  void OnContactSet(const msg::ContactSet& set, Clock::time_point now);
  void OnUserGone(const std::string& user, Clock::time_point now);
  /// A reader of deformations joined: the next tick sends keyframes.
  void RequestKeyframes();
  /// Advances to `now` (dt_s since the last tick, sub-stepped) and returns what to publish.
  TickOutput Tick(Clock::time_point now, double dt_s);

  bool ready() const { return models_ != nullptr; }
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
    bool touched_before = false;
    const PreparedDeformable* prepared = nullptr;
    double E_Pa = 0.0, nu = 0.0;
  };
  void Adopt(SceneWorld models, TickOutput& out);
  void Dump(const Deformable& d, std::uint32_t revision) const;

  std::string session_;
  SharedWorldOptions options_;
  scene::Scene scene_;
  std::unique_ptr<SceneWorld> models_;
  std::future<SceneWorld> loading_;
  std::string loading_scene_;
  Clock::time_point loading_since_{};
  session::PeerContacts peers_;
  OwnershipArbiter arbiter_;
  std::map<std::string, std::string> claims_;   // user -> object it claims ("" none)
  std::vector<Deformable> deformables_;
  std::vector<std::pair<contact::ObjectId, std::size_t>> moving_;  // object, scene index
  std::map<contact::ObjectId, Eigen::Vector3d> last_published_;     // free bodies
  std::vector<contact::RemoteContact> remote_;
  bool keyframes_requested_ = false;
};

}  // namespace handshare::world
