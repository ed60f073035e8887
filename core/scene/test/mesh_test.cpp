// The project's meshes (assets/meshes, made by assets/tools/make_meshes.py) and LoadMesh.
#include <gtest/gtest.h>

#include <fstream>
#include <map>

#include "handshare/scene/scene.hpp"

namespace handshare::scene {
namespace {

const std::filesystem::path kMeshes = std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "meshes";

struct Expected {
  double min_size_m, max_size_m;  // largest bounding-box side
  std::size_t max_vertices;
};

// Deformables: hand-sized and at most ~2,000 surface vertices (they are tetrahedralized and
// precomputed with FEM).
const std::map<std::string, Expected> kExpected = {
    {"triceratops_head", {0.08, 0.21, 2000}}, {"triceratops_tail", {0.08, 0.21, 2000}},
    {"triceratops_leg", {0.08, 0.21, 2000}},  {"daphnia_body", {0.08, 0.21, 2000}},
    {"daphnia_spine", {0.08, 0.21, 2000}},    {"ball", {0.079, 0.081, 2000}},
    {"button", {0.03, 0.05, 2000}},           {"lever", {0.05, 0.12, 2000}},
    {"arrow", {0.05, 0.12, 2000}},            {"book", {0.1, 0.2, 2000}},
};

TEST(Mesh, EveryProjectMeshIsClosedOutwardAndHandSized) {
  std::size_t seen = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kMeshes)) {
    if (entry.path().extension() != ".obj") continue;
    const std::string name = entry.path().stem().string();
    SCOPED_TRACE(name);
    const Mesh mesh = LoadMesh(entry.path());
    const MeshCheck check = CheckMesh(mesh);
    EXPECT_EQ(check.boundary_edges, 0u);
    EXPECT_EQ(check.non_manifold_edges, 0u);
    EXPECT_EQ(check.degenerate_triangles, 0u);
    EXPECT_GT(check.signed_volume_m3, 0.0);
    // Closed 2-manifold of genus 0 (all of ours are sphere-like): V - E + F = 2, E = 3F/2.
    EXPECT_EQ(2 * static_cast<long>(mesh.vertices_m.size()) - static_cast<long>(mesh.triangles.size()), 4);
    const auto it = kExpected.find(name);
    ASSERT_NE(it, kExpected.end()) << "new mesh without expectations";
    const double size_m = check.bounds.sizes().maxCoeff();
    EXPECT_GE(size_m, it->second.min_size_m);
    EXPECT_LE(size_m, it->second.max_size_m);
    EXPECT_LE(mesh.vertices_m.size(), it->second.max_vertices);
    ++seen;
  }
  EXPECT_EQ(seen, kExpected.size());
}

TEST(Mesh, BallVolumeMatchesTheSphere) {
  // A polyhedron inscribed in the sphere: volume a little below 4/3 pi r^3 (642 vertices:
  // within 2 %).
  const MeshCheck check = CheckMesh(LoadMesh(kMeshes / "ball.obj"));
  const double sphere_m3 = 4.0 / 3.0 * 3.14159265358979 * 0.04 * 0.04 * 0.04;
  EXPECT_LT(check.signed_volume_m3, sphere_m3);
  EXPECT_GT(check.signed_volume_m3, 0.98 * sphere_m3);
}

std::filesystem::path Temp(const std::string& name, const std::string& text) {
  const auto p = std::filesystem::temp_directory_path() / ("hs_mesh_test_" + name);
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

// A unit right tetrahedron, outward, as ASCII STL: every facet repeats its vertices.
const char* kTetStl = R"(solid t
facet normal 0 0 -1
 outer loop
  vertex 0 0 0
  vertex 0 1 0
  vertex 1 0 0
 endloop
endfacet
facet normal 0 -1 0
 outer loop
  vertex 0 0 0
  vertex 1 0 0
  vertex 0 0 1
 endloop
endfacet
facet normal -1 0 0
 outer loop
  vertex 0 0 0
  vertex 0 0 1
  vertex 0 1 0
 endloop
endfacet
facet normal 1 1 1
 outer loop
  vertex 1 0 0
  vertex 0 1 0
  vertex 0 0 1
 endloop
endfacet
endsolid t
)";

