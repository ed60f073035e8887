#include "scene_drawer.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "caption_text.hpp"
#include "handshare/render/projection.hpp"

namespace handshare::render::detail {

namespace {

struct Viewport {
  int x_px;  // GL convention: lower-left corner.
  int y_px;
  int width_px;
  int height_px;
};

// Lighting: a white directional light fixed to the viewer (upper left, in front), strong ambient
// and no specular, so a pure-coloured sphere keeps its hue everywhere (a white highlight would
// wash out red/green/blue fingertips) while its diffuse falloff still reads as round.
constexpr float kLightAmbient = 0.3F;
constexpr float kLightDiffuse = 0.7F;
constexpr GLfloat kLightDirection_Eye[4] = {-0.35F, 0.55F, 1.0F, 0.0F};

// Unit-sphere tessellation (latitude/longitude), built once.
constexpr int kSphereStacks = 24;
constexpr int kSphereSlices = 48;

const std::vector<Eigen::Vector3d>& UnitSphereTriangles() {
  static const std::vector<Eigen::Vector3d> triangles = [] {
    auto point = [](int stack, int slice) {
      const double theta = std::numbers::pi * stack / kSphereStacks;  // from +z
      const double phi = 2.0 * std::numbers::pi * slice / kSphereSlices;
      return Eigen::Vector3d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                             std::cos(theta));
    };
    std::vector<Eigen::Vector3d> out;
    out.reserve(static_cast<std::size_t>(6 * kSphereStacks * kSphereSlices));
    for (int i = 0; i < kSphereStacks; ++i) {
      for (int j = 0; j < kSphereSlices; ++j) {
        const Eigen::Vector3d a = point(i, j);
        const Eigen::Vector3d b = point(i + 1, j);
        const Eigen::Vector3d c = point(i + 1, j + 1);
        const Eigen::Vector3d d = point(i, j + 1);
        out.insert(out.end(), {a, b, c, a, c, d});
      }
    }
    return out;
  }();
  return triangles;
}

void DrawGrid(const GlApi& gl, const GroundGrid& grid) {
  if (!grid.visible || grid.normal_W.norm() < 1e-12 || grid.spacing_m <= 0.0 ||
      grid.half_size_m <= 0.0) {
    return;
  }
  // Two in-plane axes orthogonal to the normal.
  const Eigen::Vector3d n = grid.normal_W.normalized();
  const Eigen::Vector3d a = n.unitOrthogonal();
  const Eigen::Vector3d b = n.cross(a);
  const int lines = static_cast<int>(std::floor(grid.half_size_m / grid.spacing_m));
  gl.Disable(GL_LIGHTING);
  gl.Color3f(grid.rgb.r, grid.rgb.g, grid.rgb.b);
  gl.LineWidth(1.0F);
  gl.Begin(GL_LINES);
  for (int k = -lines; k <= lines; ++k) {
    const double offset_m = k * grid.spacing_m;
    for (const auto& [along, across] : {std::pair{a, b}, std::pair{b, a}}) {
      const Eigen::Vector3d p0 = grid.center_W + offset_m * across - grid.half_size_m * along;
      const Eigen::Vector3d p1 = grid.center_W + offset_m * across + grid.half_size_m * along;
      gl.Vertex3d(p0.x(), p0.y(), p0.z());
      gl.Vertex3d(p1.x(), p1.y(), p1.z());
    }
  }
  gl.End();
}

void DrawSpheres(const GlApi& gl, const std::vector<Sphere>& spheres) {
  const auto& unit = UnitSphereTriangles();
  for (const Sphere& sphere : spheres) {
    gl.Color3f(sphere.rgb.r, sphere.rgb.g, sphere.rgb.b);
    gl.Begin(GL_TRIANGLES);
    for (const Eigen::Vector3d& n : unit) {
      const Eigen::Vector3d p = sphere.p_W + sphere.radius_m * n;
      gl.Normal3d(n.x(), n.y(), n.z());
      gl.Vertex3d(p.x(), p.y(), p.z());
    }
    gl.End();
  }
}

void DrawBoxes(const GlApi& gl, const std::vector<Box>& boxes) {
  for (const Box& box : boxes) {
    const Eigen::Matrix3d R_WB = box.q_WB.normalized().toRotationMatrix();
    gl.Color3f(box.rgb.r, box.rgb.g, box.rgb.b);
    gl.Begin(GL_QUADS);
    for (int axis = 0; axis < 3; ++axis) {
      for (const double sign : {-1.0, 1.0}) {
        // Face with outward normal sign * e_axis; corners counter-clockwise seen from outside.
        const int u = (axis + 1) % 3;
        const int v = (axis + 2) % 3;
        Eigen::Vector3d n_B = Eigen::Vector3d::Zero();
        n_B[axis] = sign;
        const Eigen::Vector3d n_W = R_WB * n_B;
        gl.Normal3d(n_W.x(), n_W.y(), n_W.z());
        const double corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (int k = 0; k < 4; ++k) {
          const int kk = sign > 0 ? k : 3 - k;
          Eigen::Vector3d p_B;
          p_B[axis] = sign * box.half_extents_m[axis];
          p_B[u] = corners[kk][0] * box.half_extents_m[u];
          p_B[v] = corners[kk][1] * box.half_extents_m[v];
          const Eigen::Vector3d p_W = box.p_W + R_WB * p_B;
          gl.Vertex3d(p_W.x(), p_W.y(), p_W.z());
        }
      }
    }
    gl.End();
  }
}

void DrawMeshes(const GlApi& gl, const std::vector<TriangleMesh>& meshes) {
  std::vector<Eigen::Vector3d> n_MV;
  for (const TriangleMesh& mesh : meshes) {
    if (mesh.n_MV.empty()) {
      // Area-weighted vertex normals: the unnormalized face normal has twice the face's area.
      n_MV.assign(mesh.p_MV.size(), Eigen::Vector3d::Zero());
      for (const auto& t : mesh.triangles) {
        const Eigen::Vector3d face =
            (mesh.p_MV[t[1]] - mesh.p_MV[t[0]]).cross(mesh.p_MV[t[2]] - mesh.p_MV[t[0]]);
        for (const std::uint32_t index : t) n_MV[index] += face;
      }
    } else {
      n_MV = mesh.n_MV;
    }
    const Eigen::Matrix3d R_WM = mesh.X_WM.rotation();
    gl.Color3f(mesh.rgb.r, mesh.rgb.g, mesh.rgb.b);
    gl.Begin(GL_TRIANGLES);
    for (const auto& t : mesh.triangles) {
      for (const std::uint32_t index : t) {
        const double length = n_MV[index].norm();
        const Eigen::Vector3d n_W =
            length > 0.0 ? Eigen::Vector3d(R_WM * (n_MV[index] / length)) : Eigen::Vector3d::UnitZ();
        const Eigen::Vector3d p_W = mesh.X_WM * mesh.p_MV[index];
        gl.Normal3d(n_W.x(), n_W.y(), n_W.z());
        gl.Vertex3d(p_W.x(), p_W.y(), p_W.z());
      }
    }
    gl.End();
  }
}

void SetUpLighting(const GlApi& gl) {
  const GLfloat no_ambient[4] = {0.0F, 0.0F, 0.0F, 1.0F};
  const GLfloat ambient[4] = {kLightAmbient, kLightAmbient, kLightAmbient, 1.0F};
  const GLfloat diffuse[4] = {kLightDiffuse, kLightDiffuse, kLightDiffuse, 1.0F};
  const GLfloat specular[4] = {0.0F, 0.0F, 0.0F, 1.0F};
  gl.LightModelfv(GL_LIGHT_MODEL_AMBIENT, no_ambient);
  gl.LightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
  gl.Lightfv(GL_LIGHT0, GL_AMBIENT, ambient);
  gl.Lightfv(GL_LIGHT0, GL_DIFFUSE, diffuse);
  gl.Lightfv(GL_LIGHT0, GL_SPECULAR, specular);
  // Set with an identity modelview, so the direction is fixed relative to the viewer.
  gl.Lightfv(GL_LIGHT0, GL_POSITION, kLightDirection_Eye);
  gl.ColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  gl.Enable(GL_COLOR_MATERIAL);
  gl.Enable(GL_LIGHT0);
  gl.ShadeModel(GL_SMOOTH);
}

void DrawEye(const GlApi& gl, const SceneView& scene, const Camera& camera, Eye eye,
             const Viewport& viewport) {
  gl.Viewport(viewport.x_px, viewport.y_px, viewport.width_px, viewport.height_px);
  const double aspect = static_cast<double>(viewport.width_px) / viewport.height_px;
  const Eigen::Matrix4d projection = ProjectionMatrix(camera, aspect, eye);
  const Eigen::Matrix4d view = ViewMatrix(camera, eye);
  gl.MatrixMode(GL_PROJECTION);
  gl.LoadMatrixd(projection.data());  // Eigen and OpenGL are both column-major.
  gl.MatrixMode(GL_MODELVIEW);
  gl.LoadIdentity();
  SetUpLighting(gl);
  gl.LoadMatrixd(view.data());
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);

