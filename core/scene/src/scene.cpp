#include "handshare/scene/scene.hpp"

#include <nlohmann/json.hpp>

#include "handshare/common/data_dir.hpp"
#include "handshare/common/utf8.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

namespace handshare::scene {

namespace {

using nlohmann::json;

// A book's pages with content (the scene-state message does not carry them; a graphics node
// reads them from the scene file).
constexpr std::size_t kMaxBookPages = 64;

// ------------------------------------------------------------------------------------------
// JSON with the line of every field.
//
// nlohmann::json keeps no positions in its DOM, so the file is parsed with its SAX interface
// over an input iterator that records how far the lexer has read. When a SAX event arrives the
// lexer has just consumed the token (for numbers, one character of look-ahead), so the last
// non-blank character read belongs to the token; its line is the field's line.

// Input iterator over the text that remembers the furthest character handed out.
class TrackingIterator {
 public:
  using iterator_category = std::input_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;

  TrackingIterator(const char* p, const char** furthest) : p_(p), furthest_(furthest) {}
  reference operator*() const { return *p_; }
  TrackingIterator& operator++() {
    ++p_;
    if (p_ > *furthest_) *furthest_ = p_;
    return *this;
  }
  TrackingIterator operator++(int) {
    TrackingIterator old = *this;
    ++*this;
    return old;
  }
  bool operator==(const TrackingIterator& o) const { return p_ == o.p_; }
  bool operator!=(const TrackingIterator& o) const { return p_ != o.p_; }

 private:
  const char* p_;
  const char** furthest_;
};

// Line numbers of byte offsets.
class LineIndex {
 public:
  explicit LineIndex(const std::string& text) : text_(text) {
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] == '\n') newlines_.push_back(i);
    }
  }
  // 1-based line of the byte at `offset`.
  int LineOfByte(std::size_t offset) const {
    return 1 + static_cast<int>(std::lower_bound(newlines_.begin(), newlines_.end(), offset) -
                                newlines_.begin());
  }
  // Line of the last non-blank character before `end` (the token just read).
  int LineOfTokenEndingBefore(std::size_t end) const {
    std::size_t i = std::min(end, text_.size());
    while (i > 0 && std::isspace(static_cast<unsigned char>(text_[i - 1]))) --i;
    return LineOfByte(i == 0 ? 0 : i - 1);
  }

 private:
  const std::string& text_;
  std::vector<std::size_t> newlines_;
};

struct ParsedJson {
  json root;
  std::map<std::string, int> lines;  // field path ("objects[2].mesh") -> line
};

// Builds the DOM like nlohmann's own SAX DOM parser and records each field's line.
class LineRecordingSax {
 public:
  LineRecordingSax(const LineIndex& index, const char* begin, const char* const* furthest,
                   ParsedJson* out)
      : index_(index), begin_(begin), furthest_(furthest), out_(out) {}

  bool null() { return Value(json(nullptr)); }
  bool boolean(bool v) { return Value(json(v)); }
  bool number_integer(json::number_integer_t v) { return Value(json(v)); }
  bool number_unsigned(json::number_unsigned_t v) { return Value(json(v)); }
  bool number_float(json::number_float_t v, const json::string_t&) { return Value(json(v)); }
  bool string(json::string_t& v) { return Value(json(v)); }
  bool binary(json::binary_t& v) { return Value(json(v)); }
  bool start_object(std::size_t) { return Open(json::object()); }
  bool start_array(std::size_t) { return Open(json::array()); }
  bool end_object() { return Close(); }
  bool end_array() { return Close(); }
  bool key(json::string_t& k) {
    Frame& f = stack_.back();
    if (f.value->contains(k)) {
      error_line_ = Line();
      error_ = "field '" + Join(f.path, k) + "': duplicate key";
      return false;
    }
    key_ = k;
    out_->lines.emplace(Join(f.path, k), Line());
    return true;
  }
  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& e) {
    error_line_ = index_.LineOfByte(position == 0 ? 0 : position - 1);
    error_ = std::string("malformed JSON: ") + e.what();
    return false;
  }

  int error_line() const { return error_line_; }
  const std::string& error() const { return error_; }

 private:
  struct Frame {
    json* value;
    std::string path;
  };
  static std::string Join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }
  int Line() const { return index_.LineOfTokenEndingBefore(static_cast<std::size_t>(*furthest_ - begin_)); }

  // Places v in its parent and returns it with its path.
  std::pair<json*, std::string> Place(json v) {
    if (stack_.empty()) {
      out_->root = std::move(v);
      out_->lines.emplace("", Line());
      return {&out_->root, ""};
    }
    Frame& f = stack_.back();
    if (f.value->is_array()) {
      const std::string path = f.path + "[" + std::to_string(f.value->size()) + "]";
      f.value->push_back(std::move(v));
      out_->lines.emplace(path, Line());
      return {&f.value->back(), path};
    }
    const std::string path = Join(f.path, key_);
    json& slot = (*f.value)[key_];
    slot = std::move(v);
    return {&slot, path};
  }
  bool Value(json v) {
    Place(std::move(v));
    return true;
  }
  bool Open(json v) {
    auto [ptr, path] = Place(std::move(v));
    stack_.push_back({ptr, path});
    return true;
  }
  bool Close() {
    stack_.pop_back();
    return true;
  }

  const LineIndex& index_;
  const char* begin_;
  const char* const* furthest_;
  ParsedJson* out_;
  std::vector<Frame> stack_;
  std::string key_;
  int error_line_ = 0;
  std::string error_;
};

