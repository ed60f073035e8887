#pragma once
/// What the controls do to the session's scene: the one function the world server applies
/// every control event with (go to another world, change gravity, retitle the scene, show
/// messages on the board), over the scene alone. No DDS and no clock: the server turns the
/// outcome into samples (a new scene revision, board messages) and log lines.
///
/// Which action an event takes is controls::ActionOf's rule (scene files, docs/scenes.md): a
/// button's or arrow's `action` when pressed, a book's when it opens (else its first page's),
/// a book page's when turned to, a lever detent's when settled in. A control the current world
/// does not have (an event of a world already left) takes none.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "handshare/controls/controls.hpp"
#include "handshare/scene/scene.hpp"

namespace handshare::server {

/// A control event as the scene's logic sees it.
struct ControlInput {
  std::string control_id;
  controls::EventKind kind = controls::EventKind::kPressed;
  std::int32_t index = -1;  ///< lever detent, book page; moving: 1 moving, 0 at rest; -1 otherwise
  std::string user;         ///< who actuated it (for the log)
  double value = 0.0;       ///< the event's value (moving: where the control is)
};

/// What applying one control event did.
struct ControlOutcome {
  bool taken = false;            ///< the event had an action (possibly one that failed)
  bool world_changed = false;    ///< the scene is another world now
  bool revised = false;          ///< the scene changed (world, gravity or title): a new revision
  bool gravity_changed = false;  ///< same world, new gravity: its models need rebuilding
  /// Messages for the board, in the order shown: the new world's, then the action's own. Each
  /// entry is one board message in every language the scene has.
  std::vector<std::vector<scene::Message>> boards;
  std::vector<std::string> notes;        ///< lines for the server's log (errors included)
};

/// Loads a world by name (LoadWorld in the server; tests pass their own).
using SceneLoader = std::function<scene::Scene(const std::string& name)>;

/// `scene` becomes world `world` (a control's goto, or the operator's command; `by` names who
/// for the notes): the new world's messages for the board. A world that cannot be loaded
/// leaves the scene as it was, with a note saying why.
ControlOutcome GoToWorld(scene::Scene& scene, const std::string& world, const std::string& by, const SceneLoader& load);

/// What the server knows of one control of the current world: where the control events it
/// applied left it. Published on handshare/control_state so that every haptic node builds the
/// control there (also when a new revision of the same world rebuilds it: the lever that set
/// Mars' gravity stays in Mars' detent) and every screen can show it.
struct ControlStateRecord {
  std::string control_id;
  std::string scene;         ///< the world it belongs to
  std::int32_t index = -1;   ///< lever: detent (0 at rest); book: page (-1 shut); else -1
  bool engaged = false;      ///< button, arrow: pressed; book: open
  std::string user;          ///< who changed it last ("" = nobody since the world appeared)
  std::uint32_t changes = 0; ///< how many events changed it
  bool moving = false;       ///< a hand is moving it (kMoving reports), at `position`
  double position = 0.0;     ///< where that hand has it (button travel, lever or cover angle)
  /// false: where the control is is not known here (a server that resumed a killed one's
  /// session: the nodes still hold its last published states); nothing is published for it
  /// until an event, which is then published whatever it says.
  bool known = true;
};

/// The controls of `scene` as the world appears: levers in detent 0, books shut, buttons up
/// (known = false: the same records, their state unknown).
std::vector<ControlStateRecord> InitialControlStates(const scene::Scene& scene, bool known = true);

/// Whether `control` can be at `index` (ControlStateRecord::index): a lever in one of its
/// detents, a book shut (-1) or at one of its pages, any other control -1.
bool IndexFits(const scene::ControlSpec& control, std::int32_t index);

/// Applies `input` to the record of its control in `states` (events of controls not there, of
/// a world already left, change nothing; so do misses). A motion report (kMoving) sets where a
/// hand has the control (moving, position) or, at rest, clears it; a settled event clears it
/// too. Returns the record it changed, or nullptr. Apply it before the event's action: an action that changes the world replaces the
/// states with the new world's (InitialControlStates).
const ControlStateRecord* UpdateControlState(std::vector<ControlStateRecord>& states, const ControlInput& input);

/// The server's loader: scene::LoadSceneByName from the assets' scenes folder.
scene::Scene LoadWorld(const std::string& name);

/// The action `input` takes in `scene` (nullptr: none). The pointer is into `scene`.
const scene::Action* ActionOf(const scene::Scene& scene, const ControlInput& input);

/// Applies the action `input` takes to `scene`: another world first (through `load`; a world
/// that cannot be loaded leaves the scene as it was and says why in notes), then gravity and
/// title, then the messages (the new world's, then the action's own). Not real-time.
ControlOutcome ApplyControlAction(scene::Scene& scene, const ControlInput& input, const SceneLoader& load);

}  // namespace handshare::server
