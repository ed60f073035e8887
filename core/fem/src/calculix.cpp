// CalculiX decks, runs and results (see calculix.hpp). The deck is what ccx_test.cpp wrote
// before it moved here; the nonlinear models add NLGEOM and the neo-Hookean material.

#include "handshare/fem/calculix.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <utility>

#include <Eigen/Geometry>

#include "handshare/fem/error.hpp"
#include "run_program.hpp"

namespace handshare::fem {

namespace {

namespace fs = std::filesystem;

// 12 significant digits: ccx cuts fields longer than 20 characters.
std::string G12(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.12g", v);
  return b;
}

void CheckNode(const TetMesh& mesh, std::int32_t v, const char* field) {
  if (v < 0 || v >= mesh.num_nodes() || !mesh.used_nodes()[static_cast<std::size_t>(v)]) {
    throw InputError("", 0, field, "node " + std::to_string(v) + " is not a node of an element of the " +
                                       std::to_string(mesh.num_nodes()) + "-node mesh");
  }
}

}  // namespace

const char* CcxModelName(CcxModel model) noexcept {
  switch (model) {
    case CcxModel::kLinear: return "linear";
    case CcxModel::kNlgeom: return "nlgeom";
    case CcxModel::kNeoHooke: return "neo_hooke";
  }
  return "?";
}

std::array<double, 2> NeoHookeConstants(const Material& m) noexcept {
  const double G = m.E_Pa / (2.0 * (1.0 + m.nu));
  const double K = m.E_Pa / (3.0 * (1.0 - 2.0 * m.nu));
  return {G / 2.0, 2.0 / K};
}

void WriteCalculixInput(const fs::path& file, const TetMesh& mesh, const CcxCase& c) {
  for (std::int32_t v : c.fixed) CheckNode(mesh, v, "fixed");
  for (const auto& iv : c.imposed) CheckNode(mesh, iv.node, "imposed");
  for (const auto& f : c.forces) CheckNode(mesh, f.node, "forces");
  std::ofstream o(file);
  // ccx numbers nodes from 1 (a tetgen mesh's ids start at 0): the deck's id is index + 1.
  auto id = [](std::int32_t v) { return static_cast<std::int64_t>(v) + 1; };
  o << "*NODE, NSET=NALL\n";
  for (std::int32_t v = 0; v < mesh.num_nodes(); ++v) {
    if (!mesh.used_nodes()[static_cast<std::size_t>(v)]) continue;  // ccx: no element, no DOF
    const auto& x = mesh.positions_m()[static_cast<std::size_t>(v)];
    o << id(v) << ", " << G12(x.x()) << ", " << G12(x.y()) << ", " << G12(x.z()) << "\n";
  }
  o << "*ELEMENT, TYPE=C3D4, ELSET=EALL\n";
  for (std::int32_t e = 0; e < mesh.num_tets(); ++e) {
    auto t = mesh.tets()[static_cast<std::size_t>(e)];
    // C3D4 wants node 4 on the side of face 1-2-3 its right-hand normal points to (positive
    // volume); tetgen's elements come either way round.
    const auto& p = mesh.positions_m();
    const Eigen::Vector3d a = p[static_cast<std::size_t>(t[0])];
    if ((p[static_cast<std::size_t>(t[1])] - a).cross(p[static_cast<std::size_t>(t[2])] - a).dot(p[static_cast<std::size_t>(t[3])] - a) < 0.0) {
      std::swap(t[1], t[2]);
    }
    o << e + 1 << ", " << id(t[0]) << ", " << id(t[1]) << ", " << id(t[2]) << ", " << id(t[3]) << "\n";
  }
  o << "*NSET, NSET=NFIX\n";
  for (std::int32_t v : c.fixed) o << id(v) << ",\n";
  o << "*NSET, NSET=NIMP\n";
  for (const auto& iv : c.imposed) o << id(iv.node) << ",\n";
  o << "*MATERIAL, NAME=MAT\n";
  if (c.model == CcxModel::kNeoHooke) {
    const auto [C10, D1] = NeoHookeConstants(c.material);
    o << "*HYPERELASTIC, NEO HOOKE\n" << G12(C10) << ", " << G12(D1) << "\n";
  } else {
    o << "*ELASTIC\n" << G12(c.material.E_Pa) << ", " << G12(c.material.nu) << "\n";
  }
  o << "*SOLID SECTION, ELSET=EALL, MATERIAL=MAT\n";
  if (c.model == CcxModel::kLinear) {
    o << "*STEP\n*STATIC\n";
  } else {
    // Automatic incrementation: first increment, step length 1, smallest, largest.
    o << "*STEP, NLGEOM, INC=" << c.max_increments << "\n*STATIC\n"
      << G12(c.initial_increment) << ", 1.0, " << G12(c.initial_increment * 1e-4) << ", "
      << G12(c.max_increment) << "\n";
  }
  o << "*BOUNDARY\n";
  if (!c.fixed.empty()) o << "NFIX, 1, 3\n";
  for (const auto& iv : c.imposed)
    for (int a = 0; a < 3; ++a) o << id(iv.node) << ", " << a + 1 << ", " << a + 1 << ", " << G12(iv.value[a]) << "\n";
  if (!c.forces.empty()) {
    o << "*CLOAD\n";
    for (const auto& f : c.forces)
      for (int a = 0; a < 3; ++a) o << id(f.node) << ", " << a + 1 << ", " << G12(f.value[a]) << "\n";
  }
  // Nonlinear steps print every increment unless told otherwise; the last one is what counts.
  o << "*NODE PRINT, NSET=NALL\nU\n";
  if (!c.imposed.empty()) o << "*NODE PRINT, NSET=NIMP\nRF\n";
  o << "*END STEP\n";
  if (!o) throw FemError("cannot write " + file.string());
}

CcxTables ReadCalculixDat(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), 0, "", "cannot read the ccx results");
  CcxTables t;
  std::map<std::int64_t, Eigen::Vector3d>* table = nullptr;
  std::string line;
  while (std::getline(in, line)) {
    if (line.find("displacements (vx,vy,vz)") != std::string::npos) {
      table = &t.u_m;
      continue;
    }
    if (line.find("forces (fx,fy,fz)") != std::string::npos) {
      table = &t.reaction_N;
      continue;
    }
    std::istringstream ss(line);
    std::int64_t node_id = 0;
    Eigen::Vector3d v;
    if (table != nullptr && (ss >> node_id >> v.x() >> v.y() >> v.z())) (*table)[node_id] = v;
  }
  return t;
}