// ------------------------------------------------------------------------------------------
// Field access with errors that name file, line and field.

class Context {
 public:
  Context(std::string file, const std::map<std::string, int>* lines)
      : file_(std::move(file)), lines_(lines) {}

  // Line of `field`, or of the nearest enclosing field that has one (a missing field is
  // reported at the object that lacks it).
  int LineOf(std::string field) const {
    while (true) {
      if (auto it = lines_->find(field); it != lines_->end()) return it->second;
      if (field.empty()) return 0;
      const std::size_t cut = field.find_last_of(".[");
      field = cut == std::string::npos ? std::string() : field.substr(0, cut);
    }
  }
  [[noreturn]] void Fail(const std::string& field, const std::string& what) const {
    throw SceneError(file_ + ":" + std::to_string(LineOf(field)) + ": field '" + field + "': " + what);
  }
  const json& Require(const json& j, const std::string& key, const std::string& path) const {
    if (!j.is_object() || !j.contains(key)) Fail(path + key, "missing");
    return j.at(key);
  }
  std::string String(const json& j, const std::string& key, const std::string& path,
                     std::size_t max_bytes = 1023) const {
    const json& v = Require(j, key, path);
    if (!v.is_string()) Fail(path + key, "expected a string, got " + std::string(v.type_name()));
    std::string s = v.get<std::string>();
    if (s.size() > max_bytes) Fail(path + key, "longer than " + std::to_string(max_bytes) + " bytes");
    return s;
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
  // Optional number: `fallback` when absent.
  double Number(const json& j, const std::string& key, const std::string& path, double min,
                double max, double fallback) const {
    return j.contains(key) ? Number(j.at(key), path + key, min, max) : fallback;
  }
  int Integer(const json& v, const std::string& field, int min, int max) const {
    if (!v.is_number_integer()) Fail(field, "expected an integer, got " + std::string(v.type_name()));
    const auto i = v.get<long long>();
    if (i < min || i > max) {
      Fail(field, "value " + std::to_string(i) + " outside [" + std::to_string(min) + ", " +
                      std::to_string(max) + "]");
    }
    return static_cast<int>(i);
  }
  template <int N>
  Eigen::Matrix<double, N, 1> Vector(const json& v, const std::string& field, double min,
                                     double max) const {
    if (!v.is_array() || v.size() != N) Fail(field, "expected an array of " + std::to_string(N) + " numbers");
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i) out[i] = Number(v[i], field + "[" + std::to_string(i) + "]", min, max);
    return out;
  }
  const json& Object(const json& v, const std::string& field) const {
    if (!v.is_object()) Fail(field, "expected an object, got " + std::string(v.type_name()));
    return v;
  }
  const json& Array(const json& v, const std::string& field, std::size_t max_size) const {
    if (!v.is_array()) Fail(field, "expected an array, got " + std::string(v.type_name()));
    if (v.size() > max_size) Fail(field, "more than " + std::to_string(max_size) + " entries");
    return v;
  }
  // Rejects fields that are not in `allowed` (typos would otherwise be silently ignored).
  void OnlyKnown(const json& j, const std::string& path, std::initializer_list<const char*> allowed) const {
    for (const auto& item : j.items()) {
      const std::string& key = item.key();  // a named variable: clang 14 cannot capture a binding
      if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; })) {
        std::string list;
        for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
        Fail(path + key, "unknown field (expected one of: " + list + ")");
      }
    }
  }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  const std::map<std::string, int>* lines_;
};

std::array<float, 3> Rgb(const Context& c, const json& v, const std::string& field) {
  const Eigen::Vector3d rgb = c.Vector<3>(v, field, 0.0, 1.0);
  return {static_cast<float>(rgb.x()), static_cast<float>(rgb.y()), static_cast<float>(rgb.z())};
}

Eigen::Quaterniond Orientation(const Context& c, const json& j, const std::string& path) {
  if (!j.contains("orientation_wxyz")) return Eigen::Quaterniond::Identity();
  const Eigen::Vector4d q = c.Vector<4>(j["orientation_wxyz"], path + "orientation_wxyz", -1.0, 1.0);
  if (std::abs(q.norm() - 1.0) > 1e-6) c.Fail(path + "orientation_wxyz", "not a unit quaternion");
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
}

Eigen::Vector3d UnitVector(const Context& c, const json& v, const std::string& field) {
  const Eigen::Vector3d d = c.Vector<3>(v, field, -1e3, 1e3);
  if (d.norm() < 1e-9) c.Fail(field, "zero vector");
  return d.normalized();
}

Eigen::Vector3d Scale(const Context& c, const json& j, const std::string& path) {
  if (!j.contains("mesh_scale")) return Eigen::Vector3d::Ones();
  const json& v = j["mesh_scale"];
  const std::string field = path + "mesh_scale";
  Eigen::Vector3d s = v.is_array() ? c.Vector<3>(v, field, -1e3, 1e3)
                                   : Eigen::Vector3d::Constant(c.Number(v, field, -1e3, 1e3));
  if ((s.array().abs() < 1e-9).any()) c.Fail(field, "zero scale");
  return s;
}

// Where meshes and images live: paths relative to the assets folder, the parent of the scene
// folder.
std::filesystem::path ResolveAsset(const std::filesystem::path& scene_file, const std::string& uri) {
  const std::filesystem::path p(uri);
  if (p.is_absolute()) return p;
  return scene_file.parent_path().parent_path() / p;
}