  DrawGrid(gl, scene.grid);
  gl.Enable(GL_LIGHTING);
  DrawSpheres(gl, scene.spheres);
  DrawBoxes(gl, scene.boxes);
  DrawMeshes(gl, scene.meshes);
  // The hands: hidden by the scene in front of them, but writing no depth, so that the markers
  // drawn after them (the fingertips) show through them.
  gl.DepthMask(GL_FALSE);
  DrawBoxes(gl, scene.hand_boxes);
  DrawSpheres(gl, scene.hand_spheres);
  gl.DepthMask(GL_TRUE);
  DrawSpheres(gl, scene.markers);
  gl.Disable(GL_LIGHTING);
}

// The caption at the bottom of `viewport`: a dark band as tall as its lines, the text blended
// over it at its coverage (antialiased), in pixel units with y pointing down.
void DrawCaption(const GlApi& gl, const SceneView& scene, const Viewport& viewport, CaptionCache& captions) {
  const int w = viewport.width_px;
  const int h = viewport.height_px;
  const CaptionBitmap& text = captions.For(scene.caption, w, h);
  if (text.height_px == 0 || text.width_px == 0) return;
  const int pad_px = std::max(2, text.stats.pixel_size / 2);
  const int margin_px = text.stats.pixel_size;  // CaptionCache wraps to the width less two margins
  const int band_px = std::min(h, text.height_px + 2 * pad_px);

  gl.Viewport(viewport.x_px, viewport.y_px, w, h);
  // Orthographic pixels: x right in [0, w], y DOWN in [0, h] (glOrtho(0, w, h, 0, -1, 1)).
  Eigen::Matrix4d ortho = Eigen::Matrix4d::Identity();
  ortho(0, 0) = 2.0 / w;
  ortho(0, 3) = -1.0;
  ortho(1, 1) = -2.0 / h;
  ortho(1, 3) = 1.0;
  ortho(2, 2) = -1.0;
  gl.MatrixMode(GL_PROJECTION);
  gl.LoadMatrixd(ortho.data());
  gl.MatrixMode(GL_MODELVIEW);
  gl.LoadIdentity();
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_LIGHTING);

  // Dark translucent band so the text reads over any scene.
  gl.Enable(GL_BLEND);
  gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  gl.Color4f(0.0F, 0.0F, 0.0F, 0.65F);
  gl.Begin(GL_QUADS);
  gl.Vertex2d(0, h - band_px);
  gl.Vertex2d(0, h);
  gl.Vertex2d(w, h);
  gl.Vertex2d(w, h - band_px);
  gl.End();

  // The text: RGBA pixels of the caption colour with the coverage as alpha, bottom row first
  // (glDrawPixels goes up from the raster position, the text's lower-left corner).
  const int tw = std::min(text.width_px, std::max(0, w - margin_px));
  const int th = std::min(text.height_px, band_px);
  if (tw > 0 && th > 0) {
    const auto channel = [](float v) { return static_cast<std::uint8_t>(std::lround(255.0F * std::clamp(v, 0.0F, 1.0F))); };
    const std::uint8_t r = channel(scene.caption_rgb.r);
    const std::uint8_t g = channel(scene.caption_rgb.g);
    const std::uint8_t b = channel(scene.caption_rgb.b);
    std::vector<std::uint8_t> rgba(4 * static_cast<std::size_t>(tw) * static_cast<std::size_t>(th));
    for (int y = 0; y < th; ++y) {
      std::uint8_t* row = rgba.data() + 4 * static_cast<std::size_t>(th - 1 - y) * static_cast<std::size_t>(tw);
      for (int x = 0; x < tw; ++x) {
        row[4 * x] = r;
        row[4 * x + 1] = g;
        row[4 * x + 2] = b;
        row[4 * x + 3] = text.At(x, y);
      }
    }
    const int top_px = h - band_px + std::max(0, (band_px - th) / 2);
    gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl.RasterPos2d(margin_px, top_px + th - 0.5);  // inside the viewport, so the position is valid
    gl.DrawPixels(tw, th, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  }
  gl.Disable(GL_BLEND);
}

}  // namespace

