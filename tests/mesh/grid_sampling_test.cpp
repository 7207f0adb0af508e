// mmetric's grid sampling (qm3d/mesh/grid_sampling.h) against mmetric's own sampled clouds
// (shared/data/reference/mpeg/sampled/, case mm_pcc_blob4_bothnoise_g100: G = 100, the pair's
// shared box, --useNormal) and on small meshes whose samples are known.
#include "qm3d/mesh/grid_sampling.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <stdexcept>
#include <tuple>

#include "qm3d/common/error.h"
#include "qm3d/common/ply.h"
#include "qm3d/mesh/mesh_io.h"
#include "test_paths.h"

namespace qm3d::mesh {
namespace {

using test::reference_dir;

struct Reference {
  std::vector<Float3> positions, normals;
  std::vector<std::array<std::uint8_t, 3>> colours;
};

Float3 as_float(const Vec3& v) {
  return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

// mmetric's file: ASCII float x y z nx ny nz (9 digits: the float32 values exactly), uchar rgb.
Reference read_reference(const std::string& file) {
  const ply::Content c =
      ply::read(reference_dir() / "mpeg" / "sampled" / file, ply::AsciiFloat::kAsDeclared);
  Reference r;
  for (const Vec3& p : c.positions) r.positions.push_back(as_float(p));
  for (const Vec3& n : c.normals) r.normals.push_back(as_float(n));
  for (const Rgb& rgb : c.colors) {
    r.colours.push_back({static_cast<std::uint8_t>(std::lround(rgb.r * 255)),
                         static_cast<std::uint8_t>(std::lround(rgb.g * 255)),
                         static_cast<std::uint8_t>(std::lround(rgb.b * 255))});
  }
  return r;
}

ColoredMesh blob4(const std::string& name) {
  return read_mesh(reference_dir() / "cmdm" / (name + ".ply")).mesh;
}

using Row = std::tuple<Float3, Float3, std::array<std::uint8_t, 3>>;

std::vector<Row> rows(const std::vector<Float3>& p, const std::vector<Float3>& n,
                      const std::vector<std::array<std::uint8_t, 3>>& c) {
  std::vector<Row> out;
  for (std::size_t i = 0; i < p.size(); ++i) out.emplace_back(p[i], n[i], c[i]);
  return out;
}

TEST(GridSampling, EqualsMmetricsSamplesOfTheKeptCase) {
  const ColoredMesh a = blob4("blob4_ref");
  const ColoredMesh b = blob4("blob4_bothnoise");
  GridSamplingOptions o;
  o.grid_size = 100;
  o.box = union_box(vertex_box(a.positions), vertex_box(b.positions));
  // The table's box (minPos / maxPos of the case), as float32.
  EXPECT_EQ(o.box->min, (Float3{-0.997778773f, -1.05314529f, -1.04921687f}));
  EXPECT_EQ(o.box->max, (Float3{1.05481851f, 1.04963803f, 1.05762815f}));
  for (const auto& [mesh, file] :
       {std::pair{&a, "blob4_ref_g100.ply"}, std::pair{&b, "blob4_bothnoise_g100.ply"}}) {
    SCOPED_TRACE(file);
    const GridSamples s = sample_grid(*mesh, o);
    const Reference r = read_reference(file);
    EXPECT_FLOAT_EQ(s.step, 0.021281261f);
    ASSERT_EQ(s.positions.size(), r.positions.size());
    ASSERT_EQ(s.colours.size(), r.colours.size());
    // The same points in the same order (mmetric's output order: triangle by triangle).
    std::size_t differ = 0;
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
      differ += s.positions[i] != r.positions[i] || s.normals[i] != r.normals[i] ||
                s.colours[i] != r.colours[i];
    }
    EXPECT_EQ(differ, 0u);
    // And so the same point set.
    std::vector<Row> ours = rows(s.positions, s.normals, s.colours);
    std::vector<Row> theirs = rows(r.positions, r.normals, r.colours);
    std::sort(ours.begin(), ours.end());
    std::sort(theirs.begin(), theirs.end());
    EXPECT_TRUE(ours == theirs);
  }
}

TEST(GridSampling, SameSamplesOnAnyThreadCount) {
  const ColoredMesh a = blob4("blob4_ref");
  GridSamplingOptions o;
  o.grid_size = 200;
  o.threads = 1;
  const GridSamples one = sample_grid(a, o);
  for (int threads : {2, 3}) {
    o.threads = threads;
    const GridSamples many = sample_grid(a, o);
    EXPECT_EQ(many.positions, one.positions);
    EXPECT_EQ(many.normals, one.normals);
    EXPECT_EQ(many.colours, one.colours);
  }
}

// A unit right triangle in z = 0 on the box [0, 1]^2 x [0, 0] with G = 3 (step 0.5): rays along
// z from the 3 x 3 nodes; the 6 nodes with x + y <= 1 hit it (edges included).
ColoredMesh unit_triangle() {
  ColoredMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 1, 2}};
  return m;
}