// Loads (or, without load_meshes, checks the existence of) a mesh; errors name the scene
// file, the field and the mesh path.
std::shared_ptr<const Mesh> MeshOf(const Context& c, const std::string& field,
                                   const std::filesystem::path& path, const Eigen::Vector3d& scale,
                                   bool load) {
  if (!std::filesystem::is_regular_file(path)) {
    c.Fail(field, "mesh file '" + path.string() + "' does not exist");
  }
  if (!load) return nullptr;
  try {
    return std::make_shared<const Mesh>(LoadMesh(path, scale));
  } catch (const SceneError& e) {
    c.Fail(field, e.what());
  }
}

Message ParseMessage(const Context& c, const json& j, const std::string& path) {
  c.Object(j, path.substr(0, path.size() - 1));
  c.OnlyKnown(j, path, {"language", "text", "next_action", "reading", "note"});
  Message m;
  m.language = c.String(j, "language", path);
  if (m.language != "en" && m.language != "ja") c.Fail(path + "language", "'" + m.language + "' is not en or ja");
  m.text = c.String(j, "text", path);
  if (m.text.empty()) c.Fail(path + "text", "must have 1..1023 bytes");
  m.next_action = j.contains("next_action") ? c.String(j, "next_action", path, 511) : "";
  if (m.language == "ja") {
    m.reading = c.String(j, "reading", path, 2047);
    if (m.reading.empty()) c.Fail(path + "reading", "must have 1..2047 bytes");
    if (const auto at = common::FirstOutsideKanaReading(m.reading)) {
      c.Fail(path + "reading", "byte " + std::to_string(*at) +
                                   " is not kana, ASCII, 、 or 。 (the ja voice spells kanji and other signs out in English)");
    }
  } else if (j.contains("reading")) {
    c.Fail(path + "reading", "only a ja message has a reading");
  }
  return m;
}

std::vector<Message> ParseMessages(const Context& c, const json& v, const std::string& field) {
  c.Array(v, field, 16);
  std::vector<Message> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    out.push_back(ParseMessage(c, v[i], field + "[" + std::to_string(i) + "]."));
  }
  return out;
}

Action ParseAction(const Context& c, const json& j, const std::string& field,
                   const std::filesystem::path& scene_dir) {
  c.Object(j, field);
  const std::string path = field + ".";
  c.OnlyKnown(j, path, {"goto", "set_gravity", "title", "messages", "note"});
  Action a;
  if (j.contains("goto")) {
    a.goto_scene = c.String(j, "goto", path, 63);
    // A typo in a target would only show when a visitor presses the control: check it now.
    if (!std::filesystem::exists(scene_dir / (a.goto_scene + ".json"))) {
      c.Fail(path + "goto", "no scene '" + a.goto_scene + "' in " + scene_dir.string());
    }
  }
  if (j.contains("set_gravity")) {
    a.set_gravity = true;
    a.gravity_W_m_per_s2 = c.Vector<3>(j["set_gravity"], path + "set_gravity", -100.0, 100.0);
  }
  if (j.contains("title")) a.title = c.String(j, "title", path, 255);
  if (j.contains("messages")) a.messages = ParseMessages(c, j["messages"], path + "messages");
  if (a.empty()) c.Fail(field, "an action needs goto, set_gravity, title or messages");
  return a;
}

// [ {language: en | ja, text} ]: one text per language, each 1..max_bytes bytes.
std::vector<LocalText> ParseTexts(const Context& c, const json& v, const std::string& field, std::size_t max_bytes) {
  c.Array(v, field, 8);
  std::vector<LocalText> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const std::string tpath = field + "[" + std::to_string(i) + "].";
    c.Object(v[i], tpath.substr(0, tpath.size() - 1));
    c.OnlyKnown(v[i], tpath, {"language", "text", "note"});
    LocalText t;
    t.language = c.String(v[i], "language", tpath);
    if (t.language != "en" && t.language != "ja") c.Fail(tpath + "language", "'" + t.language + "' is not en or ja");
    for (const auto& earlier : out) {
      if (earlier.language == t.language) c.Fail(tpath + "language", "a second '" + t.language + "' text");
    }
    t.text = c.String(v[i], "text", tpath, max_bytes);
    if (t.text.empty()) c.Fail(tpath + "text", "must have 1.." + std::to_string(max_bytes) + " bytes");
    out.push_back(std::move(t));
  }
  return out;
}

// Labels are a few words beside an object.
constexpr std::size_t kMaxLabelBytes = 127;

// One page of a book: {text [ {language, text} ], image, action}. The action goes to `action`.
BookPage ParsePage(const Context& c, const json& j, const std::string& field, const std::filesystem::path& file,
                   Action& action) {
  c.Object(j, field);
  const std::string path = field + ".";
  c.OnlyKnown(j, path, {"text", "image", "action", "note"});
  BookPage page;
  if (j.contains("text")) page.text = ParseTexts(c, j["text"], path + "text", 1023);
  if (j.contains("image")) {
    page.image_uri = c.String(j, "image", path, 127);
    page.image_path = ResolveAsset(file, page.image_uri);
    std::string ext = page.image_path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
    if (ext != ".png") c.Fail(path + "image", "'" + page.image_uri + "' is not a PNG file (.png)");
    if (!std::filesystem::is_regular_file(page.image_path)) {
      c.Fail(path + "image", "image file '" + page.image_path.string() + "' does not exist");
    }
  }
  if (j.contains("action")) action = ParseAction(c, j["action"], path + "action", file.parent_path());
  if (page.text.empty() && page.image_uri.empty() && action.empty()) {
    c.Fail(field, "a page needs text, an image or an action");
  }
  return page;
}