CcxResult RunCalculix(const TetMesh& mesh, const CcxCase& c, const fs::path& dir, const std::string& program) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  for (const char* stale : {"job.dat", "job.sta", "job.frd", "job.cvg"}) fs::remove(dir / stale, ec);
  WriteCalculixInput(dir / "job.inp", mesh, c);
  // One thread (the machine is shared, and the runs are small), through env(1) so that this
  // process's environment stays as it is; env exits 127 when it cannot find the program.
  // timeout(1) ends a run that hangs (exit 124).
  const int rc = detail::RunProgram({"timeout", std::to_string(c.timeout_s), "env", "OMP_NUM_THREADS=1",
                                     "CCX_NPROC_EQUATION_SOLVER=1", program, "-i", "job"},
                                    dir, dir / "ccx.log", "coreutils");
  if (rc == 127) {
    throw FemError("cannot run '" + program + "' (install the Debian package calculix-ccx): " +
                   detail::Tail(dir / "ccx.log", 200));
  }

  CcxResult r;
  // job.sta: one row per increment: STEP INC ATT ITRS TOT-TIME STEP-TIME INC-TIME.
  {
    std::ifstream sta(dir / "job.sta");
    std::string line;
    while (std::getline(sta, line)) {
      std::istringstream ss(line);
      int step = 0, inc = 0, att = 0, itrs = 0;
      double tot = 0.0, step_time = 0.0, inc_time = 0.0;
      if (ss >> step >> inc >> att >> itrs >> tot >> step_time >> inc_time) {
        r.increments = inc;
        r.step_fraction = step_time;
      }
    }
  }
  r.converged = rc == 0 && std::abs(r.step_fraction - 1.0) < 1e-6;
  if (!r.converged) {
    r.message = (rc == 124 ? "ccx timed out after " + std::to_string(c.timeout_s) + " s, " : std::string()) + "ccx exit code " + std::to_string(rc) + ", step reached " + G12(r.step_fraction) + ": " +
                detail::Tail(dir / "ccx.log", 300);
  }
  CcxTables t;
  if (fs::exists(dir / "job.dat")) t = ReadCalculixDat(dir / "job.dat");
  r.u_m.assign(static_cast<std::size_t>(mesh.num_nodes()), Eigen::Vector3d::Zero());
  for (std::int32_t v = 0; v < mesh.num_nodes(); ++v) {
    if (auto it = t.u_m.find(v + 1); it != t.u_m.end()) r.u_m[static_cast<std::size_t>(v)] = it->second;
  }
  for (const auto& iv : c.imposed) {
    auto it = t.reaction_N.find(iv.node + 1);
    r.reaction_N.push_back(it != t.reaction_N.end() ? it->second : Eigen::Vector3d::Constant(std::nan("")));
  }
  if (r.converged && t.u_m.empty()) {
    r.converged = false;
    r.message = "ccx printed no displacements: " + detail::Tail(dir / "ccx.log", 300);
  }
  return r;
}

}  // namespace handshare::fem
