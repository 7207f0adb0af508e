// The rasteriser (qm3d/render/raster.h): views, framing, coverage and culling, colours (vertex,
// texture, headlight), mmetric's canonical order, clouds as splats, determinism.
#include "qm3d/render/raster.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "qm3d/common/error.h"
#include "qm3d/render/ibsm.h"

namespace qm3d::render {
namespace {

double norm(const Float3& v) { return std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]); }

/// A unit square in the plane z = 0 facing +z (counter-clockwise seen from +z), two triangles.
ColoredMesh square(const Rgb& c0, const Rgb& c1, const Rgb& c2, const Rgb& c3) {
  ColoredMesh m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  m.colors = {c0, c1, c2, c3};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

const Float3 kFront{0, 0, 1};  // from +z, looking at the square's front

/// The RGB of the view's pixel (x, y) (rows bottom first, as View holds them).
std::array<int, 4> pixel(const View& v, int x, int y) {
  const std::size_t i = (static_cast<std::size_t>(y) * v.width + x) * 4;
  return {v.rgba[i], v.rgba[i + 1], v.rgba[i + 2], v.rgba[i + 3]};
}

TEST(Raster, FibonacciDirectionsAreMmetricsSphere) {
  const std::vector<Float3> d = fibonacci_directions(16);
  ASSERT_EQ(d.size(), 16u);
  EXPECT_EQ(d.front(), (Float3{0, 1, 0}));  // y goes from 1 to -1
  EXPECT_NEAR(d.back()[1], -1.0f, 0);
  for (const Float3& v : d) EXPECT_NEAR(norm(v), 1.0, 1e-6);
  // The rotation is applied only when its magnitude is not 0.
  EXPECT_EQ(fibonacci_directions(6, {30, 60, 0}), fibonacci_directions(6));
  EXPECT_NE(fibonacci_directions(6, {30, 60, 45}), fibonacci_directions(6));
  for (const Float3& v : fibonacci_directions(6, {30, 60, 45})) EXPECT_NEAR(norm(v), 1.0, 1e-6);
  EXPECT_THROW(fibonacci_directions(1), std::invalid_argument);
}

TEST(Raster, Cmdm18DirectionsAreTheCubesFacesAndEdges) {
  const std::vector<Float3> d = cmdm18_directions();
  ASSERT_EQ(d.size(), 18u);
  std::set<Float3> distinct(d.begin(), d.end());
  EXPECT_EQ(distinct.size(), 18u);
  int axes = 0;
  for (const Float3& v : d) {
    EXPECT_NEAR(norm(v), 1.0, 1e-7);
    axes += std::count(v.begin(), v.end(), 0.0f) == 2;
  }
  EXPECT_EQ(axes, 6);
}

TEST(Raster, FrameIsTheBoxSphereWithAMargin) {
  const RenderModel m = mesh_model(square({1, 0, 0}, {1, 0, 0}, {1, 0, 0}, {1, 0, 0}));
  const Frame f = frame_of(m, m);
  EXPECT_EQ(f.center, (Float3{0, 0, 0}));
  EXPECT_FLOAT_EQ(f.radius, std::sqrt(2.0f) * 1.01f);
  EXPECT_DOUBLE_EQ(box_ratio(m, m), 100.0);
}

TEST(Raster, AFrontFaceIsDrawnAndABackFaceCulledUnlessCullingIsOff) {
  const Rgb red{1, 0, 0};
  const RenderModel m = mesh_model(square(red, red, red, red));
  const Frame f = frame_of(m, m);
  RasterOptions o;
  o.resolution = 64;
  const View front = render_view(m, f, kFront, o);
  // The square spans 1 / 1.01 / sqrt(2) of the half width: about 70 % of the side.
  const double side = 64 / std::sqrt(2.0) / 1.01;
  EXPECT_NEAR(static_cast<double>(front.drawn_pixels()), side * side, 4 * side);
  EXPECT_EQ(pixel(front, 32, 32), (std::array<int, 4>{255, 0, 0, 255}));
  const View back = render_view(m, f, {0, 0, -1}, o);
  EXPECT_EQ(back.drawn_pixels(), 0u);
  o.culling = false;
  EXPECT_EQ(render_view(m, f, {0, 0, -1}, o).drawn_pixels(), front.drawn_pixels());
}

TEST(Raster, VertexColoursAreInterpolatedAndRounded) {
  const RenderModel m = mesh_model(square({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}));
  const Frame f = frame_of(m, m);
  RasterOptions o;
  o.resolution = 257;
  const View v = render_view(m, f, kFront, o);
  // Red grows with x, green with y (the image's x is the world's x seen from +z).
  const auto centre = pixel(v, 128, 128), right = pixel(v, 170, 128), top = pixel(v, 128, 170);
  EXPECT_NEAR(centre[0], 128, 2);
  EXPECT_NEAR(centre[1], 128, 2);
  EXPECT_GT(right[0], centre[0] + 30);
  EXPECT_GT(top[1], centre[1] + 30);
  EXPECT_EQ(centre[2], 0);
}

TEST(Raster, AMeshWithoutColoursIsDrawnRedAsMmetricDoes) {
  ColoredMesh m = square({0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1});
  const RenderModel model = mesh_model(m, false);
  RasterOptions o;
  o.resolution = 32;
  EXPECT_EQ(pixel(render_view(model, frame_of(model, model), kFront, o), 16, 16),
            (std::array<int, 4>{255, 0, 0, 255}));
}

TEST(Raster, CanonicalOrderMakesTheImageIndependentOfTheFilesOrder) {
  // A bumpy grid whose faces overlap in depth from oblique views.
  ColoredMesh m;
  const int n = 12;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = i / double(n), y = j / double(n);
      m.positions.push_back({x, y, 0.2 * std::sin(9 * x) * std::cos(7 * y)});
      m.colors.push_back({x, y, 1 - x * y});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  }
  // The same mesh with vertices permuted, faces shuffled and corners rotated.
  std::mt19937 rng(5);
  std::vector<std::uint32_t> perm(m.positions.size());
  for (std::uint32_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  ColoredMesh s;
  s.positions.resize(perm.size());
  s.colors.resize(perm.size());
  for (std::size_t i = 0; i < perm.size(); ++i) {
    s.positions[perm[i]] = m.positions[i];
    s.colors[perm[i]] = m.colors[i];
  }
  for (const Triangle& t : m.triangles) {
    const int r = static_cast<int>(rng() % 3);
    s.triangles.push_back({perm[t[r]], perm[t[(r + 1) % 3]], perm[t[(r + 2) % 3]]});
  }
  std::shuffle(s.triangles.begin(), s.triangles.end(), rng);
  const RenderModel a = mesh_model(m), b = mesh_model(s);
  const Frame f = frame_of(a, a);
  RasterOptions o;
  o.resolution = 128;
  o.culling = false;
  for (const Float3& d : fibonacci_directions(8)) {
    const View va = render_view(a, f, d, o), vb = render_view(b, f, d, o);
    EXPECT_EQ(va.rgba, vb.rgba);
    EXPECT_EQ(va.depth, vb.depth);
  }
}

TEST(Raster, HeadlightShadesByTheAngleToTheCamera) {
  const Rgb grey{200 / 255.0, 200 / 255.0, 200 / 255.0};
  const RenderModel m = mesh_model(square(grey, grey, grey, grey));
  const Frame f = frame_of(m, m);
  RasterOptions o;
  o.resolution = 64;
  o.lighting = Lighting::kHeadlight;
  EXPECT_EQ(pixel(render_view(m, f, kFront, o), 32, 32)[0], 200);  // n . v = 1
  // Seen at 60 degrees: 200 * (0.4 + 0.6 * 0.5) = 140.
  const float s = std::sqrt(3.0f) / 2;
  const View oblique = render_view(m, f, {s, 0, 0.5f}, o);
  EXPECT_EQ(pixel(oblique, 32, 32)[0], 140);
  o.lighting = Lighting::kUnlit;
  EXPECT_EQ(pixel(render_view(m, f, {s, 0, 0.5f}, o), 32, 32)[0], 200);
}

TEST(Raster, TexturedMeshTakesItsTexels) {
  mesh::TexturedMesh t;
  t.file.mesh = square({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0});
  t.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  t.triangle_uvs = {{0, 1, 2}, {0, 2, 3}};
  t.triangle_texture = {0, 0};
  mesh::TextureImage img;  // 2 x 2, row 0 the top row
  img.width = img.height = 2;
  img.texels = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  t.textures = {img};
  const RenderModel m = textured_mesh_model(t);
  EXPECT_TRUE(m.is_textured());
  RasterOptions o;
  o.resolution = 256;
  const View v = render_view(m, frame_of(m, m), kFront, o);
  // Quadrants away from the bilinear blend: top left red, top right green, bottom left blue,
  // bottom right white (v = 0 is the bottom row of the image).
  EXPECT_EQ(pixel(v, 60, 196), (std::array<int, 4>{255, 0, 0, 255}));
  EXPECT_EQ(pixel(v, 196, 196), (std::array<int, 4>{0, 255, 0, 255}));
  EXPECT_EQ(pixel(v, 60, 60), (std::array<int, 4>{0, 0, 255, 255}));
  EXPECT_EQ(pixel(v, 196, 60), (std::array<int, 4>{255, 255, 255, 255}));
}

/// Points on two parallel squares, sparse: z = 0 (red, side 2) and z = -0.5 (green, side 1.6:
/// seen from +z it lies inside the red one, so any green pixel shows through a gap).
ColoredCloud two_layers(std::size_t per_layer, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  ColoredCloud c;
  for (std::size_t i = 0; i < 2 * per_layer; ++i) {
    const bool front = i < per_layer;
    const double s = front ? 1.0 : 0.8;
    c.positions.push_back({s * u(rng), s * u(rng), front ? 0.0 : -0.5});
    c.colors.push_back(front ? Rgb{1, 0, 0} : Rgb{0, 1, 0});
  }
  return c;
}

TEST(Raster, ACloudIsDrawnAndItsBackDoesNotShowThrough) {
  const ColoredCloud c = two_layers(4000, 3);
  for (SplatShape shape : {SplatShape::kDisc, SplatShape::kSquare}) {
    SplatOptions s;
    s.shape = shape;
    const RenderModel m = cloud_model(c, s);
    EXPECT_GT(m.splat_size, 0);
    RasterOptions o;
    o.resolution = 256;
    const View v = render_view(m, frame_of(m, m), kFront, o);
    std::size_t red = 0, green = 0;
    for (std::size_t i = 0; i < v.depth.size(); ++i) {
      if (!v.rgba[i * 4 + 3]) continue;
      red += v.rgba[i * 4] == 255;
      green += v.rgba[i * 4 + 1] == 255;
    }
    EXPECT_GT(red, 20000u);  // most of the square's ~33k pixels
    EXPECT_EQ(green, 0u);    // the back layer is hidden, also in the front layer's gaps
  }
}

TEST(Raster, ACloudsImageDoesNotDependOnItsPointOrder) {
  ColoredCloud c = two_layers(3000, 4);
  ColoredCloud s = c;
  std::vector<std::size_t> perm(c.positions.size());
  for (std::size_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), std::mt19937(9));
  for (std::size_t i = 0; i < perm.size(); ++i) {
    s.positions[i] = c.positions[perm[i]];
    s.colors[i] = c.colors[perm[i]];
  }
  const RenderModel a = cloud_model(c), b = cloud_model(s);
  RasterOptions o;
  o.resolution = 128;
  const Frame f = frame_of(a, a);
  for (const Float3& d : fibonacci_directions(4)) {
    EXPECT_EQ(render_view(a, f, d, o).rgba, render_view(b, f, d, o).rgba);
  }
}