// A node rule of a deformable (fixed, or a beat's driven): {nodes [indices]} or
// {plane_point_m [3], plane_normal [3]} (the side behind the plane).
void ParseNodesOrPlane(const Context& c, const json& f, const std::string& fpath, FixedRule& rule) {
  if (f.contains("nodes")) {
    rule.kind = FixedRule::Kind::kNodes;
    const json& nodes = c.Array(f["nodes"], fpath + "nodes", 1'000'000);
    if (nodes.empty()) c.Fail(fpath + "nodes", "empty");
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      rule.nodes.push_back(c.Integer(nodes[i], fpath + "nodes[" + std::to_string(i) + "]", 0, 100'000'000));
    }
  } else {
    rule.kind = FixedRule::Kind::kHalfSpace;
    rule.point_O_m = c.Vector<3>(c.Require(f, "plane_point_m", fpath), fpath + "plane_point_m", -10.0, 10.0);
    rule.normal_O = UnitVector(c, c.Require(f, "plane_normal", fpath), fpath + "plane_normal");
  }
}

SceneObject ParseObject(const Context& c, const json& j, const std::string& path,
                        const std::filesystem::path& file, const LoadOptions& options) {
  c.Object(j, path.substr(0, path.size() - 1));
  c.OnlyKnown(j, path, {"id", "kind", "shape", "radius_m", "half_extent_m", "mesh", "mesh_scale",
                        "position_m", "orientation_wxyz", "mass_kg", "rgb", "material", "fixed",
                        "motion", "beat", "label", "appearance", "note"});
  SceneObject o;
  o.line = c.LineOf(path.substr(0, path.size() - 1));
  o.id = c.String(j, "id", path, 63);
  if (o.id.empty()) c.Fail(path + "id", "must have 1..63 characters");
  const std::string kind = c.String(j, "kind", path);
  if (kind == "rigid") o.kind = ObjectKind::kRigid;
  else if (kind == "deformable") o.kind = ObjectKind::kDeformable;
  else if (kind == "control") c.Fail(path + "kind", "controls are declared in 'controls', not 'objects'");
  else c.Fail(path + "kind", "'" + kind + "' is not one of rigid, deformable");
  const std::string shape = c.String(j, "shape", path);
  if (shape == "sphere") {
    o.shape = Shape::kSphere;
    o.half_extent_m.x() = c.Number(c.Require(j, "radius_m", path), path + "radius_m", 1e-4, 10.0);
  } else if (shape == "box") {
    o.shape = Shape::kBox;
    o.half_extent_m = c.Vector<3>(c.Require(j, "half_extent_m", path), path + "half_extent_m", 1e-4, 10.0);
  } else if (shape == "mesh") {
    o.shape = Shape::kMesh;
    o.mesh_uri = c.String(j, "mesh", path, 127);  // idl: string<128> mesh_uri
    o.mesh_scale = Scale(c, j, path);
    o.mesh_path = ResolveAsset(file, o.mesh_uri);
    o.mesh = MeshOf(c, path + "mesh", o.mesh_path, o.mesh_scale, options.load_meshes);
    if (o.mesh) {
      Eigen::AlignedBox3d box;
      for (const auto& v : o.mesh->vertices_m) box.extend(v);
      o.half_extent_m = 0.5 * box.sizes();
      o.mesh_center_O_m = box.center();
    }
  } else {
    c.Fail(path + "shape", "'" + shape + "' is not one of sphere, box, mesh");
  }
  for (const char* k : {"radius_m", "half_extent_m", "mesh", "mesh_scale"}) {
    const bool wanted = (shape == "sphere" && std::string(k) == "radius_m") ||
                        (shape == "box" && std::string(k) == "half_extent_m") ||
                        (shape == "mesh" && (std::string(k) == "mesh" || std::string(k) == "mesh_scale"));
    if (j.contains(k) && !wanted) c.Fail(path + k, "not used by shape '" + shape + "'");
  }
  o.p_WO_m = c.Vector<3>(c.Require(j, "position_m", path), path + "position_m", -100.0, 100.0);
  o.q_WO = Orientation(c, j, path);
  o.mass_kg = c.Number(j, "mass_kg", path, 0.0, 1000.0, 0.0);
  if (j.contains("rgb")) o.rgb = Rgb(c, j["rgb"], path + "rgb");
  if (j.contains("label")) o.label = ParseTexts(c, j["label"], path + "label", kMaxLabelBytes);
  if (j.contains("appearance")) {
    const std::string ap = path + "appearance.";
    const json& a = c.Object(j["appearance"], path + "appearance");
    c.OnlyKnown(a, ap, {"specular", "shininess", "opacity", "note"});
    o.appearance.specular = c.Number(a, "specular", ap, 0.0, 1.0, o.appearance.specular);
    o.appearance.shininess = c.Number(a, "shininess", ap, 1.0, 128.0, o.appearance.shininess);
    o.appearance.opacity = c.Number(a, "opacity", ap, 0.05, 1.0, o.appearance.opacity);
  }

  const std::string mpath = path + "material.";
  if (o.kind == ObjectKind::kRigid && j.contains("material")) {
    const json& m = c.Object(j["material"], path + "material");
    c.OnlyKnown(m, mpath, {"stiffness_N_per_m", "damping_N_s_per_m", "mu_static", "mu_kinetic", "note"});
    RigidMaterial& r = o.rigid;
    r.stiffness_N_per_m = c.Number(m, "stiffness_N_per_m", mpath, 1.0, 1e6, r.stiffness_N_per_m);
    r.damping_N_s_per_m = c.Number(m, "damping_N_s_per_m", mpath, 0.0, 1e4, r.damping_N_s_per_m);
    r.mu_static = c.Number(m, "mu_static", mpath, 0.0, 5.0, r.mu_static);
    r.mu_kinetic = c.Number(m, "mu_kinetic", mpath, 0.0, 5.0, std::min(r.mu_kinetic, r.mu_static));
    if (r.mu_kinetic > r.mu_static) c.Fail(mpath + "mu_kinetic", "larger than mu_static");
  }
  if (o.kind == ObjectKind::kDeformable) {
    const json& m = c.Object(c.Require(j, "material", path), path + "material");
    c.OnlyKnown(m, mpath, {"E_Pa", "nu", "density_kg_per_m3", "mu_static", "mu_kinetic", "stiffening_table", "note"});
    DeformableMaterial& d = o.deformable;
    d.E_Pa = c.Number(c.Require(m, "E_Pa", mpath), mpath + "E_Pa", 100.0, 1e12);
    d.nu = c.Number(c.Require(m, "nu", mpath), mpath + "nu", 0.0, 0.499);
    d.density_kg_per_m3 = c.Number(m, "density_kg_per_m3", mpath, 1.0, 1e5, 1000.0);
    d.mu_static = c.Number(m, "mu_static", mpath, 0.0, 5.0, 0.0);
    d.mu_kinetic = c.Number(m, "mu_kinetic", mpath, 0.0, 5.0, d.mu_static);
    if (d.mu_kinetic > d.mu_static) c.Fail(mpath + "mu_kinetic", "larger than mu_static");
    if (m.contains("stiffening_table")) {
      d.stiffening_table_uri = c.String(m, "stiffening_table", mpath, 255);
      d.stiffening_table_path = ResolveAsset(file, d.stiffening_table_uri);
      if (!std::filesystem::is_regular_file(d.stiffening_table_path)) {
        c.Fail(mpath + "stiffening_table", "no such file: " + d.stiffening_table_path.string());
      }
    }

    const std::string fpath = path + "fixed.";
    const json& f = c.Object(c.Require(j, "fixed", path), path + "fixed");
    c.OnlyKnown(f, fpath, {"below_m", "plane_point_m", "plane_normal", "nodes", "note"});
    const int rules = int(f.contains("below_m")) + int(f.contains("plane_point_m") || f.contains("plane_normal")) +
                      int(f.contains("nodes"));
    if (rules != 1) c.Fail(path + "fixed", "give exactly one of below_m, plane_point_m + plane_normal, nodes");
    FixedRule& rule = o.fixed;
    if (f.contains("below_m")) {
      rule.kind = FixedRule::Kind::kHalfSpace;
      rule.point_O_m = Eigen::Vector3d(0, 0, c.Number(f["below_m"], fpath + "below_m", -10.0, 10.0));
      rule.normal_O = Eigen::Vector3d::UnitZ();
    } else {
      ParseNodesOrPlane(c, f, fpath, rule);
    }
    if (rule.kind == FixedRule::Kind::kHalfSpace && o.mesh) {
      // A rule that fixes no surface node leaves the FEM model free to float (singular K).
      const bool any = std::any_of(o.mesh->vertices_m.begin(), o.mesh->vertices_m.end(),
                                   [&](const Eigen::Vector3d& v) { return rule.FixesPoint(v); });
      if (!any) c.Fail(path + "fixed", "fixes no vertex of mesh '" + o.mesh_path.string() + "'");
    }
  } else if (j.contains("fixed")) {
    c.Fail(path + "fixed", "only deformable objects have fixed nodes");
  }
  if (j.contains("beat")) {
    const std::string bp = path + "beat.";
    const json& b = c.Object(j["beat"], path + "beat");
    if (o.kind != ObjectKind::kDeformable) c.Fail(path + "beat", "only deformable objects beat");
    c.OnlyKnown(b, bp, {"driven", "displacement_m", "rotation_rad", "center_m", "period_s", "phase_rad", "note"});
    const std::string dp = bp + "driven.";
    const json& d = c.Object(c.Require(b, "driven", bp), bp + "driven");
    c.OnlyKnown(d, dp, {"plane_point_m", "plane_normal", "nodes", "note"});
    FixedRule& rule = o.beat.driven;
    if (d.contains("nodes") == (d.contains("plane_point_m") || d.contains("plane_normal"))) {
      c.Fail(bp + "driven", "give exactly one of plane_point_m + plane_normal, nodes");
    }
    ParseNodesOrPlane(c, d, dp, rule);
    if (rule.kind == FixedRule::Kind::kHalfSpace && o.mesh &&
        std::none_of(o.mesh->vertices_m.begin(), o.mesh->vertices_m.end(),
                     [&](const Eigen::Vector3d& v) { return rule.FixesPoint(v) && !o.fixed.FixesPoint(v); })) {
      c.Fail(bp + "driven", "drives no vertex of mesh '" + o.mesh_path.string() + "' that is not fixed");
    }
    if (b.contains("displacement_m")) {
      o.beat.displacement_O_m = c.Vector<3>(b["displacement_m"], bp + "displacement_m", -0.1, 0.1);
    }
    if (b.contains("rotation_rad")) o.beat.rotation_O_rad = c.Vector<3>(b["rotation_rad"], bp + "rotation_rad", -0.5, 0.5);
    if (b.contains("center_m")) o.beat.center_O_m = c.Vector<3>(b["center_m"], bp + "center_m", -10.0, 10.0);
    if (!(o.beat.displacement_O_m.norm() > 0.0) && !(o.beat.rotation_O_rad.norm() > 0.0)) {
      c.Fail(path + "beat", "needs a non-zero displacement_m or rotation_rad: nothing beats");
    }
    o.beat.period_s = c.Number(c.Require(b, "period_s", bp), bp + "period_s", 0.05, 3600.0);
    o.beat.phase_rad = c.Number(b, "phase_rad", bp, -10.0, 10.0, 0.0);
  }
  if (j.contains("motion")) {
    const std::string mp = path + "motion.";
    const json& m = c.Object(j["motion"], path + "motion");
    c.OnlyKnown(m, mp, {"direction", "amplitude_m", "period_s", "phase_rad", "note"});
    o.motion.direction_W = UnitVector(c, c.Require(m, "direction", mp), mp + "direction");
    o.motion.amplitude_m = c.Number(c.Require(m, "amplitude_m", mp), mp + "amplitude_m", 0.0, 1.0);
    o.motion.period_s = c.Number(c.Require(m, "period_s", mp), mp + "period_s", 0.01, 3600.0);
    o.motion.phase_rad = c.Number(m, "phase_rad", mp, -10.0, 10.0, 0.0);
  }
  return o;
}

