#include "scene_drawer.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
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
constexpr float kLightSpecular = 0.6F;  // only surfaces with a specular Appearance show it
constexpr GLfloat kLightDirection_Eye[4] = {-0.35F, 0.55F, 1.0F, 0.0F};

// Unit-sphere tessellation (latitude/longitude), built once: 1,728 vertices, still round at a
// fingertip's size on screen (24 x 48 cost about 10 ms of a 1080p frame in software GL: graphics_bench).
constexpr int kSphereStacks = 12;
constexpr int kSphereSlices = 24;

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

// Spheres and meshes go to GL as vertex arrays, one draw call each (immediate mode cost one call
// per vertex attribute: thousands per sphere, too many for 60 frames a second in software).
// A sphere is the unit sphere under a translate-and-scale modelview; its normals are the unit
// sphere's points (GL_NORMALIZE undoes the scale).
// Which objects a draw call takes: the opaque ones (drawn first, writing depth) or those with
// an opacity below 1 (drawn after, blended, not writing depth).
enum class Pass { kOpaque, kTranslucent };
bool InPass(const Appearance& look, Pass pass) { return (look.opacity < 1.0F) == (pass == Pass::kTranslucent); }

// An object's colour (its alpha the opacity) and its highlight.
void SetLook(const GlApi& gl, const Rgb& rgb, const Appearance& look) {
  const GLfloat specular[4] = {look.specular, look.specular, look.specular, 1.0F};
  gl.Materialfv(GL_FRONT_AND_BACK, GL_SPECULAR, specular);
  gl.Materialf(GL_FRONT_AND_BACK, GL_SHININESS, std::clamp(look.shininess, 1.0F, 128.0F));
  gl.Color4f(rgb.r, rgb.g, rgb.b, std::clamp(look.opacity, 0.0F, 1.0F));
}

void DrawSpheres(const GlApi& gl, const std::vector<Sphere>& spheres, Pass pass = Pass::kOpaque) {
  if (spheres.empty()) return;
  const auto& unit = UnitSphereTriangles();
  gl.EnableClientState(GL_VERTEX_ARRAY);
  gl.EnableClientState(GL_NORMAL_ARRAY);
  gl.VertexPointer(3, GL_DOUBLE, 0, unit.data());
  gl.NormalPointer(GL_DOUBLE, 0, unit.data());
  gl.Enable(GL_NORMALIZE);
  for (const Sphere& sphere : spheres) {
    if (!InPass(sphere.look, pass)) continue;
    SetLook(gl, sphere.rgb, sphere.look);
    Eigen::Matrix4d X = Eigen::Matrix4d::Identity();
    X.topLeftCorner<3, 3>() *= sphere.radius_m;
    X.topRightCorner<3, 1>() = sphere.p_W;
    gl.PushMatrix();
    gl.MultMatrixd(X.data());
    gl.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(unit.size()));
    gl.PopMatrix();
  }
  gl.Disable(GL_NORMALIZE);
  gl.DisableClientState(GL_NORMAL_ARRAY);
  gl.DisableClientState(GL_VERTEX_ARRAY);
}

void DrawBoxes(const GlApi& gl, const std::vector<Box>& boxes, Pass pass = Pass::kOpaque) {
  for (const Box& box : boxes) {
    if (!InPass(box.look, pass)) continue;
    const Eigen::Matrix3d R_WB = box.q_WB.normalized().toRotationMatrix();
    SetLook(gl, box.rgb, box.look);
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

// A mesh in its frame M under the modelview X_WM, its vertex normals unit (area-weighted ones
// computed when it has none; a vertex without one gets +z of M), drawn from its own arrays.
void DrawMeshes(const GlApi& gl, const std::vector<TriangleMesh>& meshes, Pass pass = Pass::kOpaque) {
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "vertex arrays read Vector3d as 3 doubles");
  static_assert(sizeof(std::array<std::uint32_t, 3>) == 3 * sizeof(GLuint), "index arrays read 3 GLuints");
  if (meshes.empty()) return;
  std::vector<Eigen::Vector3d> n_MV;
  gl.EnableClientState(GL_VERTEX_ARRAY);
  gl.EnableClientState(GL_NORMAL_ARRAY);
  for (const TriangleMesh& mesh : meshes) {
    if (!InPass(mesh.look, pass)) continue;
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
    for (Eigen::Vector3d& n : n_MV) {
      const double length = n.norm();
      n = length > 0.0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d::UnitZ();
    }
    SetLook(gl, mesh.rgb, mesh.look);
    gl.VertexPointer(3, GL_DOUBLE, 0, mesh.p_MV.data());
    gl.NormalPointer(GL_DOUBLE, 0, n_MV.data());
    const Eigen::Matrix4d X_WM = mesh.X_WM.matrix();
    gl.PushMatrix();
    gl.MultMatrixd(X_WM.data());
    gl.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(3 * mesh.triangles.size()), GL_UNSIGNED_INT,
                    mesh.triangles.data());
    gl.PopMatrix();
  }
  gl.DisableClientState(GL_NORMAL_ARRAY);
  gl.DisableClientState(GL_VERTEX_ARRAY);
}

