#include "local_field_dump.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace handshare::haptic {

LocalFieldDump::LocalFieldDump(std::filesystem::path dir, std::string user, std::chrono::milliseconds period)
    : dir_(std::move(dir)), user_(std::move(user)), period_(period) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw std::runtime_error("--dump-deformation: cannot create '" + dir_.string() + "': " + ec.message());
}

void LocalFieldDump::Update(SceneRenderer& renderer) {
  if (&renderer != renderer_) {  // another world: its own compliances
    renderer_ = &renderer;
    fields_.clear();
  }
  if (!renderer.TakeLoads(loads_)) return;
  if (last_ns_ != 0 && loads_.step_ns < last_ns_ + static_cast<std::uint64_t>(period_.count())) return;
  last_ns_ = loads_.step_ns;
  const world::SceneModels& models = renderer.models();
  for (std::int32_t i = 0; i < loads_.count; ++i) {
    const DeformableLoads::Item& item = loads_.items[i];
    if (item.num_loads < 0) continue;  // more loads than a snapshot holds: no field this time
    const std::string& id = renderer.IdOf(item.object);
    const world::PreparedDeformable* prepared = nullptr;
    for (const auto& d : models.deformables) {
      if (d.object_id == id && d.compliance) prepared = &d;
    }
    if (prepared == nullptr) continue;
    auto& field = fields_[item.object];
    if (!field) field = std::make_unique<fem::SurfaceField>(prepared->compliance);
    u_slots_.resize(static_cast<std::size_t>(prepared->compliance->num_nodes()));
    node_loads_.resize(static_cast<std::size_t>(item.num_loads));
    for (std::size_t l = 0; l < node_loads_.size(); ++l) {
      node_loads_[l].slot = item.loads[l].slot;
      node_loads_[l].f_N = Eigen::Vector3d(item.loads[l].f_N[0], item.loads[l].f_N[1], item.loads[l].f_N[2]);
    }
    if (!field->Evaluate(node_loads_, u_slots_)) continue;
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R(r, c) = item.R_WO[3 * r + c];
    }
    // Keyed by mesh node (0-based), as the world server's dump keys its published field (the
    // scene mesh's vertices are the tetrahedral mesh's first nodes), in W.
    std::ostringstream j;
    j.precision(9);
    j << "{\"object\": \"" << id << "\", \"user\": \"" << user_ << "\", \"step_ns\": " << loads_.step_ns
      << ", \"loads\": " << item.num_loads << ",\n \"u_W_m\": {";
    bool first = true;
    const auto& nodes = prepared->compliance->nodes();
    for (std::size_t s = 0; s < u_slots_.size(); ++s) {
      if (u_slots_[s].squaredNorm() == 0.0) continue;
      const Eigen::Vector3d u = R * u_slots_[s];
      j << (first ? "" : ", ") << "\"" << nodes[s] << "\": [" << u.x() << ", " << u.y() << ", " << u.z() << "]";
      first = false;
    }
    j << "}}\n";
    const auto file = dir_ / (id + ".json");
    const auto tmp = dir_ / (id + ".json.tmp");
    {
      std::ofstream f(tmp);
      f << j.str();
      if (!f) throw std::runtime_error("--dump-deformation: cannot write '" + tmp.string() + "'");
    }
    std::error_code ec;
    std::filesystem::rename(tmp, file, ec);
    if (ec) throw std::runtime_error("--dump-deformation: cannot replace '" + file.string() + "': " + ec.message());
    ++written_;
  }
}

}  // namespace handshare::haptic
