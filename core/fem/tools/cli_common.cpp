#include "cli_common.hpp"

#include <cmath>
#include <exception>
#include <fstream>
#include <iostream>
#include <string>

#include <nlohmann/json.hpp>

#include "handshare/fem/error.hpp"

namespace handshare::fem::cli {
namespace {

using nlohmann::json;

double Number(const json& j, const std::string& file, const std::string& field) {
  if (!j.is_number()) throw InputError(file, 0, field, "expected a number, got " + j.dump());
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw InputError(file, 0, field, "not a finite number");
  return v;
}

std::int32_t Node(const json& j, const TetMesh& mesh, const std::string& file, const std::string& field) {
  if (!j.is_number_integer()) throw InputError(file, 0, field, "expected an integer node id, got " + j.dump());
  const auto id = j.get<std::int64_t>();
  const auto idx = mesh.IndexOfId(id);
  if (!idx) {
    throw InputError(file, 0, field, "unknown node id " + std::to_string(id) + " (not in " + mesh.source() + ")");
  }
  return *idx;
}

Eigen::Vector3d Vec3(const json& j, const std::string& file, const std::string& field) {
  if (!j.is_array() || j.size() != 3) throw InputError(file, 0, field, "expected [x, y, z], got " + j.dump());
  return {Number(j[0], file, field + "[0]"), Number(j[1], file, field + "[1]"),
          Number(j[2], file, field + "[2]")};
}

}  // namespace

LoadCase ReadLoadCase(const std::filesystem::path& path, const TetMesh& mesh, bool require_imposed) {
  const std::string file = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(file, 0, "file", "cannot open");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number too large
    throw InputError(file, 0, "json", e.what());
  }
  if (!j.is_object()) throw InputError(file, 0, "json", "top level must be an object");
  static const char* kKnown[] = {"E_Pa", "nu", "fixed_nodes", "fixed_nset", "imposed", "forces"};
  for (const auto& [key, value] : j.items()) {
    bool known = false;
    for (const char* k : kKnown) known = known || key == k;
    if (!known) throw InputError(file, 0, key, "unknown field (expected E_Pa, nu, fixed_nodes, fixed_nset, imposed, forces)");
  }
  LoadCase lc;
  if (!j.contains("E_Pa")) throw InputError(file, 0, "E_Pa", "missing");
  if (!j.contains("nu")) throw InputError(file, 0, "nu", "missing");
  lc.material.E_Pa = Number(j["E_Pa"], file, "E_Pa");
  lc.material.nu = Number(j["nu"], file, "nu");
  try {
    lc.material.Validate();
  } catch (const InputError& e) {
    throw InputError(file, 0, e.field(), e.what());
  }
  if (j.contains("fixed_nodes")) {
    const json& f = j["fixed_nodes"];
    if (!f.is_array()) throw InputError(file, 0, "fixed_nodes", "expected an array of node ids");
    for (std::size_t i = 0; i < f.size(); ++i) {
      lc.problem.fixed_nodes.push_back(Node(f[i], mesh, file, "fixed_nodes[" + std::to_string(i) + "]"));
    }
  }
  if (j.contains("fixed_nset")) {
    if (!j["fixed_nset"].is_string()) throw InputError(file, 0, "fixed_nset", "expected a node set name");
    const std::string name = j["fixed_nset"].get<std::string>();
    const auto* set = mesh.FindNodeSet(name);
    if (set == nullptr) throw InputError(file, 0, "fixed_nset", "no node set '" + name + "' in " + mesh.source());
    lc.problem.fixed_nodes.insert(lc.problem.fixed_nodes.end(), set->begin(), set->end());
  }
  if (lc.problem.fixed_nodes.empty()) {
    throw InputError(file, 0, "fixed_nodes", "no fixed nodes: the object would float (singular stiffness)");
  }
  if (j.contains("imposed")) {
    const json& a = j["imposed"];
    if (!a.is_array()) throw InputError(file, 0, "imposed", "expected an array");
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::string f = "imposed[" + std::to_string(i) + "]";
      if (!a[i].is_object() || !a[i].contains("node") || !a[i].contains("u_m")) {
        throw InputError(file, 0, f, "expected {\"node\": id, \"u_m\": [x, y, z]}");
      }
      const std::int32_t v = Node(a[i]["node"], mesh, file, f + ".node");
      for (std::int32_t fixed : lc.problem.fixed_nodes) {
        if (fixed == v) throw InputError(file, 0, f + ".node", "node id " + std::to_string(mesh.node_ids()[v]) + " is also fixed");
      }
      for (const auto& prev : lc.problem.imposed_u_m) {
        if (prev.node == v) throw InputError(file, 0, f + ".node", "node id " + std::to_string(mesh.node_ids()[v]) + " is imposed twice");
      }
      lc.problem.imposed_u_m.push_back({v, Vec3(a[i]["u_m"], file, f + ".u_m")});
    }
  } else if (require_imposed) {
    throw InputError(file, 0, "imposed", "missing");
  }
  if (j.contains("forces")) {
    const json& a = j["forces"];
    if (!a.is_array()) throw InputError(file, 0, "forces", "expected an array");
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::string f = "forces[" + std::to_string(i) + "]";
      if (!a[i].is_object() || !a[i].contains("node") || !a[i].contains("f_N")) {
        throw InputError(file, 0, f, "expected {\"node\": id, \"f_N\": [x, y, z]}");
      }
      lc.problem.forces_N.push_back({Node(a[i]["node"], mesh, file, f + ".node"), Vec3(a[i]["f_N"], file, f + ".f_N")});
    }
  }
  return lc;
}

int RunMain(const char* program, const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace handshare::fem::cli
