#pragma once
/// Scenes as data: a world (objects, gravity, controls) and its message-board texts, loaded from
/// JSON files in assets/scenes/. No middleware, no rendering: plain data that the world server
/// publishes and the haptic and graphics nodes use. Not real-time: load at setup or on a loader
/// thread.
///
/// Scene file format (all units SI; frames: W world, O object, C control; the full reference
/// with examples is docs/scenes.md):
///
///   name (string, required)        the scene's name, equal to the file's stem
///   title (string)                 shown on screen; default: name
///   gravity_m_per_s2 [3]           default [0, 0, -9.81]
///   note (string)                  free text, ignored (allowed in objects, materials, controls)
///   objects [ {                    at most 64
///     id (1..63 chars, unique among objects and controls), kind: rigid | deformable
///     shape: sphere (radius_m) | box (half_extent_m [3]) | mesh (mesh, mesh_scale)
///     mesh: path relative to the assets folder (the parent of the scene file's folder), or
///           absolute; OBJ, STL or PLY read with assimp; mesh_scale: number or [3], default 1
///     position_m [3] (required), orientation_wxyz [4] (unit), mass_kg, rgb [3] in 0..1
///     material: rigid      {stiffness_N_per_m, damping_N_s_per_m, mu_static, mu_kinetic}
///               deformable {E_Pa, nu, density_kg_per_m3, mu_static, mu_kinetic, stiffening_table}
///               (required for deformables; mu: fingertip friction, default 0 = frictionless)
///     fixed (deformables, required): {below_m} | {plane_point_m [3], plane_normal [3]} |
///           {nodes [indices]}: nodes of the tetrahedral mesh held fixed, in frame O
///     motion: {direction [3], amplitude_m, period_s, phase_rad}: p_WO(t) = position_m +
///           amplitude_m sin(2 pi t / period_s + phase_rad) direction
///     beat (deformables): {driven: {plane_point_m [3], plane_normal [3]} | {nodes [indices]},
///           displacement_m [3], rotation_rad [3], center_m [3], period_s, phase_rad}: each
///           driven node p (those of the rule that are not fixed) moves by
///           sin(2 pi t / period_s + phase_rad) (displacement_m + rotation_rad x (p - center_m))
///           (frame O; rotation_rad a small rotation vector, both default 0, not both 0), the
///           fixed ones stay, and the body deforms between them (its static response,
///           world::PreparedDeformable::mode_O_m); a fingertip presses the beating body
//////     label [ {language: en | ja, text} ]: shown beside the object on screens (1..127 bytes)
///     appearance: {specular 0..1, shininess 1..128, opacity 0.05..1}: how screens light it
///           (a highlight's strength and tightness; below 1, seen through), default matte, opaque
///   } ]
///   controls [ {                   at most 32; each also appears in `objects` as kind control
///     id, type: button | arrow | lever | book, position_m, orientation_wxyz, size_m [3], rgb,
///     mesh, mesh_scale (visual only), approach_margin_m, max_force_N, label (as for objects),
///     button/arrow: travel_m, click_at_m, release_at_m, stiffness_N_per_m, preload_N,
///                   click_drop (0..1), stop_stiffness_N_per_m, action
///     lever: min_angle_rad, max_angle_rad, detents (>= 2), detent_torque_N_m,
///            settle_rate_rad_per_s, stop_stiffness_N_per_m, detent_actions [one per detent]
///     book: pages, open_angle_rad, swipe_m, surface_stiffness_N_per_m, page_drag_N,
///           action (on opening; default: the first page's)
///           pages: a count (blank pages, actions in page_actions [index = page number]) or
///           [ {text [ {language: en | ja, text} ], image, action} ], at most 64: what each
///           spread shows (image: a PNG relative to the assets folder, on the left page; the
///           text in the reader's language on the right) and the action turning to it takes
///   } ]
///   action: {goto: scene name} and/or {set_gravity [3], title, messages [...]}
///   messages [ {language: en | ja, text, next_action, reading} ]   (required, non-empty)
///     reading: what the audio guide speaks for ja, text and next action in kana (eSpeak NG's
///              ja voice says "Chinese letter" for a kanji); required for ja, without kanji; not for en
///
/// Every error names the file, the line and the field: "dinosaur.json:12: field
/// 'objects[1].material.E_Pa': value -3 outside [100, 1e+12]".
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace handshare::scene {

/// A scene file (or one of its meshes) that cannot be used; what() names the file, the line and
/// the field, and the mesh path for mesh errors.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// kControl objects are the visuals of Scene::controls (added by the loader, not written in
/// `objects`).
enum class ObjectKind { kRigid, kDeformable, kControl };
enum class Shape { kSphere, kBox, kMesh };

/// A triangle surface: vertices and outward-oriented triangles (counter-clockwise seen from
/// outside).
struct Mesh {
  std::vector<Eigen::Vector3d> vertices_m;
  std::vector<std::array<std::int32_t, 3>> triangles;
};

/// Contact and friction of a rigid object (penalty contact with the fingertip proxies).
struct RigidMaterial {
  double stiffness_N_per_m = 3000.0;
  double damping_N_s_per_m = 2.0;
  double mu_static = 0.8;
  double mu_kinetic = 0.6;
};

/// Linear elastic material of a deformable object.
struct DeformableMaterial {
  double E_Pa = 0.0;
  double nu = 0.45;
  double density_kg_per_m3 = 1000.0;
  /// Coulomb friction of a fingertip on the skin (contact::DeformableDesc): 0 = frictionless.
  double mu_static = 0.0;
  double mu_kinetic = 0.0;
  /// The large-deformation correction's table (fem::ReadStiffeningSamples; docs/fem.md, "A
  /// correction beyond the paper"), resolved like a mesh; empty = the linear model's force.
  std::string stiffening_table_uri;
  std::filesystem::path stiffening_table_path;
};

/// Which nodes of a deformable's tetrahedral mesh are fixed (Dirichlet boundary).
struct FixedRule {
  enum class Kind { kNone, kHalfSpace, kNodes };
  Kind kind = Kind::kNone;
  Eigen::Vector3d point_O_m = Eigen::Vector3d::Zero();   ///< kHalfSpace: a point on the plane.
  Eigen::Vector3d normal_O = Eigen::Vector3d::UnitZ();   ///< kHalfSpace: unit, towards free side.
  std::vector<std::int32_t> nodes;                       ///< kNodes: node indices.
  /// kHalfSpace: true if p_O is on or behind the plane ((p - point) . normal <= 0).
  bool FixesPoint(const Eigen::Vector3d& p_O_m) const noexcept {
    return kind == Kind::kHalfSpace && (p_O_m - point_O_m).dot(normal_O) <= 0.0;
  }
};

/// Periodic translation of an object (the Daphnia's swimming motion).
struct Motion {
  Eigen::Vector3d direction_W = Eigen::Vector3d::UnitZ();  ///< unit.
  double amplitude_m = 0.0;
  double period_s = 0.0;  ///< 0: no motion.
  double phase_rad = 0.0;
  bool active() const noexcept { return period_s > 0.0 && amplitude_m != 0.0; }
  /// Offset of the object origin from its rest position at session time t_s [m], in W (t_s on
  /// the session clock every node agrees on: common::SessionClock).
  Eigen::Vector3d Offset_W(double t_s) const noexcept;
};

/// A periodic deformation of a deformable (the Daphnia's body and spine beating as it swims):
/// the `driven` nodes move by Scale(t) displacement_O_m while the fixed nodes stay; the rest of
/// the body follows by linear elasticity (its static response to that motion).
struct Beat {
  FixedRule driven;  ///< which nodes are driven (a node also fixed stays fixed).
  /// A driven node's displacement at Scale = 1, frame O: a translation plus a small rotation
  /// (rotation vector, linearised) about center_O_m.
  Eigen::Vector3d displacement_O_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation_O_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d center_O_m = Eigen::Vector3d::Zero();
  double period_s = 0.0;  ///< 0: no beat.
  double phase_rad = 0.0;
  bool active() const noexcept {
    return period_s > 0.0 && (displacement_O_m.squaredNorm() > 0.0 || rotation_O_rad.squaredNorm() > 0.0);
  }
  /// Where the beat puts a driven node at p_O_m, at Scale = 1 (frame O).
  Eigen::Vector3d DrivenDisplacement_O(const Eigen::Vector3d& p_O_m) const noexcept {
    return displacement_O_m + rotation_O_rad.cross(p_O_m - center_O_m);
  }
  /// sin(2 pi t_s / period_s + phase_rad) at session time t_s (common::SessionClock); 0 if not
  /// active.
  double Scale(double t_s) const noexcept;
};

/// How screens light an object beyond its colour: a white highlight of `specular` strength and
/// `shininess` tightness (the Phong exponent), and its opacity (below 1 it is seen through).
struct Appearance {
  double specular = 0.0;
  double shininess = 32.0;
  double opacity = 1.0;
};

/// A short text in several languages (a book page's text, an object's label).
struct LocalText {
  std::string language;  ///< en | ja
  std::string text;      ///< UTF-8
};
/// The text in `language`, else the English one, else the first; "" if there is none.
const std::string& TextIn(const std::vector<LocalText>& texts, const std::string& language) noexcept;

struct SceneObject {
  std::string id;
  ObjectKind kind = ObjectKind::kRigid;
  Shape shape = Shape::kSphere;
  std::string mesh_uri;                               ///< as written in the file (Shape::kMesh)
  std::filesystem::path mesh_path;                    ///< mesh_uri resolved to a file
  Eigen::Vector3d mesh_scale = Eigen::Vector3d::Ones();
  std::shared_ptr<const Mesh> mesh;                   ///< loaded, scaled, in frame O
  Eigen::Vector3d p_WO_m = Eigen::Vector3d::Zero();   ///< object origin O in world W
  Eigen::Quaterniond q_WO = Eigen::Quaterniond::Identity();
  /// box: half sizes; sphere: radius in x; mesh: half sizes of the mesh's bounding box in O
  /// (centred at mesh_center_O_m).
  Eigen::Vector3d half_extent_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d mesh_center_O_m = Eigen::Vector3d::Zero();
  double mass_kg = 0.0;
  std::array<float, 3> rgb{0.7f, 0.7f, 0.7f};
  RigidMaterial rigid;                                ///< kRigid
  DeformableMaterial deformable;                      ///< kDeformable
  FixedRule fixed;                                    ///< kDeformable
  Motion motion;
  Beat beat;                                          ///< kDeformable
  std::vector<LocalText> label;                       ///< shown beside it on screens (may be empty)
  Appearance appearance;                              ///< how screens light it
  int line = 0;                                       ///< line of the entry in the scene file

  Eigen::Isometry3d X_WO() const {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = q_WO.toRotationMatrix();
    X.translation() = p_WO_m;
    return X;
  }
};

struct Message {
  std::string language;  // "en", "ja"
  std::string text;
  std::string next_action;
  std::string reading;   // ja: text and next action in kana, as spoken; "" for en
};

/// What a control does when it is actuated. Empty fields change nothing.
struct Action {
  std::string goto_scene;                 ///< switch to this scene
  bool set_gravity = false;
  Eigen::Vector3d gravity_W_m_per_s2 = Eigen::Vector3d::Zero();
  std::string title;                      ///< new title of the current scene
  std::vector<Message> messages;          ///< new message board
  bool empty() const noexcept {
    return goto_scene.empty() && !set_gravity && title.empty() && messages.empty();
  }
};

enum class ControlType { kButton, kArrow, kLever, kBook };

/// One spread of a book as the scene file gives it: a picture on the left page, text on the
/// right (graphics nodes draw it while the book is open at it).
struct BookPage {
  std::vector<LocalText> text;        ///< 1..1023 bytes each
  std::string image_uri;              ///< as written in the file; "" = no picture
  std::filesystem::path image_path;   ///< image_uri resolved to a file (a PNG)
  /// The text in `language`, else the English one, else the first; "" if the page has none.
  const std::string& TextIn(const std::string& language) const noexcept { return scene::TextIn(text, language); }
};

/// A control entry: its geometry, force-profile parameters and actions. Frame C: origin and
/// axes as documented per type in handshare/controls/controls.hpp.
struct ControlSpec {
  std::string id;
  ControlType type = ControlType::kButton;
  Eigen::Vector3d p_WC_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WC = Eigen::Quaterniond::Identity();
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();
  std::array<float, 3> rgb{0.8f, 0.6f, 0.1f};
  std::string mesh_uri;  ///< optional visual
  std::filesystem::path mesh_path;
  Eigen::Vector3d mesh_scale = Eigen::Vector3d::Ones();
  std::shared_ptr<const Mesh> mesh;  ///< the loaded visual, in C
  double approach_margin_m = 0.03;  ///< approach zone around the control (miss detection)
  double max_force_N = 3.5;         ///< per fingertip

  struct Push {  ///< button and arrow: travel along -z of C
    double travel_m = 0.004;
    double click_at_m = 0.0025;
    double release_at_m = 0.0012;
    double stiffness_N_per_m = 400.0;
    double preload_N = 0.3;
    double click_drop = 0.4;  ///< fraction of the spring force lost at the click
    double stop_stiffness_N_per_m = 3000.0;
  } push;
  struct Lever {  ///< rotation about x of C, handle along z of C
    double min_angle_rad = 0.0;
    double max_angle_rad = 0.6;
    int detents = 2;
    double detent_torque_N_m = 0.06;
    double settle_rate_rad_per_s = 3.0;
    double stop_stiffness_N_per_m = 3000.0;
    /// The angle between two neighbouring detents (both end stops are detents).
    double spacing_rad() const { return (max_angle_rad - min_angle_rad) / (detents > 1 ? detents - 1 : 1); }
    /// The angle of detent k (0 .. detents - 1).
    double detent_angle_rad(int k) const { return min_angle_rad + k * spacing_rad(); }
  } lever;
  struct Book {  ///< lies on its back cover, spine along y of C at x = -size.x/2
    int pages = 6;
    double open_angle_rad = 1.4;
    double swipe_m = 0.04;
    double surface_stiffness_N_per_m = 2000.0;
    double page_drag_N = 0.3;
  } book;

  Action action;                     ///< button, arrow: on PRESSED; book: on opening
  std::vector<Action> detent_actions;  ///< lever: on settling in detent i (empty or one each)
  std::vector<Action> page_actions;    ///< book: on turning to page i (may be shorter)
  std::vector<BookPage> page_content;  ///< book: what page i shows (empty: blank pages)
  std::vector<LocalText> label;        ///< shown beside it on screens (may be empty)
  int line = 0;
};

struct Scene {
  std::string name;
  std::string title;
  Eigen::Vector3d gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -9.81);
  std::vector<SceneObject> objects;  ///< includes one kControl object per control (its visual)
  std::vector<ControlSpec> controls;
  std::vector<Message> messages;  // shown in order on the message board
  std::filesystem::path file;     ///< where it was loaded from
};

