// A deterministic software rasteriser: orthographic views of a coloured mesh or point cloud,
// no GPU or display. For meshes it reproduces mmetric 1.1.7's `sw_raster` pixel for pixel
// (MPEGGroup/mpeg-pcc-mmetric @ 5faa660: source/lib/source/mmRendererSw.cpp `rasterize`,
// `RendererSw::render`; the views of mmCompare.cpp `fibonacciSphere`):
// - the object at float precision, colours 0..255 rounded (roundf(float(c) * 255), as mmetric
//   reads OBJ and PLY colours), faces in mmetric's "oriented" canonical order (mmModel.h
//   `reorder`: vertices deduplicated and sorted, each face rotated to start at its smallest
//   vertex, faces sorted and deduplicated);
// - the camera framed on a bounding sphere: the centre and half diagonal (+1 %) of a box (both
//   objects' in a comparison), looking at the centre from direction * radius, orthographic;
// - a pixel (x, y) (its corner, integer coordinates, row 0 at the bottom) is drawn by a face when
//   its float barycentrics are all >= 0, nearer than what is there (a larger depth; ties keep the
//   earlier face); colours interpolated linearly and rounded; back faces (clockwise on screen)
//   culled unless culling is off.
// Textured OBJ meshes are coloured per pixel from their texture as mmetric's ShaderMap does
// (bilinear texel lookup at the interpolated UV).
// Point clouds (which mmetric draws as nothing) are drawn as splats: each point a disc (or a
// screen-aligned square) of `splat_size` (world units; at least one pixel) at the point's depth,
// in its colour, through an epsilon-z-buffer (raster.cpp draw_splats: the back does not show
// through gaps; a pixel takes the nearest splat centre on the front surface); points in canonical
// order (sorted), so the image does not depend on the file's point order.
// Optionally a headlight shades meshes (Lighting). Views: mmetric's Fibonacci sphere or the 18
// directions of the CMDM report's protocol (cmdm18_directions).
// The same pixels on every machine with IEEE single precision and no fused multiply-add.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "qm3d/common/types.h"
#include "qm3d/mesh/texture.h"

namespace qm3d::render {

using qm3d::Float3;  // common/grid_samples.h

/// How a cloud's points are drawn.
enum class SplatShape {
  kSquare,  ///< a screen-aligned square of side splat_size
  kDisc,    ///< the pixels within splat_size / 2 of the point's projection
};

/// An object as the rasteriser draws it.
struct RenderModel {
  std::vector<Float3> positions;
  /// One colour per position, 0..255 (integers); empty = drawn red, as mmetric draws a mesh
  /// without colours (and without a texture).
  std::vector<Float3> colors_255;
  /// Faces in canonical order; empty for a point cloud (drawn as splats).
  std::vector<Triangle> triangles;
  /// Textured meshes (mmetric's ShaderMap): one UV per position (a vertex of the canonical
  /// order is a (position, UV) pair), one texture index per face, the textures.
  std::vector<std::array<float, 2>> uvs;
  std::vector<std::uint32_t> triangle_texture;
  std::shared_ptr<const std::vector<mesh::TextureImage>> textures;
  /// Unit vertex normals (meshes; the headlight's): the sum of the adjacent faces' area-weighted
  /// normals, normalised (0 for a vertex of zero-area faces only).
  std::vector<Float3> normals;
  /// Side of each point's splat in world units (clouds only).
  float splat_size = 0;
  SplatShape splat_shape = SplatShape::kDisc;

