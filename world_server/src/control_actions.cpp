#include "handshare/world_server/control_actions.hpp"

#include <algorithm>
#include <cstdio>

namespace handshare::server {

namespace {
const scene::ControlSpec* FindControl(const scene::Scene& scene, const std::string& id) {
  for (const auto& c : scene.controls) {
    if (c.id == id) return &c;
  }
  return nullptr;
}
}  // namespace

scene::Scene LoadWorld(const std::string& name) { return scene::LoadSceneByName(name); }

ControlOutcome GoToWorld(scene::Scene& scene, const std::string& world, const std::string& by, const SceneLoader& load) {
  ControlOutcome out;
  try {
    scene = load(world);
  } catch (const std::exception& e) {
    out.notes.push_back(by + ": cannot go to '" + world + "': " + e.what());
    return out;
  }
  out.world_changed = out.revised = true;
  if (!scene.messages.empty()) out.boards.push_back(scene.messages);
  out.notes.push_back(by + ": scene '" + scene.name + "'");
  return out;
}

const scene::Action* ActionOf(const scene::Scene& scene, const ControlInput& input) {
  const scene::ControlSpec* spec = FindControl(scene, input.control_id);
  if (spec == nullptr) return nullptr;  // a control of a world already left
  return controls::ActionOf(*spec, input.kind, input.index);
}

ControlOutcome ApplyControlAction(scene::Scene& scene, const ControlInput& input, const SceneLoader& load) {
  ControlOutcome out;
  const scene::Action* found = ActionOf(scene, input);
  if (found == nullptr || found->empty()) return out;
  out.taken = true;
  // A copy: going to another world replaces the scene that holds the control and its action.
  const scene::Action action = *found;
  const std::string by = "control " + input.control_id + " by " + input.user;
  if (!action.goto_scene.empty()) {
    ControlOutcome went = GoToWorld(scene, action.goto_scene, by, load);
    went.taken = true;
    if (!went.world_changed) return went;
    out = std::move(went);
  }
  if (action.set_gravity) {
    scene.gravity_W_m_per_s2 = action.gravity_W_m_per_s2;
    out.revised = true;
    out.gravity_changed = !out.world_changed;
  }
  if (!action.title.empty()) {
    scene.title = action.title;
    out.revised = true;
  }
  if (action.set_gravity || !action.title.empty()) {
    char line[200];
    std::snprintf(line, sizeof line, "%s: gravity %.2f m/s^2, '%s'", by.c_str(), scene.gravity_W_m_per_s2.z(),
                  scene.title.c_str());
    out.notes.push_back(line);
  }
  if (!action.messages.empty()) out.boards.push_back(action.messages);
  return out;
}

std::vector<ControlStateRecord> InitialControlStates(const scene::Scene& scene, bool known) {
  std::vector<ControlStateRecord> out;
  for (const auto& c : scene.controls) {
    ControlStateRecord r;
    r.control_id = c.id;
    r.scene = scene.name;
    r.index = c.type == scene::ControlType::kLever ? 0 : -1;
    r.known = known;
    out.push_back(std::move(r));
  }
  return out;
}

bool IndexFits(const scene::ControlSpec& control, std::int32_t index) {
  switch (control.type) {
    case scene::ControlType::kLever: return index >= 0 && index < std::max(1, control.lever.detents);
    case scene::ControlType::kBook: return index >= -1 && index < control.book.pages;
    default: return index == -1;
  }
}

const ControlStateRecord* UpdateControlState(std::vector<ControlStateRecord>& states, const ControlInput& input) {
  auto it = std::find_if(states.begin(), states.end(), [&](const auto& r) { return r.control_id == input.control_id; });
  if (it == states.end()) return nullptr;
  ControlStateRecord next = *it;
  switch (input.kind) {
    case controls::EventKind::kPressed: next.engaged = true; break;
    case controls::EventKind::kReleased: next.engaged = false; break;
    case controls::EventKind::kMoved: next.index = input.index; break;
    case controls::EventKind::kOpened:
      next.engaged = true;
      next.index = 0;
      break;
    case controls::EventKind::kPageTurned: next.index = input.index; break;
    case controls::EventKind::kMissed: return nullptr;
    case controls::EventKind::kMoving: break;
  }
  const bool motion = input.kind == controls::EventKind::kMoving;
  next.moving = motion && input.index != 0;
  next.position = next.moving ? input.value : 0.0;
  if (motion && !it->known) return nullptr;  // motion of a control whose settled state is unknown
  if (it->known && next.index == it->index && next.engaged == it->engaged && next.moving == it->moving &&
      next.position == it->position) {
    return nullptr;
  }
  next.known = true;
  next.user = input.user;
  ++next.changes;
  *it = std::move(next);
  return &*it;
}

}  // namespace handshare::server
