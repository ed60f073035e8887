#include "handshare/fem/mesh_io.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <utility>
#include <vector>

#include "handshare/fem/error.hpp"

namespace handshare::fem {
namespace {

namespace fs = std::filesystem;

// Reads a text file line by line, counting lines, so that every error names FILE:LINE.
class LineReader {
 public:
  explicit LineReader(const fs::path& file) : file_(file.string()), in_(file) {
    if (!in_) {
      throw InputError(file_, 0, "file", std::string("cannot open: ") + std::strerror(errno));
    }
  }
  bool Next(std::string& line) {
    if (!std::getline(in_, line)) return false;
    ++line_;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  }
  // Next line that is not blank; fails with `what` at end of file.
  std::string NextNonBlank(const std::string& field, const std::string& what) {
    std::string line;
    while (Next(line)) {
      if (line.find_first_not_of(" \t") != std::string::npos) return line;
    }
    Fail(field, "unexpected end of file: " + what);
  }
  [[noreturn]] void Fail(const std::string& field, const std::string& what) const {
    throw InputError(file_, line_, field, what);
  }
  std::size_t line() const noexcept { return line_; }
  const std::string& file() const noexcept { return file_; }

 private:
  std::string file_;
  std::ifstream in_;
  std::size_t line_ = 0;
};

std::string_view Trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

std::vector<std::string_view> SplitWs(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

std::vector<std::string_view> SplitComma(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (true) {
    const auto j = s.find(',', i);
    out.push_back(Trim(s.substr(i, j == std::string_view::npos ? std::string_view::npos : j - i)));
    if (j == std::string_view::npos) break;
    i = j + 1;
  }
  return out;
}

std::int64_t ParseInt(std::string_view tok, const LineReader& r, const std::string& field) {
  std::int64_t v = 0;
  const auto* end = tok.data() + tok.size();
  auto [ptr, ec] = std::from_chars(tok.data(), end, v);
  if (tok.empty() || ec != std::errc() || ptr != end) {
    r.Fail(field, "expected an integer, got '" + std::string(tok) + "'");
  }
  return v;
}

double ParseDouble(std::string_view tok, const LineReader& r, const std::string& field) {
  double v = 0.0;
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  const auto* end = tok.data() + tok.size();
  auto [ptr, ec] = std::from_chars(tok.data(), end, v);
  if (tok.empty() || ec != std::errc() || ptr != end) {
    // Fortran-style exponents (1.0D+03) appear in some .inp writers.
    std::string s(tok);
    std::replace(s.begin(), s.end(), 'D', 'E');
    std::replace(s.begin(), s.end(), 'd', 'e');
    auto [p2, ec2] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec2 != std::errc() || p2 != s.data() + s.size()) {
      r.Fail(field, "expected a number, got '" + std::string(tok) + "'");
    }
  }
  if (!std::isfinite(v)) r.Fail(field, "not a finite number: '" + std::string(tok) + "'");
  return v;
}

// Elements and node sets refer to node ids; they are resolved after all nodes are read so that
// file order does not matter, keeping the line of each reference for the error message.
struct PendingTet {
  std::array<std::int64_t, 4> ids;
  std::int64_t element_id;
  std::size_t line;
};
struct PendingSet {
  std::vector<std::int64_t> ids;
  std::vector<std::size_t> lines;
};

struct MeshBuilder {
  explicit MeshBuilder(std::string f) : file(std::move(f)) {}
  std::string file;
  std::vector<Eigen::Vector3d> p;
  std::vector<std::int64_t> ids;
  std::vector<std::size_t> node_lines;
  std::vector<PendingTet> tets;
  std::map<std::string, PendingSet> sets;

  void AddNode(std::int64_t id, const Eigen::Vector3d& x, std::size_t line) {
    ids.push_back(id);
    p.push_back(x);
    node_lines.push_back(line);
  }

