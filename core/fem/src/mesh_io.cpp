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

namespace {

// The sections of a Gmsh file, read in turn into a MeshBuilder; the physical groups' nodes
// become node sets at the end (Finish).
class GmshReader {
 public:
  explicit GmshReader(LineReader& r) : r_(r), b_(r.file()) {}

  void ReadFormat() {
    const std::string line_1 = r_.NextNonBlank("$MeshFormat", "missing version line");
    const auto tok = SplitWs(line_1);
    if (tok.size() < 3) r_.Fail("$MeshFormat", "expected 'version file-type data-size'");
    if (tok[0].substr(0, 2) != "2.") {
      r_.Fail("version", "MSH version " + std::string(tok[0]) +
                             " not supported: export as MSH 2.2 ASCII (gmsh -format msh22)");
    }
    if (tok[1] != "0") r_.Fail("file-type", "binary MSH not supported: export as ASCII");
    ExpectEnd("$MeshFormat", "$EndMeshFormat", "expected $EndMeshFormat");
    have_format_ = true;
  }

  void ReadPhysicalNames() {
    const auto n = ParseInt(Trim(r_.NextNonBlank("$PhysicalNames", "missing count")), r_,
                            "number of physical names");
    for (std::int64_t i = 0; i < n; ++i) {
      const std::string l = r_.NextNonBlank("$PhysicalNames", "too few physical names");
      const auto tok = SplitWs(l);
      if (tok.size() < 3) r_.Fail("physical name", "expected 'dimension tag \"name\"'");
      const auto tag = ParseInt(tok[1], r_, "physical tag");
      const auto q0 = l.find('"');
      const auto q1 = l.rfind('"');
      if (q0 == std::string::npos || q1 <= q0) r_.Fail("physical name", "name must be quoted");
      physical_names_[tag] = l.substr(q0 + 1, q1 - q0 - 1);
    }
    ExpectEnd("$PhysicalNames", "$EndPhysicalNames", "expected $EndPhysicalNames (count too small?)");
  }

  void ReadNodes() {
    if (!have_format_) r_.Fail("$MeshFormat", "$Nodes before $MeshFormat");
    const auto n = ParseInt(Trim(r_.NextNonBlank("$Nodes", "missing count")), r_, "number of nodes");
    if (n < 0) r_.Fail("number of nodes", "negative");
    for (std::int64_t i = 0; i < n; ++i) {
      const std::string line_2 = r_.NextNonBlank("$Nodes", "fewer nodes than the count says");
      const auto tok = SplitWs(line_2);
      if (tok.size() != 4) r_.Fail("node", "expected 'id x y z', got " + std::to_string(tok.size()) + " fields");
      const auto id = ParseInt(tok[0], r_, "node id");
      b_.AddNode(id,
                 {ParseDouble(tok[1], r_, "x"), ParseDouble(tok[2], r_, "y"),
                  ParseDouble(tok[3], r_, "z")},
                 r_.line());
    }
    ExpectEnd("$Nodes", "$EndNodes", "expected $EndNodes (node count too small?)");
    have_nodes_ = true;
  }

  void ReadElements() {
    if (!have_nodes_) r_.Fail("$Nodes", "$Elements before $Nodes");
    const auto n = ParseInt(Trim(r_.NextNonBlank("$Elements", "missing count")), r_,
                            "number of elements");
    for (std::int64_t i = 0; i < n; ++i) {
      ReadElement(r_.NextNonBlank("$Elements", "fewer elements than the count says"));
    }
    ExpectEnd("$Elements", "$EndElements", "expected $EndElements (element count too small?)");
  }

  // Unknown section ($NodeData, $Periodic, ...): skip to its end marker. `line` is the reader's
  // line buffer, which this overwrites: the section's name is a copy.
  void SkipSection(const std::string& section, std::string& line) {
    const std::string end = "$End" + section.substr(1);
    const std::size_t start = r_.line();
    bool found = false;
    while (r_.Next(line)) {
      if (Trim(line) == end) {
        found = true;
        break;
      }
    }
    if (!found) throw InputError(r_.file(), start, section, "missing " + end);
  }

  TetMesh Finish() {
    if (!have_format_) throw InputError(r_.file(), 0, "$MeshFormat", "missing (not a Gmsh file?)");
    for (auto& [tag, set] : physical_nodes_) {
      auto it = physical_names_.find(tag);
      const std::string name = it != physical_names_.end() ? it->second : "physical:" + std::to_string(tag);
      auto& dst = b_.sets[name];
      dst.ids.insert(dst.ids.end(), set.ids.begin(), set.ids.end());
      dst.lines.insert(dst.lines.end(), set.lines.begin(), set.lines.end());
    }
    return b_.Build();
  }

