#pragma once
/// The shared world as a spectator sees it: the scene state's objects, drawn with their real
/// meshes, in the latest pose their ObjectState gives, deformed by the Deformation topic.
/// Fed with received samples (the DDS readers live in the spectator); no OpenGL. Not real-time:
/// the graphics thread, one thread at a time.
///
/// Drawn vertex v of a mesh object O:  p_WV = X_WO * p_OV + u_W[v], with
///   p_OV   the vertex of the mesh file (mesh_uri relative to the assets folder, read once with
///          scene::LoadMesh; vertex order = the Deformation node ids),
///   X_WO   the object's latest finite ObjectState pose, else the scene state's pose,
///   u_W[v] the displacement the Deformation samples gave (DeformationField).
/// Normals: area-weighted vertex normals of the mesh, recomputed while it is displaced.
/// A mesh that cannot be loaded is reported once per scene on the error stream (object, file,
/// reason) and drawn as the object's box (half_extent_m around its origin).
///
/// Objects and controls with a `label` in their scene file are named on screen in the replica's
/// language (English where a label lacks it): render::Label 1 cm above the object's top (its
/// drawn mesh's highest vertex, a sphere's or box's top), over its middle.
///
/// Books are drawn from their scene entry, not their mesh: covers in the book's colour, a spine,
/// a block of pages. Open (their control state), they lie flat with the spread they are open at:
/// the page's picture on the left page, its text in the replica's language on the right (the
/// pages' tops at z = 0 of the book's frame C, where the fingers feel them). A picture that
/// cannot be read is reported once and its page drawn blank.
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "handshare/dds/messages.hpp"
#include "handshare/graphics/deformation_field.hpp"
#include "handshare/graphics/mesh_cache.hpp"
#include "handshare/render/scene_view.hpp"

namespace handshare::graphics {

struct SceneReplicaStats {
  std::uint64_t scene_changes = 0;              ///< scene states of another scene (fields reset)
  std::uint64_t mesh_errors = 0;                ///< objects drawn as boxes for a bad mesh
  std::uint64_t deformation_samples = 0;        ///< Deformation samples received
  std::uint64_t deformation_unknown_object = 0; ///< ... of objects not in the scene, ignored
  std::uint64_t deformation_without_mesh = 0;   ///< ... of objects with no loaded mesh, ignored
  /// ... applied although their surface_node_count (when non-zero) is not the mesh's vertex
  /// count: publisher and spectator may number different meshes.
  std::uint64_t deformation_count_mismatch = 0;
  std::uint64_t object_states = 0;              ///< ObjectState samples applied
  std::uint64_t object_states_unknown = 0;      ///< ... of objects not in the scene, ignored
  std::uint64_t object_states_nonfinite = 0;    ///< ... with a non-finite or zero pose, ignored
};

class SceneReplica {
 public:
  /// assets_dir: the folder mesh uris are relative to. errors: where mesh errors are written
  /// (kept by reference; std::cerr in the node). prefix: starts each error line. language: the
  /// language books' pages are shown in (en, ja; a page without it shows its English text).
  SceneReplica(std::filesystem::path assets_dir, std::ostream& errors, std::string prefix = "",
               std::string language = "en");

  /// A new scene state. Another scene (name) resets every deformation field and object pose;
  /// a new revision of the same scene keeps them for the objects that remain.
  void OnSceneState(const msg::SceneState& state);
  /// A Deformation sample (DeformationField's receiver rule). Ignored, and counted, for objects
  /// not in the current scene or whose mesh is not loaded.
  void OnDeformation(const msg::Deformation& sample);
  /// An ObjectState sample: its pose replaces the scene state's pose of that object. Ignored,
  /// and counted, for objects not in the current scene and for non-finite poses or a zero
  /// quaternion (the last good pose stays).
  void OnObjectState(const msg::ObjectState& state);
  /// A ControlState sample (the world server's): the control is drawn where it left it, a
  /// lever turned into its detent, a pressed button or arrow down by its travel, a book open at
  /// its page, while its world is the scene; while a hand moves it (`moving`), where that hand
  /// has it (`position`: the lever's angle, the button's travel, the book cover's angle). The control's geometry comes from the scene file of that name in the
  /// assets' scenes folder (a scene that cannot be read: its controls are drawn at rest).
  void OnControlState(const msg::ControlState& state);
  /// The newest control state of `control_id` in the current scene: (index, engaged).
  std::optional<std::pair<std::int32_t, bool>> control_state(const std::string& control_id) const;

  bool has_scene() const { return has_scene_; }
  const std::string& scene() const { return scene_; }
  /// Appends every object of the scene to view (spheres, boxes, meshes, book pages, labels).
  void AddObjects(render::SceneView& view) const;

