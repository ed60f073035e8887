#include "handshare/world_server/object_authority.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "handshare/contact/finger_contact.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/session/contact_deadband.hpp"
#include "handshare/session/peer_contacts.hpp"

namespace handshare::server {

struct ObjectAuthority::BodyPlan {
  // Owned bodies: the owner, and its newest set when that set simulates the body (else null:
  // granted, and the owner has not taken it over yet).
  std::map<contact::ObjectId, std::pair<std::string, const session::PeerContacts::Entry*>> owned;
  // Held at rest this tick: a resumed session's body reserved for its owner's claim, or a body
  // handed over until its new owner simulates it.
  std::map<contact::ObjectId, Eigen::Isometry3d> at_rest;
  // Reserved for an owner's claim: not published (the claim decides, not this server).
  std::set<contact::ObjectId> reserved;
};

namespace {

// The owner's body velocity; zero when not finite or faster than any hand moves (a corrupt
// sample must not fling the body out of the world).
Eigen::Vector3d Velocity(const msg::ContactSet& s) {
  constexpr double kMaxSpeed_m_per_s = 20.0;
  const Eigen::Vector3d v = contact::AsVector(s.v_WO_m_per_s());
  return v.allFinite() && v.norm() <= kMaxSpeed_m_per_s ? v : Eigen::Vector3d::Zero();
}

/// Where an owner's body is at `now`: its newest set's pose (found trustworthy by
/// SimulatingSet), moved on at the set's velocity since the set arrived, for at most
/// session::kMaxReckoning_s (the first-order hold the owner's deadband assumes: it sends a set
/// only when the body leaves this reckoning).
Eigen::Isometry3d ReckonedPose(const session::PeerContacts::Entry& e, std::chrono::steady_clock::time_point now) {
  Eigen::Isometry3d X = contact::ToPose(e.set.p_WO_m(), e.set.q_WO_wxyz());
  const double age_s = std::chrono::duration<double>(now - e.received).count();
  X.translation() += Velocity(e.set) * std::clamp(age_s, 0.0, session::kMaxReckoning_s);
  return X;
}

/// `user`'s newest set when it reports simulating `id` at a pose to trust (contact::ToPose:
/// finite, a rotation), else nullptr.
const session::PeerContacts::Entry* SimulatingSet(const session::PeerContacts& peers, const std::string& user,
                                                  const std::string& id) {
  const auto it = peers.sets().find(user);
  Eigen::Isometry3d X_WO;
  if (it == peers.sets().end() || !it->second.set.simulating() ||
      it->second.set.simulated_object_id().to_string() != id ||
      !contact::ToPose(it->second.set.p_WO_m(), it->second.set.q_WO_wxyz(), X_WO)) {
    return nullptr;
  }
  return &it->second;
}

// The tetrahedral mesh of a published deformable, for an independent solve (Abaqus subset;
// ids = index + 1): DIR/<object>.inp (ObjectAuthorityOptions::dump_dir).
void DumpMesh(const std::filesystem::path& dir, const world::PreparedDeformable& prepared) {
  const auto& p = prepared.mesh->positions_m();
  std::filesystem::create_directories(dir);
  std::ofstream inp(dir / (prepared.object_id + ".inp"));
  inp.precision(17);
  inp << "*NODE\n";
  for (std::size_t n = 0; n < p.size(); ++n) {
    inp << n + 1 << ", " << p[n].x() << ", " << p[n].y() << ", " << p[n].z() << "\n";
  }
  inp << "*ELEMENT, TYPE=C3D4\n";
  std::size_t e = 0;
  for (const auto& t : prepared.mesh->tets()) {
    inp << ++e << ", " << t[0] + 1 << ", " << t[1] + 1 << ", " << t[2] + 1 << ", " << t[3] + 1 << "\n";
  }
}

}  // namespace

ObjectAuthority::ObjectAuthority(std::string session, ObjectAuthorityOptions options, common::SessionClock clock)
    : session_(std::move(session)), options_(std::move(options)), clock_(clock),
      peers_(std::make_unique<session::PeerContacts>(session::PeerContactsConfig{
          std::chrono::nanoseconds(options_.peers.fade_after_ns), std::chrono::nanoseconds(options_.peers.lifespan_ns)})),
      arbiter_(options_.ownership) {}

ObjectAuthority::~ObjectAuthority() {
  if (loading_.valid()) loading_.wait();
  for (auto& build : superseded_) build.future.wait();
}

void ObjectAuthority::SetScene(const scene::Scene& scene) {
  const bool same_world = scene.name == scene_.name;
  scene_ = scene;
  if (!same_world) {
    // Another world: nothing of the old one carries over (a resumed session's held bodies are
    // for the world it resumed in, which the first SetScene names).
    if (models_) reserved_.clear();
    models_.reset();
    ready_scene_.clear();
    deformables_.clear();
    scripted_ = {};
    last_published_.clear();
    arbiter_.Clear();
    claims_.clear();
    handing_over_.clear();
    peer_fade_ = {};
    peers_->Clear();
  }
  // A build in flight is superseded, not waited for: the tick goes on, and its models are
  // dropped when it finishes (Tick reaps it).
  if (loading_.valid()) superseded_.push_back({loading_scene_, std::move(loading_)});
  loading_scene_ = scene.name;
  loading_since_ = Clock::now();
  auto options = options_.models;
  loading_ = std::async(std::launch::async, [scene, options] { return world::BuildSceneModels(scene, options); });
}

void ObjectAuthority::OnContactSet(const msg::ContactSet& set, Clock::time_point now) {
  const std::string user = set.user().to_string();
  if (user.empty() || set.session().to_string() != session_) return;
  peers_->Receive(set, now);
  const std::string claim = set.grasped_object_id().to_string();
  std::string& previous = claims_[user];
  if (!previous.empty() && previous != claim) arbiter_.Report(user, previous, false, now);
  if (!claim.empty()) arbiter_.Report(user, claim, true, now);
  previous = claim;
}

void ObjectAuthority::OnUserGone(const std::string& user, Clock::time_point now) {
  arbiter_.OnUserGone(user, now);
  claims_.erase(user);
}

void ObjectAuthority::PlaceBody(const std::string& object_id, const Eigen::Isometry3d& X_WO, const std::string& owner,
                                Clock::duration grace) {
  placed_[object_id] = X_WO;
  if (!owner.empty()) reserved_[object_id] = {owner, grace, X_WO, std::nullopt};
}

void ObjectAuthority::RequestKeyframes() {
  keyframes_requested_ = true;
  for (auto& d : deformables_) d.delta->RequestKeyframe();
}

void ObjectAuthority::ReapSuperseded(TickOutput& out) {
  std::erase_if(superseded_, [&](SupersededBuild& build) {
    if (build.future.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return false;
    try {
      build.future.get();
      out.notes.push_back("models of '" + build.scene + "' dropped: a newer scene revision came while they were built");
    } catch (const std::exception& e) {
      out.notes.push_back("models of '" + build.scene + "' (superseded) failed: " + e.what());
    }
    return true;
  });
}

void ObjectAuthority::Adopt(world::SceneModels models, TickOutput& out) {
  const bool carry = models_ != nullptr;  // same world, new revision: bodies stay where they are
  if (carry) {
    for (const auto body : models_->dynamic_bodies) {
      const auto id = models.Find(models_->ids[static_cast<std::size_t>(body)]);
      if (id >= 0) models.world->SetPose(id, models_->world->pose(body));
    }
  }
  for (const auto& [id, X] : placed_) {
    const auto body = models.Find(id);
    if (body >= 0 && std::find(models.dynamic_bodies.begin(), models.dynamic_bodies.end(), body) !=
                         models.dynamic_bodies.end()) {
      models.world->SetPose(body, X);
      out.notes.push_back("object '" + id + "' placed where the session left it");
    }
  }
  placed_.clear();
  std::erase_if(reserved_, [&](const auto& r) { return models.Find(r.first) < 0; });
  models_ = std::make_unique<world::SceneModels>(std::move(models));
  ready_scene_ = scene_.name;
  deformables_.clear();
  last_published_.clear();
  remote_.assign(static_cast<std::size_t>(64), contact::FingerContact{});
  scripted_ = world::ScriptedMotion(scene_, *models_);
  for (const auto& prepared : models_->deformables) {
    Deformable d;
    d.id = prepared.object_id;
    d.object = models_->Find(d.id);
    d.prepared = &prepared;
    const scene::SceneObject* o = nullptr;
    for (const auto& so : scene_.objects) {
      if (so.id == d.id) o = &so;
    }
    if (o == nullptr || d.object < 0 || !prepared.compliance) continue;
    d.E_Pa = o->deformable.E_Pa;
    d.nu = o->deformable.nu;
    if (o->beat.active() && prepared.mode_O_m) d.beat = o->beat;
    // Published node ids: the scene mesh's vertices, which the tetrahedral mesh keeps first.
    const auto& p = prepared.mesh->positions_m();
    std::int32_t vertices = prepared.mesh->num_nodes();
    if (o->mesh) {
      vertices = static_cast<std::int32_t>(o->mesh->vertices_m.size());
      bool kept = vertices <= prepared.mesh->num_nodes();
      for (std::int32_t v = 0; kept && v < vertices; ++v) {
        kept = (p[static_cast<std::size_t>(v)] - o->mesh->vertices_m[static_cast<std::size_t>(v)]).norm() <= 1e-9;
      }
      if (!kept) {
        out.notes.push_back("deformable '" + d.id + "': its tetrahedral mesh does not keep the scene mesh's vertices "
                            "first; its deformation is not published");
        continue;
      }
    }
    const auto& compliance = *prepared.compliance;
    d.vertex_count = vertices;
    d.vertex_of_slot.assign(static_cast<std::size_t>(compliance.num_nodes()), -1);
    for (std::int32_t s = 0; s < compliance.num_nodes(); ++s) {
      const std::int32_t node = compliance.nodes()[static_cast<std::size_t>(s)];
      if (node < vertices) d.vertex_of_slot[static_cast<std::size_t>(s)] = node;
    }
    d.u_slots.assign(static_cast<std::size_t>(compliance.num_nodes()), Eigen::Vector3d::Zero());
    d.u_W.assign(3 * static_cast<std::size_t>(vertices), 0.0);
    d.u_O.assign(static_cast<std::size_t>(vertices), Eigen::Vector3d::Zero());
    d.delta = std::make_unique<DeformationDelta>(static_cast<std::size_t>(vertices), options_.delta);
    deformables_.push_back(std::move(d));
    if (!options_.dump_dir.empty()) DumpMesh(options_.dump_dir, prepared);
  }
  std::ostringstream note;
  note << "models of '" << scene_.name << "' ready in "
       << std::chrono::duration<double>(Clock::now() - loading_since_).count() << " s: "
       << models_->dynamic_bodies.size() << " dynamic bodies, " << deformables_.size() << " published deformables";
  out.notes.push_back(note.str());
}

TickOutput ObjectAuthority::Tick(Clock::time_point now, double dt_s) {
  TickOutput out;
  AdoptModels(out);
  ArbitrateOwnership(now, out);
  if (!models_) return out;
  const BodyPlan plan = PlanBodies(now, out);
  const std::size_t remote = GatherPeerContacts(now, dt_s);
  MoveScriptedObjects(now);
  StepWorld(plan, now, dt_s, remote);
  PublishBodies(plan, now, out);
  PublishFields(now, out);
  keyframes_requested_ = false;
  return out;
}

void ObjectAuthority::AdoptModels(TickOutput& out) {
  ReapSuperseded(out);
  if (loading_.valid() && loading_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    try {
      Adopt(loading_.get(), out);
    } catch (const std::exception& e) {
      out.notes.push_back("cannot build the models of '" + loading_scene_ + "': " + e.what());
    }
  }
}

void ObjectAuthority::ArbitrateOwnership(Clock::time_point now, TickOutput& out) {
  peers_->Expire(now);
  out.ownership = arbiter_.Update(now);
  for (const auto& change : out.ownership) {
    if (change.reason == OwnershipReason::kHandedOver) {
      handing_over_[change.object_id] = {change.previous_owner, std::nullopt};
    } else {
      handing_over_.erase(change.object_id);
    }
  }
}

ObjectAuthority::BodyPlan ObjectAuthority::PlanBodies(Clock::time_point now, TickOutput& out) {
  // Owned bodies follow their owner's newest reported pose; a resumed session's bodies held for
  // their owner's claim stay where the log left them.
  const auto& world = *models_->world;
  BodyPlan plan;
  for (const auto body : models_->dynamic_bodies) {
    const std::string& id = models_->ids[static_cast<std::size_t>(body)];
    const std::string owner = arbiter_.owner(id);
    if (const auto r = reserved_.find(id); r != reserved_.end()) {
      if (!r->second.until) r->second.until = now + r->second.grace;
      if (!owner.empty() || now >= *r->second.until) {
        if (owner.empty()) out.notes.push_back("object '" + id + "': no claim from '" + r->second.owner + "', free");
        reserved_.erase(r);
      } else {
        plan.at_rest[body] = r->second.X_WO;
        plan.reserved.insert(body);
        continue;
      }
    }
    if (owner.empty()) continue;
    const session::PeerContacts::Entry* set = SimulatingSet(*peers_, owner, id);
    plan.owned[body] = {owner, set};
    if (set != nullptr) {
      handing_over_.erase(id);  // the new owner simulates it
    } else if (const auto h = handing_over_.find(id); h != handing_over_.end()) {
      // Handed over, and the new owner has not taken it over yet: it is in that owner's grasp,
      // so it stays where the last owner left it instead of falling for the round trip.
      if (!h->second.X_WO) {
        const session::PeerContacts::Entry* last = SimulatingSet(*peers_, h->second.from, id);
        h->second.X_WO = last != nullptr ? ReckonedPose(*last, now) : world.pose(body);
      }
      plan.at_rest[body] = *h->second.X_WO;
    }
  }
  return plan;
}

std::size_t ObjectAuthority::GatherPeerContacts(Clock::time_point now, double dt_s) {
  auto& world = *models_->world;
  // The users' fingertips on deformables: one solve with everybody. (Rigid bodies need none:
  // whoever touches a body claims it and simulates it; a free body only falls and rests.)
  // Faded as the haptic nodes fade them, and coming back at the fade's rate as they do
  // (contact::PeerWeights), so the published field is the one the nodes' solves have.
  received_.clear();
  peers_->ForEach(*models_, now, [&](const contact::PeerContact& c, const msg::ContactSet&) {
    if (world.contact_solver(c.contact.object) != nullptr) received_.push_back(c);
  });
  return peer_fade_.Step(received_, peers_->fade(), dt_s, session::PeerContacts::SteadyNs(now), remote_);
}

void ObjectAuthority::MoveScriptedObjects(Clock::time_point now) {
  auto& world = *models_->world;
  const double motion_t =
      clock_.At_s(static_cast<std::uint64_t>(std::chrono::nanoseconds(now.time_since_epoch()).count()));
  scripted_.Apply(world, motion_t);
}

void ObjectAuthority::StepWorld(const BodyPlan& plan, Clock::time_point now, double dt_s, std::size_t remote) {
  auto& world = *models_->world;
  const int substeps = std::clamp(static_cast<int>(std::lround(dt_s / options_.physics_dt_s)), 1, 100);
  const double h = dt_s / substeps;
  for (int s = 0; s < substeps; ++s) {
    for (const auto& [body, X] : plan.at_rest) {
      world.SetPose(body, X);
      world.SetVelocity(body, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    }
    for (const auto& [body, who] : plan.owned) {
      if (who.second == nullptr) continue;
      // At the owner's pose, with its velocity: when the owner lets go, the body flies on
      // from there instead of stopping in mid-air.
      world.SetPose(body, ReckonedPose(*who.second, now));
      world.SetVelocity(body, Velocity(who.second->set), Eigen::Vector3d::Zero());
    }
    const std::size_t n = s + 1 < substeps ? 0 : remote;  // deformables: once per tick
    // No hand of its own: the server steps the others' contacts and its bodies only.
    world.Step(h, std::span<const Eigen::Vector3d>{}, std::span<const contact::FingerContact>(remote_.data(), n));
  }
}

void ObjectAuthority::PublishBodies(const BodyPlan& plan, Clock::time_point now, TickOutput& out) {
  const auto& world = *models_->world;
  // Rigid bodies to publish: owned ones at their owner's pose, free ones while they move, and
  // every one when a spectator joins and once per refresh period.
  const bool refresh = keyframes_requested_ || (options_.pose_refresh_period.count() > 0 && now >= next_pose_refresh_);
  if (refresh) next_pose_refresh_ = now + std::chrono::duration_cast<Clock::duration>(options_.pose_refresh_period);
  for (const auto body : models_->dynamic_bodies) {
    const std::string& id = models_->ids[static_cast<std::size_t>(body)];
    if (plan.reserved.count(body) != 0) continue;  // its owner's claim decides, not this server
    if (const auto it = plan.owned.find(body); it != plan.owned.end()) {
      if (it->second.second == nullptr) {
        // Granted, and the owner has not taken it over yet: tell it where the body is.
        if (const auto still = plan.at_rest.find(body); still != plan.at_rest.end()) {
          out.bodies.push_back({id, it->second.first, still->second, Eigen::Vector3d::Zero()});
        } else {
          out.bodies.push_back({id, it->second.first, world.pose(body), world.body_velocity_W(body)});
        }
      } else {
        const auto& entry = *it->second.second;
        out.bodies.push_back({id, it->second.first, ReckonedPose(entry, now), Velocity(entry.set)});
      }
      last_published_.erase(body);  // once free, its first pose is published
      continue;
    }
    const Eigen::Isometry3d X = world.pose(body);
    const auto last = last_published_.find(body);
    if (last != last_published_.end() && (last->second - X.translation()).norm() <= options_.rest_tolerance_m &&
        !refresh) {
      continue;
    }
    last_published_[body] = X.translation();
    out.bodies.push_back({id, "", X, world.body_velocity_W(body)});
  }
  for (const auto& m : scripted_.moving()) {
    out.bodies.push_back({m.id, "", world.pose(m.object), Eigen::Vector3d::Zero()});
  }
}

void ObjectAuthority::PublishFields(Clock::time_point now, TickOutput& out) {
  const auto& world = *models_->world;
  // The surface field of every touched or beating deformable (and once more after a touch): a
  // beat's s M at every vertex plus the fingertips' field.
  for (auto& d : deformables_) {
    const fem::ContactSolver* solver = world.contact_solver(d.object);
    if (solver == nullptr) continue;
    const bool touched = solver->num_unique() > 0;
    if (touched || d.touched_before || keyframes_requested_ || d.beat) {
      if (touched) {
        solver->SurfaceDisplacements(d.u_slots);
      } else {
        std::fill(d.u_slots.begin(), d.u_slots.end(), Eigen::Vector3d::Zero());
      }
      const double beat = world.mode_scale(d.object);
      for (std::size_t v = 0; v < d.u_O.size(); ++v) {
        d.u_O[v] = d.beat ? Eigen::Vector3d(beat * (*d.prepared->mode_O_m)[v]) : Eigen::Vector3d::Zero();
      }
      for (std::size_t s = 0; s < d.u_slots.size(); ++s) {
        const std::int32_t v = d.vertex_of_slot[s];
        if (v >= 0) d.u_O[static_cast<std::size_t>(v)] += d.u_slots[s];
      }
      const Eigen::Matrix3d R = world.pose(d.object).linear();
      for (std::size_t v = 0; v < d.u_O.size(); ++v) {
        const Eigen::Vector3d u = R * d.u_O[v];
        for (int k = 0; k < 3; ++k) d.u_W[3 * v + static_cast<std::size_t>(k)] = u[k];
      }
      const auto samples = d.delta->Update(d.u_W, now);
      for (const auto& sample : samples) out.deformations.emplace_back(d.id, sample);
      if (!samples.empty() && !options_.dump_dir.empty()) Dump(d, samples.front().revision, now);
    }
    d.touched_before = touched;
  }
}

void ObjectAuthority::Dump(const Deformable& d, std::uint32_t revision, Clock::time_point now) const {
  const fem::ContactSolver* solver = models_->world->contact_solver(d.object);
  const Eigen::Isometry3d X_WO = models_->world->pose(d.object);
  const Eigen::Matrix3d R = X_WO.linear();
  std::set<std::string> users;
  // The fingertips on it as the solve took them: the force each user's own solve gave its
  // fingertip (what it felt, before the device's clamp), the contact point, imposed displacement
  // and normal its set carried, and the fade's weight on it.
  std::ostringstream contacts;
  contacts.precision(17);
  bool first_contact = true;
  peers_->ForEach(*models_, now, [&](const contact::PeerContact& c, const msg::ContactSet& set) {
    const contact::FingerContact& fc = c.contact;
    if (fc.object != d.object) return;
    users.insert(set.user().to_string());
    const auto triple = [&](const char* name, const Eigen::Vector3d& v) {
      contacts << ", \"" << name << "\": [" << v[0] << ", " << v[1] << ", " << v[2] << "]";
    };
    contacts << (first_contact ? "" : ",\n  ") << "{\"user\": \"" << set.user().to_string()
             << "\", \"finger\": " << fc.finger;
    // In W as the body is here now, as the file always gave them (the felt force: minus the
    // force on the object).
    triple("f_E_W_N", R * -contact::AsVector(fc.f_O_N));
    triple("p_W_m", X_WO * contact::AsVector(fc.p_OC_m));
    triple("u_W_m", R * contact::AsVector(fc.u_O_m));
    triple("n_W", R * contact::AsVector(fc.n_O));
    contacts << ", \"weight\": " << peers_->fade().WeightAt(session::PeerContacts::SteadyNs(now), c.received_ns) << "}";
    first_contact = false;
  });
  std::ostringstream j;
  j.precision(17);
  j << "{\"object\": \"" << d.id << "\", \"scene\": \"" << scene_.name << "\", \"revision\": " << revision
    << ", \"E_Pa\": " << d.E_Pa << ", \"nu\": " << d.nu << ", \"mesh\": \"" << d.id << ".inp\",\n \"users\": [";
  bool first = true;
  for (const auto& u : users) {
    j << (first ? "" : ", ") << "\"" << u << "\"";
    first = false;
  }
  j << "],\n \"contacts\": [" << contacts.str() << "],\n \"R_WO\": [";
  for (int r = 0; r < 3; ++r) j << (r ? ", " : "") << "[" << R(r, 0) << ", " << R(r, 1) << ", " << R(r, 2) << "]";
  j << "],\n \"fixed_nodes\": [";
  first = true;
  for (const auto n : d.prepared->fixed_nodes) {
    j << (first ? "" : ", ") << n + 1;
    first = false;
  }
  // The load case for an independent static solve: each held node's displacement (in O) imposed,
  // and a beating body's driven nodes where the beat has them. Nothing else is loaded, so the
  // solution is the same field; the reactions at the held nodes are the loads.
  const double beat = d.beat ? models_->world->mode_scale(d.object) : 0.0;
  auto mode_at = [&](std::int32_t node) -> Eigen::Vector3d {
    return d.beat ? Eigen::Vector3d(beat * (*d.prepared->mode_O_m)[static_cast<std::size_t>(node)])
                             : Eigen::Vector3d::Zero();
  };
  j << "],\n \"beat_scale\": " << beat << ", \"driven_nodes\": " << d.prepared->driven_nodes.size();
  j << ",\n \"imposed\": [";
  first = true;
  for (const auto& load : solver->loads()) {
    const auto node = d.prepared->compliance->nodes()[static_cast<std::size_t>(load.slot)];
    const Eigen::Vector3d u = d.u_slots[static_cast<std::size_t>(load.slot)] + mode_at(node);
    j << (first ? "" : ",\n  ") << "{\"node\": " << node + 1 << ", \"u_m\": [" << u.x() << ", " << u.y() << ", " << u.z() << "]}";
    first = false;
  }
  for (const auto node : d.prepared->driven_nodes) {
    const Eigen::Vector3d u = mode_at(node);
    j << (first ? "" : ",\n  ") << "{\"node\": " << node + 1 << ", \"u_m\": [" << u.x() << ", " << u.y() << ", " << u.z() << "]}";
    first = false;
  }
  j << "],\n \"loads\": [";
  first = true;
  for (const auto& load : solver->loads()) {
    const auto node = d.prepared->compliance->nodes()[static_cast<std::size_t>(load.slot)];
    j << (first ? "" : ",\n  ") << "{\"node\": " << node + 1 << ", \"f_N\": [" << load.f_N.x() << ", " << load.f_N.y()
      << ", " << load.f_N.z() << "]}";
    first = false;
  }
  j << "],\n \"threshold_m\": " << options_.delta.threshold_m << ",\n \"sent_u_W_m\": {";
  first = true;
  const auto sent = d.delta->sent();
  for (std::size_t v = 0; v < sent.size() / 3; ++v) {
    if (sent[3 * v] == 0.0 && sent[3 * v + 1] == 0.0 && sent[3 * v + 2] == 0.0) continue;
    j << (first ? "" : ", ") << "\"" << v << "\": [" << sent[3 * v] << ", " << sent[3 * v + 1] << ", " << sent[3 * v + 2] << "]";
    first = false;
  }
  j << "}}\n";
  const auto file = options_.dump_dir / (d.id + ".json");
  const auto tmp = options_.dump_dir / (d.id + ".json.tmp");
  {
    std::ofstream f(tmp);
    f << j.str();
  }
  std::filesystem::rename(tmp, file);
}

}  // namespace handshare::server