TEST(Mesh, StlIsWeldedIntoAClosedMesh) {
  const auto p = Temp("tet.stl", kTetStl);
  const Mesh mesh = LoadMesh(p);
  EXPECT_EQ(mesh.vertices_m.size(), 4u);
  EXPECT_EQ(mesh.triangles.size(), 4u);
  const MeshCheck check = CheckMesh(mesh);
  EXPECT_TRUE(check.closed_and_outward());
  EXPECT_NEAR(check.signed_volume_m3, 1.0 / 6.0, 1e-12);
  std::filesystem::remove(p);
}

TEST(Mesh, PlyLoads) {
  const auto p = Temp("tet.ply",
                      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                      "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                      "end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const MeshCheck check = CheckMesh(LoadMesh(p));
  EXPECT_TRUE(check.closed_and_outward());
  EXPECT_NEAR(check.signed_volume_m3, 1.0 / 6.0, 1e-6);
  std::filesystem::remove(p);
}

TEST(Mesh, ScaleAndTransformAreApplied) {
  const auto p = Temp("tet2.stl", kTetStl);
  Eigen::Isometry3d X_AM = Eigen::Isometry3d::Identity();
  X_AM.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  X_AM.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Mesh mesh = LoadMesh(p, Eigen::Vector3d(0.1, 0.2, 0.3), X_AM);
  const MeshCheck check = CheckMesh(mesh);
  EXPECT_TRUE(check.closed_and_outward());
  EXPECT_NEAR(check.signed_volume_m3, 0.1 * 0.2 * 0.3 / 6.0, 1e-12);
  // The vertex (0, 0, 1) of the file.
  const Eigen::Vector3d expected = X_AM * Eigen::Vector3d(0.0, 0.0, 0.3);
  bool found = false;
  for (const auto& v : mesh.vertices_m) found = found || (v - expected).norm() < 1e-12;
  EXPECT_TRUE(found);
  // A mirror keeps the surface outward.
  EXPECT_TRUE(CheckMesh(LoadMesh(p, Eigen::Vector3d(-1.0, 1.0, 1.0))).closed_and_outward());
  std::filesystem::remove(p);
}

TEST(Mesh, CheckFindsHolesAndInwardSurfaces) {
  // The checker itself must catch what it is there to catch.
  const auto p = Temp("tet3.stl", kTetStl);
  Mesh mesh = LoadMesh(p);
  std::filesystem::remove(p);
  Mesh holed = mesh;
  holed.triangles.pop_back();
  EXPECT_EQ(CheckMesh(holed).boundary_edges, 3u);
  EXPECT_FALSE(CheckMesh(holed).closed_and_outward());
  Mesh inward = mesh;
  for (auto& t : inward.triangles) std::swap(t[1], t[2]);
  EXPECT_LT(CheckMesh(inward).signed_volume_m3, 0.0);
  EXPECT_FALSE(CheckMesh(inward).closed_and_outward());
  Mesh flipped_one = mesh;
  std::swap(flipped_one.triangles[0][1], flipped_one.triangles[0][2]);
  EXPECT_GT(CheckMesh(flipped_one).non_manifold_edges + CheckMesh(flipped_one).boundary_edges, 0u);
}

TEST(Mesh, BadFilesNameThePath) {
  const auto missing = std::filesystem::temp_directory_path() / "hs_mesh_test_missing.obj";
  const auto empty = Temp("empty.obj", "");
  const auto garbage = Temp("garbage.stl", "solid x\nthis is not\x01 an stl");
  const auto no_faces = Temp("nofaces.obj", "v 0 0 0\nv 1 0 0\n");
  for (const auto& p : {missing, empty, garbage, no_faces}) {
    try {
      LoadMesh(p);
      ADD_FAILURE() << p;
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    }
  }
  for (const auto& p : {empty, garbage, no_faces}) std::filesystem::remove(p);
}

}  // namespace
}  // namespace handshare::scene