ControlSpec ParseControl(const Context& c, const json& j, const std::string& path,
                         const std::filesystem::path& file, const LoadOptions& options) {
  c.Object(j, path.substr(0, path.size() - 1));
  ControlSpec s;
  s.line = c.LineOf(path.substr(0, path.size() - 1));
  s.id = c.String(j, "id", path, 31);
  if (s.id.empty()) c.Fail(path + "id", "must have 1..31 characters");
  const std::string type = c.String(j, "type", path);
  const auto common = {"id", "type", "position_m", "orientation_wxyz", "size_m", "rgb", "mesh",
                       "mesh_scale", "approach_margin_m", "max_force_N", "label", "note"};
  std::vector<const char*> allowed(common);
  const std::initializer_list<const char*> push_keys = {
      "travel_m", "click_at_m", "release_at_m", "stiffness_N_per_m", "preload_N", "click_drop",
      "stop_stiffness_N_per_m", "action"};
  if (type == "button" || type == "arrow") {
    s.type = type == "button" ? ControlType::kButton : ControlType::kArrow;
    allowed.insert(allowed.end(), push_keys);
    if (s.type == ControlType::kArrow) {
      // An arrow is a short, stiff push: it goes as soon as it is pushed.
      s.push = {.travel_m = 0.0015, .click_at_m = 0.001, .release_at_m = 0.0005,
                .stiffness_N_per_m = 1500.0, .preload_N = 0.3, .click_drop = 0.0,
                .stop_stiffness_N_per_m = 4000.0};
      s.size_m = Eigen::Vector3d(0.09, 0.06, 0.01);
    } else {
      s.size_m = Eigen::Vector3d(0.04, 0.04, 0.012);
    }
  } else if (type == "lever") {
    s.type = ControlType::kLever;
    allowed.insert(allowed.end(), {"min_angle_rad", "max_angle_rad", "detents", "detent_torque_N_m",
                                   "settle_rate_rad_per_s", "stop_stiffness_N_per_m", "detent_actions"});
    s.size_m = Eigen::Vector3d(0.02, 0.012, 0.09);
  } else if (type == "book") {
    s.type = ControlType::kBook;
    allowed.insert(allowed.end(), {"pages", "open_angle_rad", "swipe_m", "surface_stiffness_N_per_m",
                                   "page_drag_N", "action", "page_actions"});
    s.size_m = Eigen::Vector3d(0.10, 0.14, 0.03);
  } else {
    c.Fail(path + "type", "'" + type + "' is not one of button, arrow, lever, book");
  }
  for (const auto& item : j.items()) {
    const std::string& key = item.key();  // a named variable: clang 14 cannot capture a binding
    if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; })) {
      c.Fail(path + key, "unknown field for a " + type);
    }
  }
  s.p_WC_m = c.Vector<3>(c.Require(j, "position_m", path), path + "position_m", -100.0, 100.0);
  s.q_WC = Orientation(c, j, path);
  if (j.contains("size_m")) s.size_m = c.Vector<3>(j["size_m"], path + "size_m", 1e-3, 1.0);
  if (j.contains("rgb")) s.rgb = Rgb(c, j["rgb"], path + "rgb");
  if (j.contains("label")) s.label = ParseTexts(c, j["label"], path + "label", kMaxLabelBytes);
  s.approach_margin_m = c.Number(j, "approach_margin_m", path, 0.0, 0.5, s.approach_margin_m);
  s.max_force_N = c.Number(j, "max_force_N", path, 0.0, 20.0, s.max_force_N);
  if (j.contains("mesh")) {
    s.mesh_uri = c.String(j, "mesh", path, 127);
    s.mesh_scale = Scale(c, j, path);
    s.mesh_path = ResolveAsset(file, s.mesh_uri);
    s.mesh = MeshOf(c, path + "mesh", s.mesh_path, s.mesh_scale, options.load_meshes);
  }
  const std::filesystem::path scene_dir = file.parent_path();
  if (s.type == ControlType::kButton || s.type == ControlType::kArrow) {
    auto& p = s.push;
    p.travel_m = c.Number(j, "travel_m", path, 1e-4, 0.05, p.travel_m);
    p.click_at_m = c.Number(j, "click_at_m", path, 1e-5, 0.05, p.click_at_m);
    p.release_at_m = c.Number(j, "release_at_m", path, 0.0, 0.05, p.release_at_m);
    p.stiffness_N_per_m = c.Number(j, "stiffness_N_per_m", path, 0.0, 1e5, p.stiffness_N_per_m);
    p.preload_N = c.Number(j, "preload_N", path, 0.0, 10.0, p.preload_N);
    p.click_drop = c.Number(j, "click_drop", path, 0.0, 0.9, p.click_drop);
    p.stop_stiffness_N_per_m = c.Number(j, "stop_stiffness_N_per_m", path, 1.0, 1e6, p.stop_stiffness_N_per_m);
    if (p.click_at_m > p.travel_m) c.Fail(path + "click_at_m", "beyond travel_m");
    if (p.release_at_m >= p.click_at_m) c.Fail(path + "release_at_m", "must be below click_at_m");
    if (j.contains("action")) s.action = ParseAction(c, j["action"], path + "action", scene_dir);
  } else if (s.type == ControlType::kLever) {
    auto& l = s.lever;
    l.min_angle_rad = c.Number(j, "min_angle_rad", path, -3.0, 3.0, l.min_angle_rad);
    l.max_angle_rad = c.Number(j, "max_angle_rad", path, -3.0, 3.0, l.max_angle_rad);
    if (l.max_angle_rad - l.min_angle_rad < 0.05) c.Fail(path + "max_angle_rad", "must exceed min_angle_rad by 0.05 rad");
    if (j.contains("detents")) l.detents = c.Integer(j["detents"], path + "detents", 2, 16);
    l.detent_torque_N_m = c.Number(j, "detent_torque_N_m", path, 0.0, 5.0, l.detent_torque_N_m);
    l.settle_rate_rad_per_s = c.Number(j, "settle_rate_rad_per_s", path, 0.01, 100.0, l.settle_rate_rad_per_s);
    l.stop_stiffness_N_per_m = c.Number(j, "stop_stiffness_N_per_m", path, 1.0, 1e6, l.stop_stiffness_N_per_m);
    if (j.contains("detent_actions")) {
      const std::string f = path + "detent_actions";
      const json& a = c.Array(j["detent_actions"], f, 16);
      if (static_cast<int>(a.size()) != l.detents) {
        c.Fail(f, "has " + std::to_string(a.size()) + " entries for " + std::to_string(l.detents) + " detents");
      }
      for (std::size_t i = 0; i < a.size(); ++i) {
        s.detent_actions.push_back(ParseAction(c, a[i], f + "[" + std::to_string(i) + "]", scene_dir));
      }
    }
  } else {
    auto& b = s.book;
    if (j.contains("pages") && j["pages"].is_array()) {
      // Pages with their content: each carries its own action.
      const std::string f = path + "pages";
      const json& pages = c.Array(j["pages"], f, kMaxBookPages);
      if (pages.empty()) c.Fail(f, "a book needs at least one page");
      if (j.contains("page_actions")) c.Fail(path + "page_actions", "give each page's action in pages[i].action");
      b.pages = static_cast<int>(pages.size());
      for (std::size_t i = 0; i < pages.size(); ++i) {
        Action action;
        s.page_content.push_back(ParsePage(c, pages[i], f + "[" + std::to_string(i) + "]", file, action));
        s.page_actions.push_back(std::move(action));
      }
    } else if (j.contains("pages")) {
      b.pages = c.Integer(j["pages"], path + "pages", 1, 1000);
    }
    b.open_angle_rad = c.Number(j, "open_angle_rad", path, 0.2, 3.0, b.open_angle_rad);
    b.swipe_m = c.Number(j, "swipe_m", path, 0.005, 0.3, b.swipe_m);
    b.surface_stiffness_N_per_m = c.Number(j, "surface_stiffness_N_per_m", path, 1.0, 1e6, b.surface_stiffness_N_per_m);
    b.page_drag_N = c.Number(j, "page_drag_N", path, 0.0, 5.0, b.page_drag_N);
    if (j.contains("action")) s.action = ParseAction(c, j["action"], path + "action", scene_dir);
    if (j.contains("page_actions")) {
      const std::string f = path + "page_actions";
      const json& a = c.Array(j["page_actions"], f, static_cast<std::size_t>(b.pages));
      for (std::size_t i = 0; i < a.size(); ++i) {
        s.page_actions.push_back(ParseAction(c, a[i], f + "[" + std::to_string(i) + "]", scene_dir));
      }
    }
  }
  return s;
}

