#include "handshare/scene/scene.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace handshare::scene {

namespace {

using nlohmann::json;

// Turns a byte offset of a parse error into a line number, so the message points at the line.
int LineOf(const std::string& text, std::size_t byte) {
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + std::min(byte, text.size()), '\n'));
}

class Context {
 public:
  explicit Context(std::string file) : file_(std::move(file)) {}
  [[noreturn]] void Fail(const std::string& field, const std::string& what) const {
    throw SceneError(file_ + ": field '" + field + "': " + what);
  }
  const json& Require(const json& j, const std::string& key, const std::string& path) const {
    if (!j.is_object() || !j.contains(key)) Fail(path + key, "missing");
    return j.at(key);
  }
  std::string String(const json& j, const std::string& key, const std::string& path) const {
    const json& v = Require(j, key, path);
    if (!v.is_string()) Fail(path + key, "expected a string, got " + std::string(v.type_name()));
    return v.get<std::string>();
  }
  double Number(const json& v, const std::string& field, double min, double max) const {
    if (!v.is_number()) Fail(field, "expected a number, got " + std::string(v.type_name()));
    const double d = v.get<double>();
    if (!std::isfinite(d) || d < min || d > max) {
      std::ostringstream s;
      s << "value " << d << " outside [" << min << ", " << max << "]";
      Fail(field, s.str());
    }
    return d;
  }
  template <int N>
  Eigen::Matrix<double, N, 1> Vector(const json& v, const std::string& field, double min,
                                     double max) const {
    if (!v.is_array() || v.size() != N) Fail(field, "expected an array of " + std::to_string(N) + " numbers");
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i) out[i] = Number(v[i], field + "[" + std::to_string(i) + "]", min, max);
    return out;
  }

 private:
  std::string file_;
};

SceneObject ParseObject(const Context& c, const json& j, const std::string& path) {
  SceneObject o;
  o.id = c.String(j, "id", path);
  if (o.id.empty() || o.id.size() > 63) c.Fail(path + "id", "must have 1..63 characters");
  const std::string kind = c.String(j, "kind", path);
  if (kind == "rigid") o.kind = ObjectKind::kRigid;
  else if (kind == "deformable") o.kind = ObjectKind::kDeformable;
  else if (kind == "control") o.kind = ObjectKind::kControl;
  else c.Fail(path + "kind", "'" + kind + "' is not one of rigid, deformable, control");
  const std::string shape = c.String(j, "shape", path);
  if (shape == "sphere") {
    o.shape = Shape::kSphere;
    o.half_extent_m.x() = c.Number(c.Require(j, "radius_m", path), path + "radius_m", 1e-4, 10.0);
  } else if (shape == "box") {
    o.shape = Shape::kBox;
    o.half_extent_m = c.Vector<3>(c.Require(j, "half_extent_m", path), path + "half_extent_m", 1e-4, 10.0);
  } else if (shape == "mesh") {
    o.shape = Shape::kMesh;
    o.mesh_uri = c.String(j, "mesh", path);
  } else {
    c.Fail(path + "shape", "'" + shape + "' is not one of sphere, box, mesh");
  }
  o.p_WO_m = c.Vector<3>(c.Require(j, "position_m", path), path + "position_m", -100.0, 100.0);
  if (j.contains("orientation_wxyz")) {
    const Eigen::Vector4d q = c.Vector<4>(j["orientation_wxyz"], path + "orientation_wxyz", -1.0, 1.0);
    if (std::abs(q.norm() - 1.0) > 1e-6) c.Fail(path + "orientation_wxyz", "not a unit quaternion");
    o.q_WO = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  }
  if (j.contains("mass_kg")) o.mass_kg = c.Number(j["mass_kg"], path + "mass_kg", 0.0, 1000.0);
  if (j.contains("rgb")) {
    const Eigen::Vector3d rgb = c.Vector<3>(j["rgb"], path + "rgb", 0.0, 1.0);
    o.rgb = {static_cast<float>(rgb.x()), static_cast<float>(rgb.y()), static_cast<float>(rgb.z())};
  }
  return o;
}

}  // namespace

Scene LoadScene(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw SceneError(file.string() + ": cannot open scene file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    throw SceneError(file.string() + ":" + std::to_string(LineOf(text, e.byte)) +
                     ": malformed JSON: " + e.what());
  }
  const Context c(file.string());
  Scene s;
  s.name = c.String(root, "name", "");
  s.title = root.contains("title") ? c.String(root, "title", "") : s.name;
  if (root.contains("gravity_m_per_s2")) {
    s.gravity_W_m_per_s2 = c.Vector<3>(root["gravity_m_per_s2"], "gravity_m_per_s2", -100.0, 100.0);
  }
  std::set<std::string> ids;
  if (root.contains("objects")) {
    const json& objects = root["objects"];
    if (!objects.is_array()) c.Fail("objects", "expected an array");
    if (objects.size() > 64) c.Fail("objects", "more than 64 objects");
    for (std::size_t i = 0; i < objects.size(); ++i) {
      SceneObject o = ParseObject(c, objects[i], "objects[" + std::to_string(i) + "].");
      if (!ids.insert(o.id).second) c.Fail("objects[" + std::to_string(i) + "].id", "duplicate id '" + o.id + "'");
      s.objects.push_back(std::move(o));
    }
  }
  const json& messages = c.Require(root, "messages", "");
  if (!messages.is_array() || messages.empty()) c.Fail("messages", "expected a non-empty array");
  for (std::size_t i = 0; i < messages.size(); ++i) {
    const std::string path = "messages[" + std::to_string(i) + "].";
    Message m;
    m.language = c.String(messages[i], "language", path);
    if (m.language != "en" && m.language != "ja") c.Fail(path + "language", "'" + m.language + "' is not en or ja");
    m.text = c.String(messages[i], "text", path);
    if (m.text.empty() || m.text.size() > 1023) c.Fail(path + "text", "must have 1..1023 bytes");
    m.next_action = messages[i].contains("next_action") ? c.String(messages[i], "next_action", path) : "";
    if (m.next_action.size() > 511) c.Fail(path + "next_action", "longer than 511 bytes");
    s.messages.push_back(std::move(m));
  }
  return s;
}

std::filesystem::path DefaultSceneDir() {
  if (const char* env = std::getenv("HANDSHARE_ASSETS"); env != nullptr && *env != '\0') {
    return std::filesystem::path(env) / "scenes";
  }
  return std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes";
}

Scene LoadSceneByName(const std::string& name, const std::filesystem::path& dir) {
  const auto file = dir / (name + ".json");
  if (!std::filesystem::exists(file)) {
    std::string available;
    if (std::filesystem::is_directory(dir)) {
      for (const auto& e : std::filesystem::directory_iterator(dir)) {
        if (e.path().extension() == ".json") available += " " + e.path().stem().string();
      }
    }
    throw SceneError("unknown scene '" + name + "' (no " + file.string() + "); available:" +
                     (available.empty() ? " none" : available));
  }
  return LoadScene(file);
}

}  // namespace handshare::scene