// Pages: each a texture on its quad, unlit (the paper's and the ink's own colours), tested
// against depth like the scene. Each page's texture object is filled once and bound again while
// the page shows the same content (PageTextureObjects).
void BindPageTexture(const GlApi& gl, const PageTexture& t, PageTextureObjects& objects) {
  PageTextureObjects::Slot& slot = objects.slots[t.slot];
  if (slot.name == 0) {
    gl.GenTextures(1, &slot.name);
    gl.BindTexture(GL_TEXTURE_2D, slot.name);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  } else {
    gl.BindTexture(GL_TEXTURE_2D, slot.name);
  }
  if (slot.serial == t.serial) return;
  slot.serial = t.serial;
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  // Row 0 of the texture image is its top edge: uploaded first, it is t = 0.
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGB, t.width_px, t.height_px, 0, GL_RGB, GL_UNSIGNED_BYTE, t.rgb.data());
  ++objects.uploads;
}

void DrawPages(const GlApi& gl, const std::vector<Page>& pages, PageCache& cache, PageTextureObjects& objects) {
  if (pages.empty()) return;
  gl.TexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE);
  gl.Disable(GL_LIGHTING);
  gl.Enable(GL_TEXTURE_2D);
  for (const Page& page : pages) {
    BindPageTexture(gl, cache.For(page), objects);
    constexpr double kTexCoords[4][2] = {{0.0, 1.0}, {1.0, 1.0}, {1.0, 0.0}, {0.0, 0.0}};
    gl.Begin(GL_QUADS);
    for (int k = 0; k < 4; ++k) {
      gl.TexCoord2d(kTexCoords[k][0], kTexCoords[k][1]);
      const Eigen::Vector3d& p = page.corners_W[static_cast<std::size_t>(k)];
      gl.Vertex3d(p.x(), p.y(), p.z());
    }
    gl.End();
  }
  gl.Disable(GL_TEXTURE_2D);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  gl.Enable(GL_LIGHTING);
}

// Pixel coordinates over `viewport`: x right in [0, w], y DOWN in [0, h] (glOrtho(0, w, h, 0,
// -1, 1)), no depth test, no lighting.
void PixelOrtho(const GlApi& gl, const Viewport& viewport) {
  const int w = viewport.width_px;
  const int h = viewport.height_px;
  gl.Viewport(viewport.x_px, viewport.y_px, w, h);
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
}

