#pragma once
/// What the operator's page shows, as plain data (no DDS types): filled by the console from the
/// session's topics, turned into the one JSON document every viewer receives (over the
/// WebSocket, and at GET /api/state). Not real-time.
#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "handshare/figure/hand_figure.hpp"
#include "handshare/scene/scene.hpp"

#include "handshare/controls/control_table.hpp"
#include "handshare/web_console/world_routes.hpp"

namespace handshare::web_console {

/// One station's loop, from its newest LoopStatistics sample: a haptic node's loop, a
/// screen's (graphics node's) frames, a guide's (audio guide's) board loop.
struct StationStats {
  std::string node;      ///< the sample's key, e.g. "haptic_node/alice"
  std::string user;      ///< the user part of node ("alice")
  std::string kind;      ///< the member kind of the node's user and program ("haptic", "graphics",
                         ///< "audio_guide"; KindOfNode until its member info came)
  std::string device;    ///< from the user's member info ("sim", "hiro", ...); "" if unknown
  double rate_Hz = 0.0;
  double jitter_p50_us = 0.0;
  double jitter_p99_us = 0.0;
  double step_p99_us = 0.0;
  std::uint64_t steps = 0;
  std::uint64_t overruns = 0;
  std::uint64_t resyncs = 0;
  std::uint64_t faults = 0;
  std::uint64_t samples_dropped = 0;
  std::uint64_t deadline_misses = 0;   ///< DDS deadlines missed, its readers' and writers'
  double sent_bytes_per_s = 0.0;       ///< what its writers wrote, over its last period
  std::chrono::steady_clock::time_point received;
};

struct MemberRow {
  std::string user;
  std::string kind;    ///< "world_server", "haptic", "graphics", "audio_guide"
  std::string device;
};

/// One object of the current world as the 3-D view draws it (the scene state's object, with the
/// scene file's mesh scale).
struct ViewObject {
  std::string id;
  std::string kind;                 ///< "rigid", "deformable", "control"
  std::string shape;                ///< "box", "sphere", "mesh"
  std::string mesh;                 ///< URL of its .glb ("/meshes/NAME.glb"); "" unless a mesh
  std::array<double, 3> p_WO_m{};
  std::array<double, 4> q_WO_wxyz{1, 0, 0, 0};
  std::array<double, 3> half_extent_m{};
  std::array<double, 3> mesh_scale{1, 1, 1};
  std::array<float, 3> rgb{};
};

/// One user's hand for the view: the hand base and the fingertips the device has, in W.
struct HandView {
  std::string user;
  std::array<double, 3> p_WH_m{};              ///< hand base H (the palm; fingers along +y of H, up +z)
  std::array<double, 4> q_WH_wxyz{1, 0, 0, 0};
  std::vector<int> fingers;                    ///< finger index of each tip (thumb 0)
  std::vector<std::array<double, 3>> p_WE_m;   ///< fingertip centres
  double fingertip_radius_m = 0.0;
  std::uint64_t stamp_ns = 0;                  ///< the device state's sender stamp (its steady clock)
  figure::DeviceHand device;                   ///< the device state's hand, all of it: its figure's input
};

/// A body of the current world that moves: its newest ObjectState pose, as the screens draw it.
struct BodyView {
  std::array<double, 3> p_WO_m{};
  std::array<double, 4> q_WO_wxyz{1, 0, 0, 0};
  std::string owner;  ///< the user who holds it, "" when the world server simulates it
  std::uint64_t stamp_ns = 0;  ///< the object state's sender stamp (its writer's steady clock)
};

/// A control of the current world in its state (the world server's ControlState), drawn as the
/// screens draw it (graphics_node's SceneReplica::DrawnPose): a lever turned about x of its
/// frame to its detent's angle, a pressed button or arrow down its travel along -z, while a hand
/// moves it where the hand has it; a book open at its page.
struct ControlView {
  std::string id;
  std::string type;          ///< "button", "arrow", "lever", "book"
  std::int32_t index = -1;   ///< lever: detent; book: page; -1 otherwise
  bool engaged = false;      ///< button, arrow: pressed; book: open
  bool moving = false;       ///< a hand moves it: drawn at position
  double position = 0.0;     ///< button travel [m], lever angle [rad], book cover angle [rad]
  std::string user;          ///< who changed it last
  std::array<double, 3> p_WO_m{};  ///< the pose it is drawn at
  std::array<double, 4> q_WO_wxyz{1, 0, 0, 0};
  std::array<double, 3> size_m{};  ///< a book's size (its frame C: the closed book's top at z = 0)
  std::map<std::string, std::string> page_text;  ///< an open book's page, by language
  /// An open book's picture on its left page: its URL ("/pictures/NAME.png", the scene file's
  /// image by its file name; the console serves the assets' images there); "" none.
  std::string page_picture;
};

/// The state of a control as the world server sent it (ControlState), before it is drawn.
struct ControlStateIn {
  std::int32_t index = -1;
  bool engaged = false;
  bool moving = false;
  double position = 0.0;
  std::string user;
};

/// `spec` in `state`, drawn from the pose the scene state gives it (p_WO_m, q_WO_wxyz), as
/// ControlView says. Book pages in every language of `languages`.
ControlView DrawnControl(const scene::ControlSpec& spec, const ControlStateIn& state,
                         const std::array<double, 3>& p_WO_m, const std::array<double, 4>& q_WO_wxyz,
                         const std::vector<std::string>& languages);

/// One mesh object's surface field for the view, fed by Deformation samples with the graphics
/// node's receiver rule (graphics_node's DeformationField): a keyframe of a revision not seen
/// last zeroes every vertex first; then u[node_ids[i]] = u_W_m[3i..3i+2]. Vertex v is the mesh's
/// vertex v as scene::LoadMesh reads it, which is the view's glTF vertex v (gltf_export.hpp).
class ViewField {
 public:
  explicit ViewField(std::size_t vertex_count) : u_W_m_(vertex_count, {0.0F, 0.0F, 0.0F}) {}
  /// Applies a sample. false (nothing changed) if u_W_m does not hold 3 values per node id; ids
  /// at or above the vertex count and non-finite displacements are skipped (and counted).
  bool Apply(std::uint32_t revision, bool keyframe, std::span<const std::uint32_t> node_ids,
             std::span<const float> u_W_m);
  std::size_t vertex_count() const { return u_W_m_.size(); }
  const std::vector<std::array<float, 3>>& u_W_m() const { return u_W_m_; }
  std::optional<std::uint32_t> revision() const { return revision_; }
  std::uint64_t skipped() const { return skipped_; }