 private:
  void ExpectEnd(const std::string& section, std::string_view end, const std::string& what) {
    if (Trim(r_.NextNonBlank(section, "missing " + std::string(end))) != end) r_.Fail(section, what);
  }

  // One line of $Elements: a tetrahedron, or a lower-dimensional element whose nodes join its
  // physical group.
  void ReadElement(const std::string& line_3) {
    const auto tok = SplitWs(line_3);
    if (tok.size() < 3) r_.Fail("element", "expected 'id type ntags tags... nodes...'");
    const auto id = ParseInt(tok[0], r_, "element id");
    const auto type = ParseInt(tok[1], r_, "element type");
    const auto ntags = ParseInt(tok[2], r_, "number of tags");
    if (ntags < 0 || 3 + ntags > static_cast<std::int64_t>(tok.size())) {
      r_.Fail("number of tags", "inconsistent with the line length");
    }
    const std::size_t first = 3 + static_cast<std::size_t>(ntags);
    const int nn = NodesOfElement(id, type);
    if (tok.size() - first != static_cast<std::size_t>(nn)) {
      r_.Fail("element " + std::to_string(id), "type " + std::to_string(type) + " needs " +
                                                   std::to_string(nn) + " node ids, got " +
                                                   std::to_string(tok.size() - first));
    }
    if (type == 4) {
      PendingTet pt{{}, id, r_.line()};
      for (int v = 0; v < 4; ++v) pt.ids[v] = ParseInt(tok[first + v], r_, "node id");
      b_.tets.push_back(pt);
    } else if (ntags >= 1) {
      const auto phys = ParseInt(tok[3], r_, "physical tag");
      if (phys != 0) {
        auto& set = physical_nodes_[phys];
        for (int v = 0; v < nn; ++v) {
          set.ids.push_back(ParseInt(tok[first + v], r_, "node id"));
          set.lines.push_back(r_.line());
        }
      }
    }
  }

  int NodesOfElement(std::int64_t id, std::int64_t type) const {
    // Node count of the lower-dimensional Gmsh element types (points, lines, triangles, quads and
    // their higher-order versions), which are skipped except for their physical groups.
    static const std::map<std::int64_t, int> kLowerDim = {
        {1, 2},  {2, 3},  {3, 4},  {8, 3},  {9, 6},  {10, 9}, {15, 1}, {16, 8},  {20, 9},
        {21, 10}, {22, 12}, {23, 15}, {24, 15}, {25, 21}, {26, 4}, {27, 5}, {28, 6}};
    if (type == 4) return 4;
    if (auto it = kLowerDim.find(type); it != kLowerDim.end()) return it->second;
    r_.Fail("element type", "element " + std::to_string(id) + " has type " + std::to_string(type) +
                                ": only 4-node tetrahedra (type 4) are supported as volume "
                                "elements");
  }

  LineReader& r_;
  MeshBuilder b_;
  std::map<std::int64_t, std::string> physical_names_;
  std::map<std::int64_t, PendingSet> physical_nodes_;
  bool have_format_ = false;
  bool have_nodes_ = false;
};

}  // namespace

TetMesh ReadGmshMsh(const fs::path& path) {
  LineReader r(path);
  GmshReader gmsh(r);
  std::string line;
  while (r.Next(line)) {
    const std::string_view t = Trim(line);
    if (t.empty()) continue;
    if (t == "$MeshFormat") {
      gmsh.ReadFormat();
    } else if (t == "$PhysicalNames") {
      gmsh.ReadPhysicalNames();
    } else if (t == "$Nodes") {
      gmsh.ReadNodes();
    } else if (t == "$Elements") {
      gmsh.ReadElements();
    } else if (t.front() == '$') {
      // `t` views `line`, which SkipSection overwrites: copy the section's name first.
      gmsh.SkipSection(std::string(t), line);
    } else {
      r.Fail("section", "unexpected text outside a $Section: '" + std::string(t.substr(0, 40)) + "'");
    }
  }
  return gmsh.Finish();
}

// ---------------------------------------------------------------- TetGen .node/.ele

namespace {

// Both files: '#' starts a comment; the first data line is the header.
std::vector<std::string_view> TetgenDataTokens(LineReader& r, std::string& line) {
  while (r.Next(line)) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    auto tok = SplitWs(line);
    if (!tok.empty()) return tok;
  }
  return {};
}

