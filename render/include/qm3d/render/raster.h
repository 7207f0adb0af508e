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
// Point clouds (which mmetric draws as nothing) are drawn as splats: each point a screen-aligned
// square of `splat_size` (world units; at least one pixel) at the point's depth, in its colour;
// points in canonical order (sorted), so the image does not depend on the file's point order.
// The same pixels on every machine with IEEE single precision and no fused multiply-add.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d::render {

using Float3 = std::array<float, 3>;

/// An object as the rasteriser draws it.
struct RenderModel {
  std::vector<Float3> positions;
  /// One colour per position, 0..255 (integers); empty = drawn red, as mmetric draws a mesh
  /// without colours.
  std::vector<Float3> colors_255;
  /// Faces in canonical order; empty for a point cloud (drawn as splats).
  std::vector<Triangle> triangles;
  /// Side of each point's square splat in world units (clouds only).
  float splat_size = 0;

  bool is_cloud() const { return triangles.empty(); }
};

/// A mesh made ready to draw (float precision, rounded colours, canonical face order).
/// `has_colors` false: drawn red. FormatError when it has no faces.
RenderModel mesh_model(const ColoredMesh& mesh, bool has_colors = true);

/// How a cloud's splat size is chosen.
struct SplatOptions {
  /// World units; 0 = kAutoSplatFactor times the median distance of a point to its nearest
  /// other point (over an evenly spaced subset of at most kSpacingSamples points).
  double size = 0;
};
/// Splat side = this many median nearest-neighbour spacings: a surface sampled uniformly at
/// random leaves about exp(-0.22 * 16) = 3 % of it uncovered at this size (Poisson coverage),
/// so a mesh and a cloud sampled from it give few unmatched pixels.
constexpr double kAutoSplatFactor = 4.0;
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

struct RasterOptions {
  int resolution = 2048;  ///< width = height, pixels
  bool culling = true;    ///< back-face culling (mmetric's default; --ibsmDisableCulling)
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