  TetMesh Build() {
    std::unordered_map<std::int64_t, std::int32_t> index;
    index.reserve(ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) {
      if (!index.emplace(ids[i], static_cast<std::int32_t>(i)).second) {
        throw InputError(file, node_lines[i], "node id",
                         "duplicate node id " + std::to_string(ids[i]));
      }
    }
    if (tets.empty()) throw InputError(file, 0, "elements", "no 4-node tetrahedra in the file");
    std::vector<Tet> t;
    t.reserve(tets.size());
    for (const PendingTet& pt : tets) {
      Tet tet;
      for (int v = 0; v < 4; ++v) {
        auto it = index.find(pt.ids[v]);
        if (it == index.end()) {
          throw InputError(file, pt.line, "element " + std::to_string(pt.element_id) + " node " +
                                              std::to_string(v + 1),
                           "unknown node id " + std::to_string(pt.ids[v]));
        }
        tet[v] = it->second;
      }
      const double vol = SignedVolume(p[tet[0]], p[tet[1]], p[tet[2]], p[tet[3]]);
      if (!(vol > 0.0)) {
        throw InputError(file, pt.line, "element " + std::to_string(pt.element_id),
                         std::string(vol < 0.0 ? "inverted tetrahedron (negative volume "
                                               : "degenerate tetrahedron (volume ") +
                             std::to_string(vol) + " m^3)");
      }
      t.push_back(tet);
    }
    std::vector<std::pair<std::string, std::vector<std::int32_t>>> resolved;
    for (auto& [name, set] : sets) {
      std::vector<std::int32_t> idx;
      for (std::size_t i = 0; i < set.ids.size(); ++i) {
        auto it = index.find(set.ids[i]);
        if (it == index.end()) {
          throw InputError(file, set.lines[i], "node set " + name,
                           "unknown node id " + std::to_string(set.ids[i]));
        }
        idx.push_back(it->second);
      }
      resolved.emplace_back(name, std::move(idx));
    }
    TetMesh mesh(std::move(p), std::move(t), std::move(ids), file);
    for (auto& [name, idx] : resolved) mesh.SetNodeSet(name, std::move(idx));
    return mesh;
  }
};

std::string Upper(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return u;
}

}  // namespace

// ---------------------------------------------------------------- Gmsh 2.2 ASCII

TetMesh ReadGmshMsh(const fs::path& path) {
  LineReader r(path);
  MeshBuilder b(r.file());
  std::map<std::int64_t, std::string> physical_names;
  std::map<std::int64_t, PendingSet> physical_nodes;
  bool have_format = false;
  bool have_nodes = false;
  std::string line;
  // Node count of the lower-dimensional Gmsh element types (points, lines, triangles, quads and
  // their higher-order versions), which are skipped except for their physical groups.
  static const std::map<std::int64_t, int> kLowerDim = {
      {1, 2},  {2, 3},  {3, 4},  {8, 3},  {9, 6},  {10, 9}, {15, 1}, {16, 8},  {20, 9},
      {21, 10}, {22, 12}, {23, 15}, {24, 15}, {25, 21}, {26, 4}, {27, 5}, {28, 6}};

  while (r.Next(line)) {
    const std::string_view t = Trim(line);
    if (t.empty()) continue;
    if (t == "$MeshFormat") {
      const std::string line_1 = r.NextNonBlank("$MeshFormat", "missing version line");
        const auto tok = SplitWs(line_1);
      if (tok.size() < 3) r.Fail("$MeshFormat", "expected 'version file-type data-size'");
      if (tok[0].substr(0, 2) != "2.") {
        r.Fail("version", "MSH version " + std::string(tok[0]) +
                              " not supported: export as MSH 2.2 ASCII (gmsh -format msh22)");
      }
      if (tok[1] != "0") r.Fail("file-type", "binary MSH not supported: export as ASCII");
      if (Trim(r.NextNonBlank("$MeshFormat", "missing $EndMeshFormat")) != "$EndMeshFormat") {
        r.Fail("$MeshFormat", "expected $EndMeshFormat");
      }
      have_format = true;
    } else if (t == "$PhysicalNames") {
      const auto n = ParseInt(Trim(r.NextNonBlank("$PhysicalNames", "missing count")), r,
                              "number of physical names");
      for (std::int64_t i = 0; i < n; ++i) {
        const std::string l = r.NextNonBlank("$PhysicalNames", "too few physical names");
        const auto tok = SplitWs(l);
        if (tok.size() < 3) r.Fail("physical name", "expected 'dimension tag \"name\"'");
        const auto tag = ParseInt(tok[1], r, "physical tag");
        const auto q0 = l.find('"');
        const auto q1 = l.rfind('"');
        if (q0 == std::string::npos || q1 <= q0) r.Fail("physical name", "name must be quoted");
        physical_names[tag] = l.substr(q0 + 1, q1 - q0 - 1);
      }
      if (Trim(r.NextNonBlank("$PhysicalNames", "missing $EndPhysicalNames")) !=
          "$EndPhysicalNames") {
        r.Fail("$PhysicalNames", "expected $EndPhysicalNames (count too small?)");
      }
    } else if (t == "$Nodes") {
      if (!have_format) r.Fail("$MeshFormat", "$Nodes before $MeshFormat");
      const auto n = ParseInt(Trim(r.NextNonBlank("$Nodes", "missing count")), r, "number of nodes");
      if (n < 0) r.Fail("number of nodes", "negative");
      for (std::int64_t i = 0; i < n; ++i) {
        const std::string line_2 = r.NextNonBlank("$Nodes", "fewer nodes than the count says");
        const auto tok = SplitWs(line_2);
        if (tok.size() != 4) r.Fail("node", "expected 'id x y z', got " + std::to_string(tok.size()) + " fields");
        const auto id = ParseInt(tok[0], r, "node id");
        b.AddNode(id,
                  {ParseDouble(tok[1], r, "x"), ParseDouble(tok[2], r, "y"),
                   ParseDouble(tok[3], r, "z")},
                  r.line());
      }
      if (Trim(r.NextNonBlank("$Nodes", "missing $EndNodes")) != "$EndNodes") {
        r.Fail("$Nodes", "expected $EndNodes (node count too small?)");
      }
      have_nodes = true;
    } else if (t == "$Elements") {
      if (!have_nodes) r.Fail("$Nodes", "$Elements before $Nodes");
      const auto n = ParseInt(Trim(r.NextNonBlank("$Elements", "missing count")), r,
                              "number of elements");
      for (std::int64_t i = 0; i < n; ++i) {
        const std::string line_3 = r.NextNonBlank("$Elements", "fewer elements than the count says");
        const auto tok = SplitWs(line_3);
        if (tok.size() < 3) r.Fail("element", "expected 'id type ntags tags... nodes...'");
        const auto id = ParseInt(tok[0], r, "element id");
        const auto type = ParseInt(tok[1], r, "element type");
        const auto ntags = ParseInt(tok[2], r, "number of tags");
        if (ntags < 0 || 3 + ntags > static_cast<std::int64_t>(tok.size())) {
          r.Fail("number of tags", "inconsistent with the line length");
        }
        const std::size_t first = 3 + static_cast<std::size_t>(ntags);
        int nn = 0;
        if (type == 4) {
          nn = 4;
        } else if (auto it = kLowerDim.find(type); it != kLowerDim.end()) {
          nn = it->second;
        } else {
          r.Fail("element type", "element " + std::to_string(id) + " has type " +
                                     std::to_string(type) +
                                     ": only 4-node tetrahedra (type 4) are supported as volume "
                                     "elements");
        }
        if (tok.size() - first != static_cast<std::size_t>(nn)) {
          r.Fail("element " + std::to_string(id), "type " + std::to_string(type) + " needs " +
                                                      std::to_string(nn) + " node ids, got " +
                                                      std::to_string(tok.size() - first));
        }
        if (type == 4) {
          PendingTet pt{{}, id, r.line()};
          for (int v = 0; v < 4; ++v) pt.ids[v] = ParseInt(tok[first + v], r, "node id");
          b.tets.push_back(pt);
        } else if (ntags >= 1) {
          const auto phys = ParseInt(tok[3], r, "physical tag");
          if (phys != 0) {
            auto& set = physical_nodes[phys];
            for (int v = 0; v < nn; ++v) {
              set.ids.push_back(ParseInt(tok[first + v], r, "node id"));
              set.lines.push_back(r.line());
            }
          }
        }
      }
      if (Trim(r.NextNonBlank("$Elements", "missing $EndElements")) != "$EndElements") {
        r.Fail("$Elements", "expected $EndElements (element count too small?)");
      }
    } else if (t.front() == '$') {
      // Unknown section ($NodeData, $Periodic, ...): skip to its end marker.
      // `t` views `line`, which the loop below overwrites: copy the section's name first.
      const std::string section(t);
      const std::string end = "$End" + section.substr(1);
      const std::size_t start = r.line();
      bool found = false;
      while (r.Next(line)) {
        if (Trim(line) == end) {
          found = true;
          break;
        }
      }
      if (!found) throw InputError(r.file(), start, section, "missing " + end);
    } else {
      r.Fail("section", "unexpected text outside a $Section: '" + std::string(t.substr(0, 40)) + "'");
    }
  }
  if (!have_format) throw InputError(r.file(), 0, "$MeshFormat", "missing (not a Gmsh file?)");
  for (auto& [tag, set] : physical_nodes) {
    auto it = physical_names.find(tag);
    const std::string name = it != physical_names.end() ? it->second : "physical:" + std::to_string(tag);
    auto& dst = b.sets[name];
    dst.ids.insert(dst.ids.end(), set.ids.begin(), set.ids.end());
    dst.lines.insert(dst.lines.end(), set.lines.begin(), set.lines.end());
  }
  return b.Build();
}

// ---------------------------------------------------------------- TetGen .node/.ele

TetMesh ReadTetgen(const fs::path& node_ele_or_base) {
  fs::path base = node_ele_or_base;
  if (base.extension() == ".node" || base.extension() == ".ele") base.replace_extension();
  fs::path node_file = base;
  node_file += ".node";
  fs::path ele_file = base;
  ele_file += ".ele";

  // Both files: '#' starts a comment; the first data line is the header.
  auto data_tokens = [](LineReader& r, std::string& line) -> std::vector<std::string_view> {
    while (r.Next(line)) {
      const auto hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      auto tok = SplitWs(line);
      if (!tok.empty()) return tok;
    }
    return {};
  };

  MeshBuilder b(node_file.string());
  std::map<std::int64_t, PendingSet> markers;
  {
    LineReader r(node_file);
    b.file = r.file();
    std::string line;
    auto head = data_tokens(r, line);
    if (head.size() < 2) r.Fail("header", "expected '<#points> <dimension> [<#attributes> <#markers>]'");
    const auto n = ParseInt(head[0], r, "number of points");
    const auto dim = ParseInt(head[1], r, "dimension");
    const auto nattr = head.size() > 2 ? ParseInt(head[2], r, "number of attributes") : 0;
    const auto nmark = head.size() > 3 ? ParseInt(head[3], r, "boundary markers") : 0;
    if (dim != 3) r.Fail("dimension", "must be 3, got " + std::to_string(dim));
    if (n < 0 || nattr < 0 || nmark < 0 || nmark > 1) r.Fail("header", "invalid counts");
    const std::size_t want = 4 + static_cast<std::size_t>(nattr + nmark);
    for (std::int64_t i = 0; i < n; ++i) {
      auto tok = data_tokens(r, line);
      if (tok.empty()) r.Fail("point", "unexpected end of file: fewer points than the header says");
      if (tok.size() != want) {
        r.Fail("point", "expected " + std::to_string(want) + " fields, got " + std::to_string(tok.size()));
      }
      const auto id = ParseInt(tok[0], r, "point id");
      b.AddNode(id, {ParseDouble(tok[1], r, "x"), ParseDouble(tok[2], r, "y"), ParseDouble(tok[3], r, "z")},
                r.line());
      if (nmark == 1) {
        const auto m = ParseInt(tok[want - 1], r, "boundary marker");
        if (m != 0) {
          markers[m].ids.push_back(id);
          markers[m].lines.push_back(r.line());
        }
      }
    }
  }
  {
    LineReader r(ele_file);
    std::string line;
    auto head = data_tokens(r, line);
    if (head.size() < 2) r.Fail("header", "expected '<#tetrahedra> <nodes per tet> [<region attribute>]'");
    const auto n = ParseInt(head[0], r, "number of tetrahedra");
    const auto npt = ParseInt(head[1], r, "nodes per tetrahedron");
    const auto nattr = head.size() > 2 ? ParseInt(head[2], r, "region attributes") : 0;
    if (npt != 4) r.Fail("nodes per tetrahedron", "only 4-node tetrahedra are supported, got " + std::to_string(npt));
    if (n < 0 || nattr < 0) r.Fail("header", "invalid counts");
    const std::size_t want = 5 + static_cast<std::size_t>(nattr);
    for (std::int64_t i = 0; i < n; ++i) {
      auto tok = data_tokens(r, line);
      if (tok.empty()) r.Fail("tetrahedron", "unexpected end of file: fewer tetrahedra than the header says");
      if (tok.size() != want) {
        r.Fail("tetrahedron", "expected " + std::to_string(want) + " fields, got " + std::to_string(tok.size()));
      }
      PendingTet pt{{}, ParseInt(tok[0], r, "tetrahedron id"), r.line()};
      for (int v = 0; v < 4; ++v) pt.ids[v] = ParseInt(tok[1 + v], r, "node id");
      b.tets.push_back(pt);
    }
    b.file = r.file();  // element errors name the .ele file
  }
  for (auto& [m, set] : markers) b.sets["marker:" + std::to_string(m)] = std::move(set);
  TetMesh mesh = b.Build();
  return mesh;
}

// ---------------------------------------------------------------- Abaqus / CalculiX .inp

TetMesh ReadAbaqusInp(const fs::path& path) {
  LineReader r(path);
  MeshBuilder b(r.file());
  enum class Block { kNone, kNode, kElement, kNset, kSkip };
  Block block = Block::kNone;
  std::string nset_name;         // for *NODE, NSET= and *NSET
  bool generate = false;
  bool continued = false;  // the last element line ended with ',': data goes on
  std::string pending_text;
  std::size_t pending_line = 0;
  std::string line;

  auto keyword_params = [&](std::string_view kw_line) {
    std::map<std::string, std::string> params;
    auto parts = SplitComma(kw_line);
    for (std::size_t i = 1; i < parts.size(); ++i) {
      const auto eq = parts[i].find('=');
      if (eq == std::string_view::npos) {
        params[Upper(parts[i])] = "";
      } else {
        params[Upper(Trim(parts[i].substr(0, eq)))] = std::string(Trim(parts[i].substr(eq + 1)));
      }
    }
    return std::make_pair(Upper(Trim(parts[0].substr(1))), params);
  };

  auto finish_element = [&](const std::vector<std::string_view>& tok, std::size_t at_line) {
    // id, n1, n2, n3, n4
    if (tok.size() != 5) {
      throw InputError(r.file(), at_line, "element", "C3D4 needs 'id, n1, n2, n3, n4', got " +
                                                         std::to_string(tok.size()) + " fields");
    }
    PendingTet pt{{}, ParseInt(tok[0], r, "element id"), at_line};
    for (int v = 0; v < 4; ++v) pt.ids[v] = ParseInt(tok[1 + v], r, "node id");
    b.tets.push_back(pt);
  };

  while (r.Next(line)) {
    std::string_view t = Trim(line);
    if (t.empty() || t.substr(0, 2) == "**") continue;
    if (t.front() == '*') {
      if (continued) r.Fail("element", "element data ends with ',' but no continuation line follows");
      auto [kw, params] = keyword_params(t);
      block = Block::kSkip;
      if (kw == "NODE") {
        block = Block::kNode;
        nset_name = params.count("NSET") ? Upper(params["NSET"]) : "";
      } else if (kw == "ELEMENT") {
        const std::string type = params.count("TYPE") ? Upper(params["TYPE"]) : "";
        if (type.empty()) r.Fail("*ELEMENT TYPE", "missing TYPE=");
        if (type == "C3D4") {
          block = Block::kElement;
        } else if (type.rfind("C3D", 0) == 0) {
          r.Fail("*ELEMENT TYPE", "element type " + type + " not supported: only C3D4 (4-node tetrahedra)");
        }
      } else if (kw == "NSET") {
        if (!params.count("NSET") || params["NSET"].empty()) r.Fail("*NSET", "missing NSET=name");
        block = Block::kNset;
        nset_name = Upper(params["NSET"]);
        generate = params.count("GENERATE") > 0;
        b.sets[nset_name];
      } else if (kw == "INCLUDE") {
        r.Fail("*INCLUDE", "not supported: inline the included file");
      }
      continue;
    }
    switch (block) {
      case Block::kNone:
        r.Fail("data", "data line before any keyword");
      case Block::kSkip:
        break;
      case Block::kNode: {
        auto tok = SplitComma(t);
        if (!tok.empty() && tok.back().empty()) tok.pop_back();
        if (tok.size() != 4) r.Fail("node", "expected 'id, x, y, z', got " + std::to_string(tok.size()) + " fields");
        const auto id = ParseInt(tok[0], r, "node id");
        b.AddNode(id, {ParseDouble(tok[1], r, "x"), ParseDouble(tok[2], r, "y"), ParseDouble(tok[3], r, "z")},
                  r.line());
        if (!nset_name.empty()) {
          b.sets[nset_name].ids.push_back(id);
          b.sets[nset_name].lines.push_back(r.line());
        }
        break;
      }
      case Block::kElement: {
        // A trailing comma continues the element on the next line.
        if (!continued) pending_line = r.line();
        pending_text += std::string(t);
        continued = t.back() == ',';
        if (continued) break;
        auto tok = SplitComma(pending_text);
        finish_element(tok, pending_line);
        pending_text.clear();
        break;
      }
      case Block::kNset: {
        auto tok = SplitComma(t);
        if (!tok.empty() && tok.back().empty()) tok.pop_back();
        auto& set = b.sets[nset_name];
        if (generate) {
          if (tok.size() < 2 || tok.size() > 3) r.Fail("*NSET GENERATE", "expected 'first, last[, increment]'");
          const auto first = ParseInt(tok[0], r, "first");
          const auto last = ParseInt(tok[1], r, "last");
          const auto inc = tok.size() == 3 ? ParseInt(tok[2], r, "increment") : 1;
          if (inc <= 0 || last < first) r.Fail("*NSET GENERATE", "needs first <= last and increment > 0");
          for (auto id = first; id <= last; id += inc) {
            set.ids.push_back(id);
            set.lines.push_back(r.line());
          }
        } else {
          for (auto tk : tok) {
            if (tk.empty()) continue;
            if (std::isdigit(static_cast<unsigned char>(tk.front())) || tk.front() == '-') {
              set.ids.push_back(ParseInt(tk, r, "node id"));
              set.lines.push_back(r.line());
            } else {
              auto it = b.sets.find(Upper(tk));
              if (it == b.sets.end() || Upper(tk) == nset_name) {
                r.Fail("*NSET " + nset_name, "unknown node set '" + std::string(tk) + "'");
              }
              // Copy first: the source is another entry of the same map.
              const PendingSet src = it->second;
              set.ids.insert(set.ids.end(), src.ids.begin(), src.ids.end());
              set.lines.insert(set.lines.end(), src.lines.begin(), src.lines.end());
            }
          }
        }
        break;
      }
    }
  }
  if (continued) r.Fail("element", "file ends inside a continued element line");
  if (b.p.empty()) throw InputError(r.file(), 0, "*NODE", "no nodes in the file");
  return b.Build();
}

}  // namespace handshare::fem