/// Every board message a scene can show, in file order: its own, then each control's (its
/// action, its detent actions, its page actions).
std::vector<Message> AllMessages(const Scene& scene);

struct LoadOptions {
  /// Load (and so validate) every mesh into SceneObject::mesh. false: only check that the files
  /// exist (fast listing of scenes).
  bool load_meshes = true;
};

/// Loads and validates one scene file. Throws SceneError naming the file, line and field.
Scene LoadScene(const std::filesystem::path& file, const LoadOptions& options = {});

/// The folder of the project's scene files: $HANDSHARE_ASSETS/scenes if set, else the installed
/// share/handshare/assets/scenes, else the source tree's assets/scenes (common::AssetsDir).
std::filesystem::path DefaultSceneDir();

/// The scenes in `dir` (the stems of its .json files), sorted; empty if it is not a folder.
std::vector<std::string> SceneNames(const std::filesystem::path& dir = DefaultSceneDir());

/// Loads scene `name` from dir/name.json. Throws SceneError listing the scenes available.
Scene LoadSceneByName(const std::string& name, const std::filesystem::path& dir = DefaultSceneDir(),
                      const LoadOptions& options = {});

/// Reads a triangle mesh (OBJ, STL, PLY: anything assimp reads) into frame A: every vertex p_M
/// of the file (after its node transforms) becomes X_AM * (scale .* p_M). Polygons are
/// triangulated, vertices with bitwise-identical positions welded; a negative scale product
/// flips the winding so that outward stays outward.
/// @throws SceneError naming the file if it is missing, unreadable or has no triangles.
Mesh LoadMesh(const std::filesystem::path& file,
              const Eigen::Vector3d& scale = Eigen::Vector3d::Ones(),
              const Eigen::Isometry3d& X_AM = Eigen::Isometry3d::Identity());

/// Closedness and orientation of a mesh.
struct MeshCheck {
  std::size_t boundary_edges = 0;     ///< directed edges without the opposite edge
  std::size_t non_manifold_edges = 0; ///< directed edges used more than once
  std::size_t degenerate_triangles = 0;
  double signed_volume_m3 = 0.0;      ///< > 0 for a closed outward-oriented mesh
  Eigen::AlignedBox3d bounds;
  bool closed_and_outward() const noexcept {
    return boundary_edges == 0 && non_manifold_edges == 0 && degenerate_triangles == 0 &&
           signed_volume_m3 > 0.0;
  }
};
MeshCheck CheckMesh(const Mesh& mesh);

/// Flat-punch indentation of an elastic half space: depth [m] of a rigid circular punch of
/// radius a_m pressed with force_N (Boussinesq flat punch, F = 2 a E delta / (1 - nu^2); see
/// Johnson, Contact Mechanics, ch. 3). Used to choose E of the deformables (several mm at 3 N
/// for an 8 mm fingertip).
double FlatPunchDepth_m(double force_N, double a_m, double E_Pa, double nu) noexcept;

}  // namespace handshare::scene
