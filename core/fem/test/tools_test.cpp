// The command-line tools: fem_solve prints the static solution as JSON and fails cleanly on bad
// input; fem_precompute writes, reuses and rebuilds a cache.

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/mesh_io.hpp"
#include "handshare/fem/static_solver.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

const std::filesystem::path kData = HANDSHARE_FEM_TEST_DATA;

struct ToolRun {
  int exit_code;
  std::string out, err;
};

ToolRun RunTool(const std::string& exe, const std::string& args, const test::TempDir& dir) {
  const auto err_file = dir.path() / "stderr.txt";
  const std::string cmd = "'" + exe + "' " + args + " 2> '" + err_file.string() + "'";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int status = pclose(p);
  std::ifstream e(err_file);
  std::stringstream ss;
  ss << e.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out, ss.str()};
}

// box_2x1x1: node ids 101 + 2 i; bottom (z = 0) ids 101..111; top ids 113..123.
constexpr const char* kLoadCase = R"({"E_Pa": 1e4, "nu": 0.3,
  "fixed_nodes": [101, 103, 105, 107, 109, 111],
  "imposed": [{"node": 121, "u_m": [0.0, 1e-4, -5e-4]}, {"node": 115, "u_m": [2e-4, 0, 0]}]})";

TEST(FemSolveTool, PrintsDisplacementsAndReactions) {
  test::TempDir dir;
  const auto lc = dir.Write("lc.json", kLoadCase);
  const ToolRun r = RunTool(HANDSHARE_FEM_SOLVE, (kData / "box_2x1x1.inp").string() + " " + lc.string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  // The same problem through the library.
  const TetMesh mesh = ReadAbaqusInp(kData / "box_2x1x1.inp");
  StaticProblem p;
  for (std::int64_t id : {101, 103, 105, 107, 109, 111}) p.fixed_nodes.push_back(*mesh.IndexOfId(id));
  p.imposed_u_m = {{*mesh.IndexOfId(121), {0.0, 1e-4, -5e-4}}, {*mesh.IndexOfId(115), {2e-4, 0, 0}}};
  const StaticSolution s = SolveStatic(mesh, {1e4, 0.3}, p);
  ASSERT_EQ(j["displacements"].size(), 12u);
  for (std::int32_t v = 0; v < mesh.num_nodes(); ++v) {
    const auto& u = j["displacements"][std::to_string(mesh.node_ids()[v])];
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(u[a].get<double>(), s.u_m[v][a], 1e-15);
  }
  ASSERT_EQ(j["reactions"].size(), 2u);
  for (std::int64_t id : {121, 115}) {
    const auto& f = j["reactions"][std::to_string(id)];
    const auto v = *mesh.IndexOfId(id);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(f[a].get<double>(), s.reaction_N[v][a], 1e-12);
  }
  // Imposed values come back exactly; equilibrium: all reactions sum to zero (no external load).
  EXPECT_EQ(j["displacements"]["121"][2].get<double>(), -5e-4);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto* table : {&j["reactions"], &j["support_reactions"]}) {
    for (const auto& [id, f] : table->items()) sum += Eigen::Vector3d(f[0], f[1], f[2]);
  }
  EXPECT_LT(sum.norm(), 1e-12);
}

TEST(FemSolveTool, BadInputGivesNonZeroExitAndAClearMessage) {
  test::TempDir dir;
  const std::string mesh = (kData / "box_2x1x1.inp").string();
  struct Case {
    std::string json;
    std::string expect;
  };
  const Case cases[] = {
      {R"({"E_Pa": 1e4, "nu": 0.3, "fixed_nodes": [101], "imposed": [{"node": 999, "u_m": [0,0,0]}]})",
       "field 'imposed[0].node': unknown node id 999"},
      {R"({"E_Pa": 1e4, "nu": 0.3, "fixed_nodes": [101], "imposed": [{"node": 121, "u_m": [0,"NaN",0]}]})",
       "field 'imposed[0].u_m[1]': expected a number"},
      {R"({"E_Pa": 1e4, "nu": 0.5, "fixed_nodes": [101], "imposed": []})", "field 'nu'"},
      {R"({"nu": 0.3, "fixed_nodes": [101], "imposed": []})", "field 'E_Pa': missing"},
      {R"({"E_Pa": 1e4, "nu": 0.3, "fixed_nodes": [101], "imposed": [{"node": 101, "u_m": [0,0,0]}]})",
       "is also fixed"},
      {R"({"E_Pa": 1e4, "nu": 0.3, "fixed_nodes": [101], "imposed": [], "force": []})", "field 'force': unknown field"},
      {R"({"E_Pa": 1e4, "nu": 0.3, "fixed_nodes": [], "imposed": []})", "no fixed nodes"},
      {R"({"E_Pa": 1e4, "nu": 0.3, "fixed_nodes": [101], "imposed": [})", "parse error"},
      // nlohmann's out_of_range, not a parse_error (found by the load_case fuzz target).
      {R"({"E_Pa": 1e999, "nu": 0.3, "fixed_nodes": [101], "imposed": []})", "number overflow"},
  };
  for (const auto& c : cases) {
    const auto lc = dir.Write("bad.json", c.json);
    const ToolRun r = RunTool(HANDSHARE_FEM_SOLVE, mesh + " " + lc.string(), dir);
    EXPECT_EQ(r.exit_code, 1) << c.json;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << "stderr: " << r.err;
    EXPECT_NE(r.err.find("bad.json"), std::string::npos) << "stderr: " << r.err;
    EXPECT_TRUE(r.out.empty());
  }
  const auto lc = dir.Write("lc.json", kLoadCase);
  ToolRun r = RunTool(HANDSHARE_FEM_SOLVE, (dir.path() / "none.msh").string() + " " + lc.string(), dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("none.msh"), std::string::npos) << r.err;
  r = RunTool(HANDSHARE_FEM_SOLVE, "", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("usage"), std::string::npos);
}

TEST(FemPrecomputeTool, WritesReusesAndRebuildsTheCache) {
  test::TempDir dir;
  const std::string mesh = (kData / "box_2x1x1.msh").string();
  const auto cache = dir.path() / "box.compliance";
  auto lc = dir.Write("lc.json", R"({"E_Pa": 1e4, "nu": 0.3, "fixed_nset": "bottom"})");
  ToolRun r = RunTool(HANDSHARE_FEM_PRECOMPUTE, mesh + " " + lc.string() + " --out " + cache.string() + " --float32", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("no cache"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("100.0%"), std::string::npos) << r.err;  // the progress bar finished
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["surface_nodes"].get<int>(), 6);  // 12 nodes, all on the surface, 6 fixed
  EXPECT_EQ(j["precision"].get<std::string>(), "float32");
  EXPECT_TRUE(std::filesystem::exists(cache));
  r = RunTool(HANDSHARE_FEM_PRECOMPUTE, mesh + " " + lc.string() + " --out " + cache.string() + " --float32", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("loaded"), std::string::npos) << r.err;
  lc = dir.Write("lc.json", R"({"E_Pa": 2e4, "nu": 0.3, "fixed_nset": "bottom"})");
  r = RunTool(HANDSHARE_FEM_PRECOMPUTE, mesh + " " + lc.string() + " --out " + cache.string() + " --float32", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("stale"), std::string::npos) << r.err;
  r = RunTool(HANDSHARE_FEM_PRECOMPUTE, mesh + " " + lc.string() + " --bogus", dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown option '--bogus'"), std::string::npos) << r.err;
  r = RunTool(HANDSHARE_FEM_PRECOMPUTE, mesh + " " + lc.string() + " --block many", dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("field '--block'"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace handshare::fem