// The points of a .node file into b; nonzero boundary markers into markers.
void ReadTetgenNodes(const fs::path& node_file, MeshBuilder& b, std::map<std::int64_t, PendingSet>& markers) {
  LineReader r(node_file);
  b.file = r.file();
  std::string line;
  auto head = TetgenDataTokens(r, line);
  if (head.size() < 2) r.Fail("header", "expected '<#points> <dimension> [<#attributes> <#markers>]'");
  const auto n = ParseInt(head[0], r, "number of points");
  const auto dim = ParseInt(head[1], r, "dimension");
  const auto nattr = head.size() > 2 ? ParseInt(head[2], r, "number of attributes") : 0;
  const auto nmark = head.size() > 3 ? ParseInt(head[3], r, "boundary markers") : 0;
  if (dim != 3) r.Fail("dimension", "must be 3, got " + std::to_string(dim));
  if (n < 0 || nattr < 0 || nmark < 0 || nmark > 1) r.Fail("header", "invalid counts");
  const std::size_t want = 4 + static_cast<std::size_t>(nattr + nmark);
  for (std::int64_t i = 0; i < n; ++i) {
    auto tok = TetgenDataTokens(r, line);
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

// The tetrahedra of an .ele file into b.
void ReadTetgenElements(const fs::path& ele_file, MeshBuilder& b) {
  LineReader r(ele_file);
  std::string line;
  auto head = TetgenDataTokens(r, line);
  if (head.size() < 2) r.Fail("header", "expected '<#tetrahedra> <nodes per tet> [<region attribute>]'");
  const auto n = ParseInt(head[0], r, "number of tetrahedra");
  const auto npt = ParseInt(head[1], r, "nodes per tetrahedron");
  const auto nattr = head.size() > 2 ? ParseInt(head[2], r, "region attributes") : 0;
  if (npt != 4) r.Fail("nodes per tetrahedron", "only 4-node tetrahedra are supported, got " + std::to_string(npt));
  if (n < 0 || nattr < 0) r.Fail("header", "invalid counts");
  const std::size_t want = 5 + static_cast<std::size_t>(nattr);
  for (std::int64_t i = 0; i < n; ++i) {
    auto tok = TetgenDataTokens(r, line);
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

}  // namespace

TetMesh ReadTetgen(const fs::path& node_ele_or_base) {
  fs::path base = node_ele_or_base;
  if (base.extension() == ".node" || base.extension() == ".ele") base.replace_extension();
  fs::path node_file = base;
  node_file += ".node";
  fs::path ele_file = base;
  ele_file += ".ele";
  MeshBuilder b(node_file.string());
  std::map<std::int64_t, PendingSet> markers;
  ReadTetgenNodes(node_file, b, markers);
  ReadTetgenElements(ele_file, b);
  for (auto& [m, set] : markers) b.sets["marker:" + std::to_string(m)] = std::move(set);
  TetMesh mesh = b.Build();
  return mesh;
}

// ---------------------------------------------------------------- Abaqus / CalculiX .inp

namespace {

// A keyword line: the keyword and its parameters (names upper case).
std::pair<std::string, std::map<std::string, std::string>> KeywordParams(std::string_view kw_line) {
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
}

// The keywords of an .inp file and the data lines of the blocks they open, read in turn into a
// MeshBuilder.
class AbaqusReader {
 public:
  explicit AbaqusReader(LineReader& r) : r_(r), b_(r.file()) {}

  void Keyword(std::string_view t) {
    if (continued_) r_.Fail("element", "element data ends with ',' but no continuation line follows");
    auto [kw, params] = KeywordParams(t);
    block_ = Block::kSkip;
    if (kw == "NODE") {
      block_ = Block::kNode;
      nset_name_ = params.count("NSET") ? Upper(params["NSET"]) : "";
    } else if (kw == "ELEMENT") {
      const std::string type = params.count("TYPE") ? Upper(params["TYPE"]) : "";
      if (type.empty()) r_.Fail("*ELEMENT TYPE", "missing TYPE=");
      if (type == "C3D4") {
        block_ = Block::kElement;
      } else if (type.rfind("C3D", 0) == 0) {
        r_.Fail("*ELEMENT TYPE", "element type " + type + " not supported: only C3D4 (4-node tetrahedra)");
      }
    } else if (kw == "NSET") {
      if (!params.count("NSET") || params["NSET"].empty()) r_.Fail("*NSET", "missing NSET=name");
      block_ = Block::kNset;
      nset_name_ = Upper(params["NSET"]);
      generate_ = params.count("GENERATE") > 0;
      b_.sets[nset_name_];
    } else if (kw == "INCLUDE") {
      r_.Fail("*INCLUDE", "not supported: inline the included file");
    }
  }

  void Data(std::string_view t) {
    switch (block_) {
      case Block::kNone:
        r_.Fail("data", "data line before any keyword");
      case Block::kSkip:
        break;
      case Block::kNode:
        NodeLine(t);
        break;
      case Block::kElement:
        ElementLine(t);
        break;
      case Block::kNset:
        NsetLine(t);
        break;
    }
  }

  TetMesh Finish() {
    if (continued_) r_.Fail("element", "file ends inside a continued element line");
    if (b_.p.empty()) throw InputError(r_.file(), 0, "*NODE", "no nodes in the file");
    return b_.Build();
  }

 private:
  enum class Block { kNone, kNode, kElement, kNset, kSkip };

  void NodeLine(std::string_view t) {
    auto tok = SplitComma(t);
    if (!tok.empty() && tok.back().empty()) tok.pop_back();
    if (tok.size() != 4) r_.Fail("node", "expected 'id, x, y, z', got " + std::to_string(tok.size()) + " fields");
    const auto id = ParseInt(tok[0], r_, "node id");
    b_.AddNode(id, {ParseDouble(tok[1], r_, "x"), ParseDouble(tok[2], r_, "y"), ParseDouble(tok[3], r_, "z")},
               r_.line());
    if (!nset_name_.empty()) {
      b_.sets[nset_name_].ids.push_back(id);
      b_.sets[nset_name_].lines.push_back(r_.line());
    }
  }

  void ElementLine(std::string_view t) {
    // A trailing comma continues the element on the next line.
    if (!continued_) pending_line_ = r_.line();
    pending_text_ += std::string(t);
    continued_ = t.back() == ',';
    if (continued_) return;
    auto tok = SplitComma(pending_text_);
    FinishElement(tok, pending_line_);
    pending_text_.clear();
  }

  void FinishElement(const std::vector<std::string_view>& tok, std::size_t at_line) {
    // id, n1, n2, n3, n4
    if (tok.size() != 5) {
      throw InputError(r_.file(), at_line, "element", "C3D4 needs 'id, n1, n2, n3, n4', got " +
                                                          std::to_string(tok.size()) + " fields");
    }
    PendingTet pt{{}, ParseInt(tok[0], r_, "element id"), at_line};
    for (int v = 0; v < 4; ++v) pt.ids[v] = ParseInt(tok[1 + v], r_, "node id");
    b_.tets.push_back(pt);
  }

  void NsetLine(std::string_view t) {
    auto tok = SplitComma(t);
    if (!tok.empty() && tok.back().empty()) tok.pop_back();
    auto& set = b_.sets[nset_name_];
    if (generate_) {
      if (tok.size() < 2 || tok.size() > 3) r_.Fail("*NSET GENERATE", "expected 'first, last[, increment]'");
      const auto first = ParseInt(tok[0], r_, "first");
      const auto last = ParseInt(tok[1], r_, "last");
      const auto inc = tok.size() == 3 ? ParseInt(tok[2], r_, "increment") : 1;
      if (inc <= 0 || last < first) r_.Fail("*NSET GENERATE", "needs first <= last and increment > 0");
      for (auto id = first; id <= last; id += inc) {
        set.ids.push_back(id);
        set.lines.push_back(r_.line());
      }
      return;
    }
    for (auto tk : tok) {
      if (tk.empty()) continue;
      if (std::isdigit(static_cast<unsigned char>(tk.front())) || tk.front() == '-') {
        set.ids.push_back(ParseInt(tk, r_, "node id"));
        set.lines.push_back(r_.line());
      } else {
        auto it = b_.sets.find(Upper(tk));
        if (it == b_.sets.end() || Upper(tk) == nset_name_) {
          r_.Fail("*NSET " + nset_name_, "unknown node set '" + std::string(tk) + "'");
        }
        // Copy first: the source is another entry of the same map.
        const PendingSet src = it->second;
        set.ids.insert(set.ids.end(), src.ids.begin(), src.ids.end());
        set.lines.insert(set.lines.end(), src.lines.begin(), src.lines.end());
      }
    }
  }

  LineReader& r_;
  MeshBuilder b_;
  Block block_ = Block::kNone;
  std::string nset_name_;  // for *NODE, NSET= and *NSET
  bool generate_ = false;
  bool continued_ = false;  // the last element line ended with ',': data goes on
  std::string pending_text_;
  std::size_t pending_line_ = 0;
};

}  // namespace

TetMesh ReadAbaqusInp(const fs::path& path) {
  LineReader r(path);
  AbaqusReader inp(r);
  std::string line;
  while (r.Next(line)) {
    std::string_view t = Trim(line);
    if (t.empty() || t.substr(0, 2) == "**") continue;
    if (t.front() == '*') {
      inp.Keyword(t);
    } else {
      inp.Data(t);
    }
  }
  return inp.Finish();
}

}  // namespace handshare::fem