// Coverage text in `rgb` with its top-left corner at pixel (x, y) of the current pixel
// ortho (y down), blended (glDrawPixels goes up from the raster position, the text's lower-left
// corner). Rows and columns beyond `max_w` x `max_h` are left out.
void BlendText(const GlApi& gl, const CaptionBitmap& text, const Rgb& rgb, int x, int y, int max_w, int max_h) {
  const int tw = std::min(text.width_px, max_w);
  const int th = std::min(text.height_px, max_h);
  if (tw <= 0 || th <= 0) return;
  const auto channel = [](float v) { return static_cast<std::uint8_t>(std::lround(255.0F * std::clamp(v, 0.0F, 1.0F))); };
  const std::uint8_t r = channel(rgb.r);
  const std::uint8_t g = channel(rgb.g);
  const std::uint8_t b = channel(rgb.b);
  std::vector<std::uint8_t> rgba(4 * static_cast<std::size_t>(tw) * static_cast<std::size_t>(th));
  for (int row = 0; row < th; ++row) {
    std::uint8_t* out = rgba.data() + 4 * static_cast<std::size_t>(th - 1 - row) * static_cast<std::size_t>(tw);
    for (int col = 0; col < tw; ++col) {
      out[4 * col] = r;
      out[4 * col + 1] = g;
      out[4 * col + 2] = b;
      out[4 * col + 3] = text.At(col, row);
    }
  }
  gl.Enable(GL_BLEND);
  gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl.RasterPos2d(x, y + th - 0.5);  // inside the viewport, so the position is valid
  gl.DrawPixels(tw, th, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  gl.Disable(GL_BLEND);
}

// A dark translucent rectangle in pixel ortho coordinates (y down).
void DarkBox(const GlApi& gl, double x0, double y0, double x1, double y1, float alpha) {
  gl.Enable(GL_BLEND);
  gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  gl.Color4f(0.0F, 0.0F, 0.0F, alpha);
  gl.Begin(GL_QUADS);
  gl.Vertex2d(x0, y0);
  gl.Vertex2d(x0, y1);
  gl.Vertex2d(x1, y1);
  gl.Vertex2d(x1, y0);
  gl.End();
  gl.Disable(GL_BLEND);
}

// The labels, in pixel ortho over `viewport`: each centred above its point's projection
// (clip = P V p), kept inside the viewport; skipped behind the eye or off the image.
void DrawLabels(const GlApi& gl, const std::vector<Label>& labels, const Eigen::Matrix4d& clip_from_W,
                const Viewport& viewport, LabelCache& cache) {
  if (labels.empty()) return;
  const int w = viewport.width_px;
  const int h = viewport.height_px;
  PixelOrtho(gl, viewport);
  for (const Label& label : labels) {
    if (label.text.empty() || !label.p_W.allFinite()) continue;
    const Eigen::Vector4d clip = clip_from_W * label.p_W.homogeneous();
    if (clip.w() <= 1e-9) continue;  // behind the eye
    const Eigen::Vector3d ndc = clip.head<3>() / clip.w();
    if (std::abs(ndc.x()) > 1.0 || std::abs(ndc.y()) > 1.0 || std::abs(ndc.z()) > 1.0) continue;
    const double col = (ndc.x() + 1.0) / 2.0 * w;
    const double row = (1.0 - ndc.y()) / 2.0 * h;  // y down
    const CaptionBitmap& text = cache.For(label.text, h, std::max(1, w / 3));
    if (text.width_px == 0 || text.height_px == 0) continue;
    const int pad = std::max(2, text.stats.pixel_size / 4);
    const int box_w = text.width_px + 2 * pad;
    const int box_h = text.height_px + 2 * pad;
    const int x0 = std::clamp(static_cast<int>(std::lround(col)) - box_w / 2, 0, std::max(0, w - box_w));
    const int y0 = std::clamp(static_cast<int>(std::lround(row)) - box_h - pad, 0, std::max(0, h - box_h));
    DarkBox(gl, x0, y0, x0 + box_w, y0 + box_h, 0.5F);
    BlendText(gl, text, label.rgb, x0 + pad, y0 + pad, w - x0 - pad, h - y0 - pad);
  }
}

void SetUpLighting(const GlApi& gl) {
  const GLfloat no_ambient[4] = {0.0F, 0.0F, 0.0F, 1.0F};
  const GLfloat ambient[4] = {kLightAmbient, kLightAmbient, kLightAmbient, 1.0F};
  const GLfloat diffuse[4] = {kLightDiffuse, kLightDiffuse, kLightDiffuse, 1.0F};
  const GLfloat specular[4] = {kLightSpecular, kLightSpecular, kLightSpecular, 1.0F};
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
             const Viewport& viewport, TextCaches& text) {
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
  DrawPages(gl, scene.pages, text.pages, text.page_objects);
  // What shows what is behind it: after everything opaque, blended, writing no depth.
  gl.Enable(GL_BLEND);
  gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  gl.DepthMask(GL_FALSE);
  DrawSpheres(gl, scene.spheres, Pass::kTranslucent);
  DrawBoxes(gl, scene.boxes, Pass::kTranslucent);
  DrawMeshes(gl, scene.meshes, Pass::kTranslucent);
  gl.DepthMask(GL_TRUE);
  gl.Disable(GL_BLEND);
  if (!scene.labels.empty()) {
    // Over the scene, under the hands and fingertips; then back to the eye's matrices.
    DrawLabels(gl, scene.labels, projection * view, viewport, text.labels);
    gl.Viewport(viewport.x_px, viewport.y_px, viewport.width_px, viewport.height_px);
    gl.MatrixMode(GL_PROJECTION);
    gl.LoadMatrixd(projection.data());
    gl.MatrixMode(GL_MODELVIEW);
    gl.LoadMatrixd(view.data());
    gl.Enable(GL_DEPTH_TEST);
    gl.Enable(GL_LIGHTING);
  }
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
  PixelOrtho(gl, viewport);
  // Dark translucent band so the text reads over any scene, then the text over it.
  DarkBox(gl, 0, h - band_px, w, h, 0.65F);
  const int th = std::min(text.height_px, band_px);
  const int top_px = h - band_px + std::max(0, (band_px - th) / 2);
  BlendText(gl, text, scene.caption_rgb, margin_px, top_px, std::max(0, w - margin_px), band_px);
}

// The overlay at the top-left of `viewport`: a dark box as large as its text, the text over it.
void DrawOverlay(const GlApi& gl, const SceneView& scene, const Viewport& viewport, LabelCache& cache) {
  if (scene.overlay.empty()) return;
  const int w = viewport.width_px;
  const int h = viewport.height_px;
  const CaptionBitmap& text = cache.For(scene.overlay, h, std::max(1, w / 2));
  if (text.width_px == 0 || text.height_px == 0) return;
  const int pad = std::max(2, text.stats.pixel_size / 2);
  PixelOrtho(gl, viewport);
  DarkBox(gl, 0, 0, std::min(w, text.width_px + 2 * pad), std::min(h, text.height_px + 2 * pad), 0.55F);
  BlendText(gl, text, scene.overlay_rgb, pad, pad, std::max(0, w - pad), std::max(0, h - pad));
}

}  // namespace

