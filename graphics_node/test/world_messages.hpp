#pragma once
// Samples of the shared world's topics as the world server would send them, and a temporary
// folder, for the graphics node's tests.
#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <Eigen/Geometry>

#include "handshare/dds/messages.hpp"
#include "handshare/render/scene_view.hpp"

namespace handshare::graphics {

/// A folder of its own under the system's temporary folder, removed at the end.
class TempDir {
 public:
  TempDir() {
    path_ = std::filesystem::temp_directory_path() /
            ("graphics_node_test_" + std::to_string(getpid()) + "_" + std::to_string(next_++));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  static inline int next_ = 0;
  std::filesystem::path path_;
};

/// An object of a scene state; half_extent_m: box half sizes, sphere radius in x.
inline msg::SceneObject Object(const std::string& id, const std::string& shape,
                               const std::string& uri, const Eigen::Isometry3d& X_WO,
                               const render::Rgb& rgb,
                               const Eigen::Vector3d& half_extent_m = Eigen::Vector3d::Constant(0.02)) {
  msg::SceneObject o;
  o.object_id(id);
  o.kind(msg::OBJECT_DEFORMABLE);
  o.shape(shape);
  o.mesh_uri(uri);
  const Eigen::Vector3d p = X_WO.translation();
  const Eigen::Quaterniond q(X_WO.linear());
  o.p_WO_m({p.x(), p.y(), p.z()});
  o.q_WO_wxyz({q.w(), q.x(), q.y(), q.z()});
  o.half_extent_m({half_extent_m.x(), half_extent_m.y(), half_extent_m.z()});
  o.mass_kg(0.1);
  o.rgb({rgb.r, rgb.g, rgb.b});
  return o;
}

inline msg::SceneState Scene(const std::string& name, std::uint32_t revision,
                             const std::vector<msg::SceneObject>& objects, const std::string& session = "test") {
  msg::SceneState s;
  s.session(session);
  s.scene(name);
  s.revision(revision);
  s.gravity_W_m_per_s2({0.0, 0.0, -9.81});
  for (const auto& o : objects) s.objects().push_back(o);
  return s;
}

inline msg::Deformation Deformation(const std::string& id, std::uint32_t revision, bool keyframe,
                                    const std::vector<std::uint32_t>& ids,
                                    const std::vector<float>& u, const std::string& session = "test") {
  msg::Deformation d;
  d.object_id(id);
  d.session(session);
  d.revision(revision);
  d.keyframe(keyframe);
  d.surface_node_count(0);
  d.node_ids(ids);
  d.u_W_m(u);
  return d;
}

inline msg::ObjectState State(const std::string& id, const Eigen::Vector3d& p,
                              const Eigen::Vector4d& q_wxyz, const std::string& session = "test") {
  msg::ObjectState s;
  s.object_id(id);
  s.session(session);
  s.p_WO_m({p.x(), p.y(), p.z()});
  s.q_WO_wxyz({q_wxyz[0], q_wxyz[1], q_wxyz[2], q_wxyz[3]});
  return s;
}

}  // namespace handshare::graphics
