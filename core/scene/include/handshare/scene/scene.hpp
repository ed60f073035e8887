#pragma once
/// Scenes as data: a world (objects, gravity, controls later) and its message-board texts,
/// loaded from JSON files in assets/scenes/. No middleware, no rendering: plain data that the
/// world server publishes and the haptic and graphics nodes use.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace handshare::scene {

/// A scene file that cannot be used; what() names the file and the field (and line when the
/// JSON itself is malformed).
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class ObjectKind { kRigid, kDeformable, kControl };
enum class Shape { kSphere, kBox, kMesh };

struct SceneObject {
  std::string id;
  ObjectKind kind = ObjectKind::kRigid;
  Shape shape = Shape::kSphere;
  std::string mesh_uri;                               // for Shape::kMesh
  Eigen::Vector3d p_WO_m = Eigen::Vector3d::Zero();   // object origin O in world W
  Eigen::Quaterniond q_WO = Eigen::Quaterniond::Identity();
  Eigen::Vector3d half_extent_m = Eigen::Vector3d::Zero();  // box; sphere radius in x
  double mass_kg = 0.0;
  std::array<float, 3> rgb{0.7f, 0.7f, 0.7f};
};

struct Message {
  std::string language;  // "en", "ja"
  std::string text;
  std::string next_action;
};

struct Scene {
  std::string name;
  std::string title;
  Eigen::Vector3d gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -9.81);
  std::vector<SceneObject> objects;
  std::vector<Message> messages;  // shown in order on the message board
};

/// Loads and validates one scene file. Throws SceneError naming the file and field.
Scene LoadScene(const std::filesystem::path& file);

/// The folder of the project's scene files: $HANDSHARE_ASSETS/scenes if set, else the source
/// tree's assets/scenes (path compiled in).
std::filesystem::path DefaultSceneDir();

/// Loads scene `name` from dir/name.json. Throws SceneError listing the scenes available.
Scene LoadSceneByName(const std::string& name, const std::filesystem::path& dir = DefaultSceneDir());

}  // namespace handshare::scene