void ValidateScene(const SceneView& scene, const Camera& camera) {
  ValidateCamera(camera);
  for (std::size_t p = 0; p < scene.pages.size(); ++p) {
    const Page& page = scene.pages[p];
    const std::string where = "render::SceneView: pages[" + std::to_string(p) + "]";
    for (const Eigen::Vector3d& corner : page.corners_W) {
      if (!corner.allFinite()) throw std::invalid_argument(where + " has a non-finite corner");
    }
    if (page.image && (page.image->width_px < 0 || page.image->height_px < 0 ||
                       page.image->rgb.size() != 3 * static_cast<std::size_t>(page.image->width_px) *
                                                     static_cast<std::size_t>(page.image->height_px))) {
      throw std::invalid_argument(where + ": its image holds " + std::to_string(page.image->rgb.size()) +
                                  " bytes for " + std::to_string(page.image->width_px) + " x " +
                                  std::to_string(page.image->height_px) + " pixels");
    }
  }
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
               int fb_width_px, int fb_height_px, TextCaches& text) {
  CaptionCache& captions = text.captions;
  ValidateScene(scene, camera);
  if (fb_width_px <= 0 || fb_height_px <= 0) return;  // minimized window: nothing to draw.

  gl.Disable(GL_SCISSOR_TEST);
  gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl.ClearColor(scene.background_rgb.r, scene.background_rgb.g, scene.background_rgb.b, 1.0F);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

  const Viewport full{0, 0, fb_width_px, fb_height_px};
  switch (mode) {
    case StereoMode::kMono:
      DrawEye(gl, scene, camera, Eye::kCenter, full, text);
      DrawCaption(gl, scene, full, captions);
      DrawOverlay(gl, scene, full, text.overlay);
      break;
    case StereoMode::kSideBySide: {
      const int left_width_px = fb_width_px / 2;
      const Viewport left{0, 0, left_width_px, fb_height_px};
      const Viewport right{left_width_px, 0, fb_width_px - left_width_px, fb_height_px};
      if (left.width_px > 0) {
        DrawEye(gl, scene, camera, Eye::kLeft, left, text);
        DrawCaption(gl, scene, left, captions);
        DrawOverlay(gl, scene, left, text.overlay);
      }
      DrawEye(gl, scene, camera, Eye::kRight, right, text);
      DrawCaption(gl, scene, right, captions);
      DrawOverlay(gl, scene, right, text.overlay);
      break;
    }
    case StereoMode::kAnaglyph:
      // Red/cyan: the left eye writes only red, the right eye only green and blue.
      gl.ColorMask(GL_TRUE, GL_FALSE, GL_FALSE, GL_TRUE);
      DrawEye(gl, scene, camera, Eye::kLeft, full, text);
      gl.Clear(GL_DEPTH_BUFFER_BIT);
      gl.ColorMask(GL_FALSE, GL_TRUE, GL_TRUE, GL_TRUE);
      DrawEye(gl, scene, camera, Eye::kRight, full, text);
      gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      DrawCaption(gl, scene, full, captions);
      DrawOverlay(gl, scene, full, text.overlay);
      break;
  }
  gl.CheckError("drawing the scene");
}

}  // namespace handshare::render::detail