void ValidateScene(const SceneView& scene, const Camera& camera) {
  ValidateCamera(camera);
  for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
    const TriangleMesh& mesh = scene.meshes[m];
    const std::string where = "render::SceneView: meshes[" + std::to_string(m) + "]";
    if (!mesh.n_MV.empty() && mesh.n_MV.size() != mesh.p_MV.size()) {
      throw std::invalid_argument(where + " has " + std::to_string(mesh.n_MV.size()) +
                                  " normals for " + std::to_string(mesh.p_MV.size()) + " vertices");
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      for (const std::uint32_t index : mesh.triangles[t]) {
        if (index >= mesh.p_MV.size()) {
          throw std::invalid_argument(where + ": triangle " + std::to_string(t) +
                                      " refers to vertex " + std::to_string(index) + " of " +
                                      std::to_string(mesh.p_MV.size()));
        }
      }
    }
  }
}

void DrawFrame(const GlApi& gl, const SceneView& scene, const Camera& camera, StereoMode mode,
               int fb_width_px, int fb_height_px, CaptionCache& captions) {
  ValidateScene(scene, camera);
  if (fb_width_px <= 0 || fb_height_px <= 0) return;  // minimized window: nothing to draw.

  gl.Disable(GL_SCISSOR_TEST);
  gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl.ClearColor(scene.background_rgb.r, scene.background_rgb.g, scene.background_rgb.b, 1.0F);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

  const Viewport full{0, 0, fb_width_px, fb_height_px};
  switch (mode) {
    case StereoMode::kMono:
      DrawEye(gl, scene, camera, Eye::kCenter, full);
      DrawCaption(gl, scene, full, captions);
      break;
    case StereoMode::kSideBySide: {
      const int left_width_px = fb_width_px / 2;
      const Viewport left{0, 0, left_width_px, fb_height_px};
      const Viewport right{left_width_px, 0, fb_width_px - left_width_px, fb_height_px};
      if (left.width_px > 0) {
        DrawEye(gl, scene, camera, Eye::kLeft, left);
        DrawCaption(gl, scene, left, captions);
      }
      DrawEye(gl, scene, camera, Eye::kRight, right);
      DrawCaption(gl, scene, right, captions);
      break;
    }
    case StereoMode::kAnaglyph:
      // Red/cyan: the left eye writes only red, the right eye only green and blue.
      gl.ColorMask(GL_TRUE, GL_FALSE, GL_FALSE, GL_TRUE);
      DrawEye(gl, scene, camera, Eye::kLeft, full);
      gl.Clear(GL_DEPTH_BUFFER_BIT);
      gl.ColorMask(GL_FALSE, GL_TRUE, GL_TRUE, GL_TRUE);
      DrawEye(gl, scene, camera, Eye::kRight, full);
      gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      DrawCaption(gl, scene, full, captions);
      break;
  }
  gl.CheckError("drawing the scene");
}

}  // namespace handshare::render::detail