  bool is_cloud() const { return triangles.empty(); }
  bool is_textured() const { return !uvs.empty(); }
};

/// A mesh made ready to draw (float precision, rounded colours, canonical face order).
/// `has_colors` false: drawn red. FormatError when it has no faces.
RenderModel mesh_model(const ColoredMesh& mesh, bool has_colors = true);
/// A textured OBJ made ready to draw: its faces' UVs and textures, each pixel coloured by
/// mmetric's bilinear texel lookup (mesh::mm_texture_lookup) at the interpolated UV; vertices
/// keyed by (position, UV) in mmetric's canonical order, faces sorted by (corners, texture).
RenderModel textured_mesh_model(const mesh::TexturedMesh& mesh);

/// How a cloud's splat size is chosen.
struct SplatOptions {
  /// World units; 0 = kAutoSplatFactor times the median distance of a point to its nearest
  /// other point (over an evenly spaced subset of at most kSpacingSamples points).
  double size = 0;
  SplatShape shape = SplatShape::kDisc;
};
/// Splat size = this many median nearest-neighbour spacings. Chosen by measurement: the monkey
/// of the CMDM set against 500k points sampled from it (1024², 16 views, discs) scores
/// YUV PSNR 40.9 / 38.8 / 37.3 dB at 4 / 6 / 8 spacings, with 5.8 / 2.9 / 3.1 % unmatched
/// pixels (smaller splats leave gaps where no point lands; larger ones widen the silhouette and
/// blur the colours).
constexpr double kAutoSplatFactor = 6.0;
constexpr std::size_t kSpacingSamples = 20000;

/// A cloud made ready to draw (points sorted, rounded colours, splat size). FormatError when it
/// is empty, or when the spacing is 0 (all points equal) and no size is given.
RenderModel cloud_model(const ColoredCloud& cloud, const SplatOptions& options = {});

/// The bounding sphere the camera is framed on (mmetric's BSphereCtr / BSphereRad).
struct Frame {
  Float3 center{0, 0, 0};
  float radius = 0;
};
/// The bounding box of both models' positions (float), its centre and half diagonal + 1 %.
Frame frame_of(const RenderModel& a, const RenderModel& b);
/// 100 * diagonal(b's box) / diagonal(a's box) (mmetric's BoxRatio).
double box_ratio(const RenderModel& a, const RenderModel& b);

/// `count` view directions on a Fibonacci sphere (mmetric's fibonacciSphere), rotated by
/// `rotation_deg` = (polar angle, azimuth, rotation magnitude) in degrees as mmetric's
/// --ibsmCameraRotation (applied only when the magnitude is not 0). std::invalid_argument when
/// count < 2 (mmetric divides by count - 1).
std::vector<Float3> fibonacci_directions(int count, const Float3& rotation_deg = {0, 0, 0});

/// The 18 view directions of the CMDM report's image metrics ("18 snapshots taken from
/// different viewpoints, camera positions regularly sampled"; the report gives no list): the
/// 6 axis directions +x, -x, +y, -y, +z, -z, then the 12 diagonals of the coordinate planes,
/// (+-1, +-1, 0), (+-1, 0, +-1), (0, +-1, +-1) normalised (the centres of a cube's faces and
/// edges seen from its centre), in that order, signs + before -.
std::vector<Float3> cmdm18_directions();

/// How surfaces are shaded.
enum class Lighting {
  kUnlit,      ///< the colour itself (mmetric's sw_raster without a texture: ShaderCpv)
  /// A headlight: colour * (0.4 + 0.6 * max(n . v, 0)), n the interpolated vertex normal
  /// renormalised per pixel, v the direction towards the camera (mmetric's ShaderMapLight with
  /// its default ambient 0.4, diffuse 0.6, white light, placed at the camera); |n . v| when
  /// culling is off, so that back faces are lit as seen. Meshes only: a cloud's splats are
  /// drawn unlit (a cloud has no normals to shade with).
  kHeadlight,
};

struct RasterOptions {
  int resolution = 2048;  ///< width = height, pixels
  bool culling = true;    ///< back-face culling (mmetric's default; --ibsmDisableCulling)
  Lighting lighting = Lighting::kUnlit;
};

/// One rendered view: RGBA (alpha 255 where drawn, 0 elsewhere) and depth (larger = nearer;
/// -FLT_MAX where nothing is drawn), rows bottom first (OpenGL's order, as mmetric).
struct View {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;
  std::vector<float> depth;
  /// The depth range of the frame's sphere in depth units (mmetric's depthRange, the "signal
  /// dynamic" of its depth PSNR).
  float depth_range = 0;
  std::size_t drawn_pixels() const;
};

/// Renders `model` seen from `direction` (towards the frame's centre), framed on `frame`.
/// std::invalid_argument for a resolution < 1.
View render_view(const RenderModel& model, const Frame& frame, const Float3& direction,
                 const RasterOptions& options = {});

}  // namespace qm3d::render