// The visual of a control, so that nodes that only draw objects show it.
SceneObject ControlVisual(const ControlSpec& s) {
  SceneObject o;
  o.id = s.id;
  o.kind = ObjectKind::kControl;
  o.p_WO_m = s.p_WC_m;
  o.q_WO = s.q_WC;
  o.rgb = s.rgb;
  o.line = s.line;
  o.label = s.label;
  o.half_extent_m = 0.5 * s.size_m;
  if (!s.mesh_uri.empty()) {
    o.shape = Shape::kMesh;
    o.mesh_uri = s.mesh_uri;
    o.mesh_path = s.mesh_path;
    o.mesh_scale = s.mesh_scale;
    o.mesh = s.mesh;
  } else {
    // A box centred on the control's body: below the top face of buttons, arrows and books,
    // above the hinge of a lever.
    o.shape = Shape::kBox;
    const double up = s.type == ControlType::kLever ? 0.5 * s.size_m.z() : -0.5 * s.size_m.z();
    o.p_WO_m = s.p_WC_m + s.q_WC * Eigen::Vector3d(0.0, 0.0, up);
  }
  return o;
}

}  // namespace

const std::string& TextIn(const std::vector<LocalText>& texts, const std::string& language) noexcept {
  static const std::string kNone;
  for (const auto& t : texts) {
    if (t.language == language) return t.text;
  }
  for (const auto& t : texts) {
    if (t.language == "en") return t.text;
  }
  return texts.empty() ? kNone : texts.front().text;
}