TEST(Raster, BadCloudsAreRefused) {
  EXPECT_THROW(cloud_model(ColoredCloud{}), FormatError);
  ColoredCloud same;
  same.positions = {{1, 2, 3}, {1, 2, 3}};
  same.colors = {{0, 0, 0}, {0, 0, 0}};
  EXPECT_THROW(cloud_model(same), FormatError);  // no spacing, so no splat size
  SplatOptions given;
  given.size = 0.1;
  EXPECT_EQ(cloud_model(same, given).positions.size(), 1u);
  EXPECT_THROW(mesh_model(ColoredMesh{}), FormatError);
}

TEST(Raster, SameImagesOnOneAndTwoThreads) {
  const RenderModel mesh = mesh_model(square({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}));
  const RenderModel cloud = cloud_model(two_layers(2000, 8));
  RasterOptions o;
  o.resolution = 96;
  o.culling = false;
  for (const RenderModel* m : {&mesh, &cloud}) {
    const Frame f = frame_of(*m, *m);
    const std::vector<Float3> dirs = fibonacci_directions(6, {30, 60, 45});
    const std::vector<View> one = render_views(*m, f, dirs, o, 1);
    const std::vector<View> two = render_views(*m, f, dirs, o, 2);
    ASSERT_EQ(one.size(), two.size());
    for (std::size_t i = 0; i < one.size(); ++i) {
      EXPECT_EQ(one[i].rgba, two[i].rgba);
      EXPECT_EQ(one[i].depth, two[i].depth);
    }
  }
}

}  // namespace
}  // namespace qm3d::render
