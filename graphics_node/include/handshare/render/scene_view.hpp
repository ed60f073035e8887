#pragma once
/// @file
/// Plain data that the renderers draw: a camera and one frame's worth of scene content.
/// Nothing here depends on OpenGL or on the middleware; the graphics node fills these from DDS.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "handshare/render/image.hpp"

namespace handshare::render {

/// A colour with components in [0, 1] (linear, no gamma handling).
struct Rgb {
  float r = 1.0F;
  float g = 1.0F;
  float b = 1.0F;
};

/// How the two eyes of a stereo camera are laid out in the output.
enum class StereoMode {
  kMono,        ///< one image from the camera's eye.
  kSideBySide,  ///< left eye in the left half, right eye in the right half (twice the width).
  kAnaglyph,    ///< red from the left eye, green and blue from the right eye (red/cyan glasses).
};

/// A pinhole camera in the OpenGL convention.
///
/// Projection convention (identical to gluLookAt + gluPerspective + a full-image viewport):
///   f = normalize(target_W - eye_W), s = normalize(f x up_W), u = s x f.
///   For a world point p_W, camera coordinates are
///     x_C = s . (p_W - eye_W),  y_C = u . (p_W - eye_W),  depth = f . (p_W - eye_W)  (> 0 in front).
///   With aspect = width_px / height_px and c = cot(fov_y_rad / 2):
///     x_ndc = (c / aspect) * x_C / depth,   y_ndc = c * y_C / depth.
///   Continuous image coordinates (pixel (col, row) covers [col, col+1) x [row, row+1)):
///     col = (x_ndc + 1) / 2 * width_px,   row = (1 - y_ndc) / 2 * height_px,
///   so row 0 is the TOP row of the image (and of the PNG), column 0 the leftmost.
///   Only points with near_m <= depth <= far_m are drawn.
///
/// Stereo (StereoMode::kSideBySide, kAnaglyph): each eye E is the camera translated by
/// e = -/+ stereo_eye_separation_m / 2 (left/right) along s, looking along the same f (parallel
/// axes, no toe-in), with an asymmetric (off-axis) frustum whose zero-parallax plane lies at the
/// focal distance d = |target_W - eye_W|:
///     x_ndc = (c / aspect) * ((x_C - e) / depth + e / d),   y_ndc as in mono,
/// with x_C, depth measured from the mono eye. Points at depth d land on the same pixel in both
/// eyes; nearer points shift left in the right eye's image, farther points shift right.
struct Camera {
  Eigen::Vector3d eye_W{0.0, -1.0, 0.5};    ///< eye (centre of projection) in world W [m].
  Eigen::Vector3d target_W{0.0, 0.0, 0.0};  ///< point looked at in W [m]; sets the stereo focal distance.
  Eigen::Vector3d up_W{0.0, 0.0, 1.0};      ///< up direction in W (need not be unit or orthogonal to f).
  double fov_y_rad = 0.8;                    ///< vertical field of view [rad], in (0, pi).
  int width_px = 640;                        ///< image width of one eye [pixels].
  int height_px = 480;                       ///< image height [pixels].
  double near_m = 0.01;                      ///< near clip distance [m], > 0.
  double far_m = 100.0;                      ///< far clip distance [m], > near_m.
  double stereo_eye_separation_m = 0.065;    ///< interocular distance [m], used in stereo modes only.
};

/// Throws std::invalid_argument naming the offending field if `camera` cannot define a projection
/// (non-finite vectors, eye == target, up parallel to the view direction, bad fov, size or clip).
void ValidateCamera(const Camera& camera);

/// How a surface takes the light beyond its colour: a white highlight of `specular` strength
/// (0: matte) and `shininess` tightness (1..128, the Phong exponent), and its `opacity` (1:
/// opaque; below 1 it is drawn after everything opaque, blended, without hiding what is behind
/// it).
struct Appearance {
  float specular = 0.0F;
  float shininess = 32.0F;
  float opacity = 1.0F;
};

/// A shaded sphere, e.g. a fingertip.
struct Sphere {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();  ///< centre in W [m].
  double radius_m = 0.01;                          ///< radius [m], > 0.
  Rgb rgb;                                         ///< colour.
  Appearance look{};
};

/// A shaded box B.
struct Box {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();                  ///< centre of B in W [m].
  Eigen::Vector3d half_extents_m{0.05, 0.05, 0.05};               ///< half sizes along B's axes [m].
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();       ///< orientation of B in W.
  Rgb rgb;                                                        ///< colour.
  Appearance look{};
};

/// A triangle mesh in its own frame M (for example a deformable object's surface, whose vertex
/// positions change every frame). Triangles are counter-clockwise seen from outside; both sides
/// are lit.
struct TriangleMesh {
  Eigen::Isometry3d X_WM = Eigen::Isometry3d::Identity();  ///< pose of mesh frame M in W.
  std::vector<Eigen::Vector3d> p_MV;                        ///< vertex positions in M [m].
  std::vector<std::array<std::uint32_t, 3>> triangles;      ///< vertex indices into p_MV.
  /// Optional per-vertex normals in M (any length, normalized when drawn). Empty: area-weighted
  /// vertex normals are computed from the triangles. Otherwise the size must equal p_MV's.
  std::vector<Eigen::Vector3d> n_MV;
  Rgb rgb;                                                  ///< colour.
  Appearance look{};
};

/// A square grid of lines on a plane, drawn unlit.
struct GroundGrid {
  bool visible = true;                                       ///< draw it at all.
  Eigen::Vector3d center_W = Eigen::Vector3d::Zero();        ///< centre of the grid in W [m].
  Eigen::Vector3d normal_W = Eigen::Vector3d::UnitZ();       ///< plane normal in W (non-zero).
  double half_size_m = 1.0;                                  ///< grid spans +- half_size_m [m].
  double spacing_m = 0.1;                                    ///< distance between lines [m], > 0.
  Rgb rgb{0.45F, 0.45F, 0.5F};                               ///< line colour.
};

/// A flat page in the scene (a book's open spread): paper with a picture, text, or both (the
/// picture above, fitted to the page's width and keeping its aspect; the text below it in the
/// caption font, wrapped to the page, cut with an ellipsis where it does not fit). Drawn unlit,
/// as a texture on the quad, hidden by what is in front of it.
struct Page {
  /// Corners in W [m], counter-clockwise seen from the front: bottom-left, bottom-right,
  /// top-right, top-left as the page is read.
  std::array<Eigen::Vector3d, 4> corners_W{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                           Eigen::Vector3d(1.0, 1.0, 0.0), Eigen::Vector3d::UnitY()};
  std::string text;                        ///< UTF-8; '\n' starts a paragraph; empty: none
  std::shared_ptr<const ImageRgb8> image;  ///< null: none
  Rgb paper{0.96F, 0.94F, 0.88F};
  Rgb ink{0.10F, 0.10F, 0.12F};
};

/// A label: a few words on screen beside a point of the scene (an object's or a control's
/// name), in the caption font (em height 1/40 of the image's, at least 12 px), on a dark
/// translucent box, centred above the point's projection and kept inside the image. Drawn over
/// the scene and its pages but under the hands and the fingertips, which must stay visible; not
/// drawn when the point is behind the eye or outside the image.
struct Label {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();  ///< the point it names, in W [m].
  std::string text;                               ///< UTF-8, at most two lines drawn.
  Rgb rgb{1.0F, 0.93F, 0.6F};                     ///< text colour.
};

/// What the caption of the last frame held: for a viewer to report, and for tests.
struct CaptionStats {
  int pixel_size = 0;      ///< the font's em height [px]
  int lines = 0;           ///< lines drawn
  int glyphs = 0;          ///< characters drawn with the font's own glyph (spaces not counted)
  int missing_glyphs = 0;  ///< characters the font lacks, drawn as hollow boxes
  bool cut = false;        ///< the text did not fit and ends in an ellipsis
};

/// Everything drawn in one frame.
struct SceneView {
  std::vector<Sphere> spheres;
  std::vector<Box> boxes;
  std::vector<TriangleMesh> meshes;
  std::vector<Page> pages;
  std::vector<Label> labels;
  /// The users' hands, drawn after the scene (hidden by what is in front of them) without
  /// writing depth: the markers show through them.
  std::vector<Box> hand_boxes;
  std::vector<Sphere> hand_spheres;
  /// Drawn last, over the hands: the fingertips (the contact points a spectator must see).
  std::vector<Sphere> markers;
  GroundGrid grid;
  /// The message board, UTF-8, drawn at the bottom of the image over a dark band in the caption
  /// font (FreeType, a CJK font: Latin and Japanese): wrapped to the image's width, '\n' starts a
  /// paragraph, at most a third of the height; text beyond that is cut and ends in an ellipsis.
  /// A character the font lacks is drawn as a hollow box. Empty: no band.
  std::string caption;
  Rgb caption_rgb{1.0F, 1.0F, 1.0F};            ///< caption text colour.
  /// Text over the top-left corner of the image (a user's help and readouts), UTF-8, '\n'
  /// starts a line, in the caption font (em height 1/50 of the image's, at least 12 px, at most
  /// 30 lines, half the image's width) on a dark translucent box. Empty: none.
  std::string overlay;
  Rgb overlay_rgb{0.95F, 0.95F, 0.85F};         ///< overlay text colour.
  Rgb background_rgb{0.08F, 0.09F, 0.12F};      ///< clear colour.
};

}  // namespace handshare::render
