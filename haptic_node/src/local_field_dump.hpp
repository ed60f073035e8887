#pragma once
/// The haptic node's own field of each deformable it solves (--dump-deformation DIR): the
/// surface displacement its solve gives the body, with this hand's fingertips and the peers'
/// contacts as this node holds them. A file per object, DIR/<object>.json, replaced (write and
/// rename) at most every `period`: what a test compares with the world server's field of the
/// same body (net.delayed_tail: one body, one shape). Bridge thread; not real-time.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "handshare/fem/surface_field.hpp"
#include "handshare/haptic/scene_renderer.hpp"

namespace handshare::haptic {

class LocalFieldDump {
 public:
  LocalFieldDump(std::filesystem::path dir, std::string user, std::chrono::milliseconds period);

  /// Takes the renderer's newest loads and, if `period` has passed since the last write, writes
  /// each touched deformable's field. Errors (a directory that cannot be written) are thrown
  /// once as std::runtime_error naming the file.
  void Update(SceneRenderer& renderer);

  std::uint64_t written() const { return written_; }

 private:
  std::filesystem::path dir_;
  std::string user_;
  std::chrono::nanoseconds period_;
  std::uint64_t last_ns_ = 0;
  std::uint64_t written_ = 0;
  const SceneRenderer* renderer_ = nullptr;  // the one the fields below belong to
  std::map<std::int32_t, std::unique_ptr<fem::SurfaceField>> fields_;  // by world object
  std::vector<Eigen::Vector3d> u_slots_;
  std::vector<fem::NodeLoad> node_loads_;
  DeformableLoads loads_;
};

}  // namespace handshare::haptic