 private:
  std::vector<std::array<float, 3>> u_W_m_;
  std::optional<std::uint32_t> revision_;
  std::uint64_t skipped_ = 0;
};

struct WorldView {
  bool known = false;   ///< a scene state has come
  std::string scene;
  std::string title;    ///< from the scene file, "" if the console cannot load it
  std::uint32_t revision = 0;
  double tick_Hz = 0.0;
  double gravity_z_m_per_s2 = 0.0;
  std::size_t objects = 0;
  std::vector<ViewObject> view;  ///< what the 3-D view draws
};

struct BoardView {
  std::uint32_t message_id = 0;
  std::string text;
  std::string next_action;
};

struct ConsoleState {
  std::string session;
  std::string console_name;
  bool actions_enabled = false;                  ///< a token is set (--token-file)
  WorldView world;
  std::vector<WorldRoute> routes;                ///< worlds the current one links to
  std::vector<std::string> worlds;               ///< every world the operator may send the session to
  std::map<std::string, BoardView> boards;       ///< by language
  std::map<std::string, StationStats> stations;  ///< by node
  std::map<std::string, MemberRow> members;      ///< by member id
  std::uint64_t samples_refused = 0;             ///< samples the console's checks dropped
  std::uint64_t viewers = 0;                     ///< WebSocket viewers now
  std::uint64_t viewers_dropped = 0;             ///< viewers dropped for not keeping up
  /// The paper's Table 4 by kind of control, from the control events heard since the console
  /// started (session_report's rule: handshare/controls/control_table.hpp).
  controls::KindTable table4;
  std::uint64_t control_events = 0;              ///< control events counted in it
};

/// The state as the page reads it (docs/web_console.md, "The state document"). Text from the
/// session that is not valid UTF-8 is replaced, not refused. `now` ages the stations.
std::string ToJson(const ConsoleState& state, std::chrono::steady_clock::time_point now);

/// The hands document the view reads ({"type": "hands", "hands": [...]}), sent apart from the
/// state and more often. Each hand carries its device state's stamp (a decimal string: 64 bits
/// are beyond JavaScript's exact integers) and its figure as the
/// screens draw it (figure::DrawnHand: the palm and the fingers' links, a HIRO II's hand with
/// `hiro_model` for users whose device is "hiro", a pen or a gripper), its boxes and spheres in
/// W rounded to 1 um (quaternions to 1e-6).
std::string HandsJson(const std::map<std::string, HandView>& hands,  // any key: the order of the list
                      const hiro::HiroModel* hiro_model = nullptr);

/// The moving bodies and the controls in their states ({"type": "bodies", "scene": ...,
/// "bodies": [{"id", "p_WO_m", "q_WO_wxyz", "owner", "stamp_ns" (a decimal string)}], "controls": [...]}), sent apart from
/// the state and as often as the hands.
std::string BodiesJson(const std::string& scene, const std::map<std::string, BodyView>& bodies,
                       const std::vector<ControlView>& controls);

/// The deformed meshes ({"type": "deformation", "scene": ..., "objects": [{"id", "revision",
/// "vertex_count", "ids": [v, ...], "u_um": [ux, uy, uz, ...]}]}): every vertex whose
/// displacement rounds to a non-zero number of micrometres, u in W in whole micrometres (0.5 um
/// at most off the sample's float; far below a pixel). Objects whose field is all zero are listed
/// with no ids, so that a view puts them back.
std::string DeformationJson(const std::string& scene, const std::map<std::string, ViewField>& fields);

/// The user of a station's node key: what follows the last '/', else the whole key.
std::string UserOfNode(const std::string& node);
/// The member kind of a station's program, by its node key's prefix: "haptic" (haptic_node/),
/// "graphics" (graphics_node/), "audio_guide" (audio_guide/), else "".
std::string KindOfNode(const std::string& node);

}  // namespace handshare::web_console