std::vector<Message> AllMessages(const Scene& scene) {
  std::vector<Message> all = scene.messages;
  const auto add = [&all](const Action& a) { all.insert(all.end(), a.messages.begin(), a.messages.end()); };
  for (const auto& c : scene.controls) {
    add(c.action);
    for (const auto& a : c.detent_actions) add(a);
    for (const auto& a : c.page_actions) add(a);
  }
  return all;
}

Eigen::Vector3d Motion::Offset_W(double t_s) const noexcept {
  if (!active()) return Eigen::Vector3d::Zero();
  return amplitude_m * std::sin(2.0 * std::numbers::pi * t_s / period_s + phase_rad) * direction_W;
}

double Beat::Scale(double t_s) const noexcept {
  if (!active()) return 0.0;
  return std::sin(2.0 * std::numbers::pi * t_s / period_s + phase_rad);
}

double FlatPunchDepth_m(double force_N, double a_m, double E_Pa, double nu) noexcept {
  return force_N * (1.0 - nu * nu) / (2.0 * a_m * E_Pa);
}

Scene LoadScene(const std::filesystem::path& file, const LoadOptions& options) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SceneError(file.string() + ": cannot open scene file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();

  ParsedJson parsed;
  const LineIndex index(text);
  const char* furthest = text.data();
  LineRecordingSax sax(index, text.data(), &furthest, &parsed);
  const bool ok = json::sax_parse(TrackingIterator(text.data(), &furthest),
                                  TrackingIterator(text.data() + text.size(), &furthest), &sax);
  if (!ok) throw SceneError(file.string() + ":" + std::to_string(sax.error_line()) + ": " + sax.error());

  const json& root = parsed.root;
  const Context c(file.string(), &parsed.lines);
  c.Object(root, "");
  c.OnlyKnown(root, "", {"name", "title", "gravity_m_per_s2", "objects", "controls", "messages", "note"});
  Scene s;
  s.file = file;
  s.name = c.String(root, "name", "", 63);
  s.title = root.contains("title") ? c.String(root, "title", "", 255) : s.name;
  if (root.contains("gravity_m_per_s2")) {
    s.gravity_W_m_per_s2 = c.Vector<3>(root["gravity_m_per_s2"], "gravity_m_per_s2", -100.0, 100.0);
  }
  std::set<std::string> ids;
  if (root.contains("objects")) {
    const json& objects = c.Array(root["objects"], "objects", 64);
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const std::string path = "objects[" + std::to_string(i) + "].";
      SceneObject o = ParseObject(c, objects[i], path, file, options);
      if (!ids.insert(o.id).second) c.Fail(path + "id", "duplicate id '" + o.id + "'");
      s.objects.push_back(std::move(o));
    }
  }
  if (root.contains("controls")) {
    const json& controls = c.Array(root["controls"], "controls", 32);
    for (std::size_t i = 0; i < controls.size(); ++i) {
      const std::string path = "controls[" + std::to_string(i) + "].";
      ControlSpec spec = ParseControl(c, controls[i], path, file, options);
      if (!ids.insert(spec.id).second) c.Fail(path + "id", "duplicate id '" + spec.id + "'");
      s.objects.push_back(ControlVisual(spec));
      s.controls.push_back(std::move(spec));
    }
  }
  // The scene-state message (idl: sequence<SceneObject, 64>) carries objects and control
  // visuals together.
  if (s.objects.size() > 64) {
    c.Fail("controls", std::to_string(s.objects.size()) + " objects and controls together; at most 64");
  }
  const json& messages = c.Require(root, "messages", "");
  if (!messages.is_array() || messages.empty()) c.Fail("messages", "expected a non-empty array");
  s.messages = ParseMessages(c, messages, "messages");
  return s;
}

std::filesystem::path DefaultSceneDir() { return common::AssetsDir() / "scenes"; }

std::vector<std::string> SceneNames(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return names;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

Scene LoadSceneByName(const std::string& name, const std::filesystem::path& dir,
                      const LoadOptions& options) {
  const auto file = dir / (name + ".json");
  if (!std::filesystem::exists(file)) {
    std::string available;
    for (const auto& n : SceneNames(dir)) available += " " + n;
    throw SceneError("unknown scene '" + name + "' (no " + file.string() + "); available:" +
                     (available.empty() ? " none" : available));
  }
  return LoadScene(file, options);
}

}  // namespace handshare::scene