TEST(GridSampling, RaysFromTheGridNodesHitTheTriangleEdgesIncluded) {
  GridSamplingOptions o;
  o.grid_size = 3;
  const GridSamples s = sample_grid(unit_triangle(), o);
  ASSERT_EQ(s.positions.size(), 6u);
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    EXPECT_LE(s.positions[i][0] + s.positions[i][1], 1.0f);
    EXPECT_EQ(s.normals[i], (Float3{0, 0, 1}));
    // Barycentric colour: red at (0, 0), green at (1, 0), blue at (0, 1).
    const float x = s.positions[i][0], y = s.positions[i][1];
    EXPECT_EQ(s.colours[i][0], std::lround(255 * (1 - x - y)));
    EXPECT_EQ(s.colours[i][1], std::lround(255 * x));
    EXPECT_EQ(s.colours[i][2], std::lround(255 * y));
  }
}

TEST(GridSampling, AllAxesFindsTheSamePointsOnceEach) {
  GridSamplingOptions o;
  o.grid_size = 3;
  o.all_axes = true;  // the box is flat in z: x and y rays are skipped, as mmetric does
  const GridSamples s = sample_grid(unit_triangle(), o);
  EXPECT_EQ(s.positions.size(), 6u);
}

TEST(GridSampling, DuplicateSamplesOfTwoCoplanarTrianglesAreDroppedInOrder) {
  // Two triangles of one square, same colour everywhere: the nodes on the shared diagonal are
  // hit by both with the same normal and colour, and kept once.
  ColoredMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.colors.assign(4, Rgb{0.5, 0.5, 0.5});
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  GridSamplingOptions o;
  o.grid_size = 3;
  const GridSamples s = sample_grid(m, o);
  EXPECT_EQ(s.positions.size(), 9u);
  EXPECT_EQ(s.duplicate_samples, 3u);
}

TEST(GridSampling, ZeroAreaFacesAreSkippedAndCounted) {
  ColoredMesh m = unit_triangle();
  m.positions.push_back({0.5, 0.5, 0});
  m.colors.push_back({1, 1, 1});
  m.triangles.push_back({0, 3, 3});  // coincident corners
  m.triangles.push_back({0, 1, 1});
  GridSamplingOptions o;
  o.grid_size = 3;
  const GridSamples s = sample_grid(m, o);
  EXPECT_EQ(s.degenerate_faces, 2u);
  EXPECT_EQ(s.positions.size(), 6u);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0], "2 faces of zero area were not sampled (as mmetric)");
}

TEST(GridSampling, AGridWithoutSamplesIsAnError) {
  ColoredMesh m = unit_triangle();
  m.triangles = {{0, 1, 1}};  // nothing to sample
  GridSamplingOptions o;
  o.grid_size = 3;
  EXPECT_THROW(sample_grid(m, o), NumericError);
}

TEST(GridSampling, AMeshWithoutColoursHasNone) {
  ColoredMesh m = unit_triangle();
  m.colors.clear();
  GridSamplingOptions o;
  o.grid_size = 3;
  const GridSamples s = sample_grid(m, o);
  EXPECT_EQ(s.positions.size(), 6u);
  EXPECT_TRUE(s.colours.empty());
}

TEST(GridSampling, BadGridSizesAndBoxesAreRefused) {
  GridSamplingOptions o;
  o.grid_size = 1;
  EXPECT_THROW(sample_grid(unit_triangle(), o), std::invalid_argument);
  o.grid_size = 10;
  o.box = FloatBox{{0, 0, 0}, {1, 0, 0}};  // a segment: no ray crosses it
  EXPECT_THROW(sample_grid(unit_triangle(), o), NumericError);
  o.box = FloatBox{{0, 0, 0}, {NAN, 1, 1}};
  EXPECT_THROW(sample_grid(unit_triangle(), o), NumericError);
  // A box that leaves part of the mesh out: sampled as mmetric does, with a warning.
  o.box = FloatBox{{0, 0, 0}, {0.5f, 0.5f, 0}};
  const GridSamples s = sample_grid(unit_triangle(), o);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("outside"), std::string::npos);
  EXPECT_FALSE(s.positions.empty());
}

TEST(GridSampling, TheSampleCountIsBounded) {
  GridSamplingOptions o;
  o.grid_size = 1000000;  // 5e11 nodes on this triangle: refused up front with the estimate
  try {
    sample_grid(unit_triangle(), o);
    ADD_FAILURE() << "no exception";
  } catch (const MemoryLimitError& e) {
    EXPECT_NE(std::string(e.what()).find("samples (the faces' area / step^2)"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace qm3d::mesh