  /// The field of object_id; null if it is not a mesh object of the current scene with a
  /// loaded mesh.
  const DeformationField* deformation(const std::string& object_id) const;
  /// Pose the object is drawn in; empty if it is not in the current scene.
  std::optional<Eigen::Isometry3d> X_WO(const std::string& object_id) const;
  /// True when that pose came from an ObjectState (else it is the scene state's).
  bool pose_received(const std::string& object_id) const;
  /// The sender's stamp of each drawn ObjectState pose, "id@stamp_ns" joined by ';' in scene
  /// order (objects drawn at the scene state's pose left out): what a frame shows of moving
  /// objects, by stamps a replay carries unchanged.
  std::string pose_stamps() const;
  /// The revision of each mesh's field that a Deformation sample gave, "id@revision" joined by
  /// ';' in scene order (fields no sample reached left out): what a frame shows of deformations.
  std::string field_revisions() const;
  /// The current scene's objects, in scene-state order.
  const std::vector<std::string>& object_ids() const { return order_; }
  const SceneReplicaStats& stats() const { return stats_; }
  /// Deformation statistics summed over the current fields.
  DeformationStats deformation_stats() const;
  MeshCache& meshes() { return meshes_; }

  /// Writes what the fields hold as JSON:
  ///   {"<object_id>": {"revision": R, "vertex_count": V,
  ///                    "u_W_m": {"<vertex>": [ux, uy, uz], ...}}, ...}
  /// with one entry per object of the current scene that received at least one Deformation
  /// sample, and only the vertices with a non-zero displacement (in W [m], the received floats).
  /// Written to a temporary file and renamed, so a reader never sees half a file. Throws
  /// std::runtime_error naming the file when it cannot be written.
  void WriteDeformationJson(const std::filesystem::path& file) const;

 private:
  struct Object {
    msg::SceneObject spec;
    Eigen::Isometry3d X_WO_scene = Eigen::Isometry3d::Identity();  // from the scene state
    std::optional<Eigen::Isometry3d> X_WO_state;                  // latest ObjectState
    std::uint64_t state_stamp_ns = 0;                              // its sender's stamp
    std::shared_ptr<const render::TriangleMesh> mesh;              // null: not a mesh, or failed
    std::unique_ptr<DeformationField> field;                       // with mesh
    const Eigen::Isometry3d& X_WO() const { return X_WO_state ? *X_WO_state : X_WO_scene; }
  };

  /// What drawing a control in its state needs of its scene entry.
  struct ControlGeometry {
    std::vector<double> detent_angles_rad;  // a lever's detents (empty: not a lever)
    double travel_m = 0.0;                  // a button's or arrow's travel (0: not one)
    bool book = false;
    Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();  // a book's frame C
    Eigen::Vector3d size_m = Eigen::Vector3d::Zero();        // a book's size
    struct Page {
      std::string text;             // in the replica's language
      std::filesystem::path image;  // "" = none
    };
    std::vector<Page> pages;  // a book's pages
  };
  struct ControlDrawn {
    std::string scene;
    std::int32_t index = -1;
    bool engaged = false;
    bool moving = false;    // a hand moves it: drawn at `position`
    double position = 0.0;  // button travel [m], lever angle [rad], book cover angle [rad]
  };
  /// The newest state of `control_id` in the current scene, or null.
  const ControlDrawn* drawn_state(const std::string& control_id) const;
  /// X_WO of object `id` as drawn: a control turned or pressed as its state says.
  Eigen::Isometry3d DrawnPose(const std::string& id, const Eigen::Isometry3d& X_WO) const;
  /// A book, shut or open at its page as its state says (see the class comment).
  void AddBook(render::SceneView& view, const std::string& id, const ControlGeometry& book,
               const render::Rgb& rgb) const;
  /// The picture of a book page, read once (null, reported once, if it cannot be read).
  std::shared_ptr<const render::ImageRgb8> PageImage(const std::filesystem::path& file) const;

  std::ostream& errors_;
  std::string prefix_;
  std::filesystem::path scenes_dir_;
  std::map<std::string, ControlGeometry> control_geometry_;  // the current scene's controls
  std::map<std::string, std::string> labels_;                 // object id -> its label, in language_
  std::map<std::string, render::Appearance> looks_;           // object id -> how it is lit
  std::map<std::string, ControlDrawn> control_states_;        // newest per control id
  std::string language_;                                      // the books' pages' language
  // Pictures of book pages by file: read on the graphics thread when first drawn.
  mutable std::map<std::filesystem::path, std::shared_ptr<const render::ImageRgb8>> page_images_;
  MeshCache meshes_;
  bool has_scene_ = false;
  std::string scene_;
  std::map<std::string, Object> objects_;
  std::vector<std::string> order_;  // objects in scene-state order (drawing order)
  std::set<std::string> reported_;  // mesh errors already written for this scene
  DeformationStats retired_;        // statistics of the fields of earlier scenes
  SceneReplicaStats stats_;
};

}  // namespace handshare::graphics
