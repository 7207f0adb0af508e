// The two geometry types every reader produces and every metric consumes.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace qm3d {

/// A 3-D position or vector, in the file's units.
using Vec3 = std::array<double, 3>;

/// An sRGB colour with channels in [0, 1] (gamma-encoded, as stored in files).
struct Rgb {
  double r = 0;
  double g = 0;
  double b = 0;
};

/// A triangle as three vertex indices.
using Triangle = std::array<std::uint32_t, 3>;

/// A colored point cloud: #P positions and #P colours.
struct ColoredCloud {
  std::vector<Vec3> positions;
  std::vector<Rgb> colors;

  std::size_t size() const { return positions.size(); }
};

/// A triangle mesh with one colour per vertex: #V positions, #V colours, #F triangles.
struct ColoredMesh {
  std::vector<Vec3> positions;
  std::vector<Rgb> colors;
  std::vector<Triangle> triangles;

  std::size_t num_vertices() const { return positions.size(); }
};

/// The vertices of a mesh as a point cloud (faces dropped).
inline ColoredCloud vertex_cloud(const ColoredMesh& mesh) {
  return ColoredCloud{mesh.positions, mesh.colors};
}

/// Axis-aligned bounding box of a set of positions.
struct BoundingBox {
  Vec3 min{0, 0, 0};
  Vec3 max{0, 0, 0};

  /// The longest side, max over axes of (max - min): CMDM's "BB" (SPEC-CMDM 1.4).
  double longest_side() const;
};

/// Bounding box of a non-empty set of positions. Throws NumericError when empty.
BoundingBox bounding_box(const std::vector<Vec3>& positions);
/// Bounding box of the positions in [begin, end).
BoundingBox bounding_box(const Vec3* begin, const Vec3* end);

}  // namespace qm3d
