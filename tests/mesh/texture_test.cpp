#include "qm3d/mesh/texture.h"

#include <gtest/gtest.h>
#include <stb/stb_image_write.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "qm3d/common/error.h"
#include "qm3d/mesh/cmdm.h"
#include "qm3d/mesh/sampling.h"

namespace qm3d::mesh {
namespace {

namespace fs = std::filesystem;

constexpr int kSide = 8;  // texels per side of the checkerboard, and vertices per side of the grid
using Texel = std::array<unsigned char, 3>;
constexpr Texel kDark{30, 60, 200};
constexpr Texel kLight{240, 200, 20};

Texel checker(int i, int j) { return (i + j) % 2 ? kDark : kLight; }

double float_precision(double x) { return static_cast<float>(x); }

class Texture : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_texture_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }

  void write_png(const std::string& name, int w, int h, const std::vector<Texel>& texels) {
    ASSERT_NE(stbi_write_png((dir_ / name).c_str(), w, h, 3, texels.data(), w * 3), 0);
  }

  void write_checker_png() {
    std::vector<Texel> texels;
    for (int j = 0; j < kSide; ++j) {
      for (int i = 0; i < kSide; ++i) texels.push_back(checker(i, j));
    }
    write_png("checker.png", kSide, kSide, texels);
  }

  static Vec3 grid_position(int i, int j) {
    return {double(i), double(j), 0.3 * std::sin(i) * std::cos(0.7 * j)};
  }

  // The kSide x kSide grid; vertex (i, j) carries texel (i, j) either as a UV or as a colour.
  static std::string grid_obj(bool textured) {
    std::ostringstream o;
    if (textured) o << "mtllib checker.mtl\nusemtl board\n";
    for (int j = 0; j < kSide; ++j) {
      for (int i = 0; i < kSide; ++i) {
        const Vec3 p = grid_position(i, j);
        o << "v " << p[0] << " " << p[1] << " " << p[2];
        const Texel t = checker(i, j);
        if (!textured) o << " " << int(t[0]) << " " << int(t[1]) << " " << int(t[2]);
        o << "\n";
        if (textured) o << "vt " << (i + 0.5) / kSide << " " << 1 - (j + 0.5) / kSide << "\n";
      }
    }
    for (int j = 0; j + 1 < kSide; ++j) {
      for (int i = 0; i + 1 < kSide; ++i) {
        const int a = j * kSide + i + 1, b = a + 1, c = a + kSide, d = c + 1;
        o << "f " << a << "/" << a << " " << b << "/" << b << " " << d << "/" << d << "\n";
        o << "f " << a << "/" << a << " " << d << "/" << d << " " << c << "/" << c << "\n";
      }
    }
    return o.str();
  }

  void write_checker_scene() {
    write_checker_png();
    write("checker.mtl", "newmtl board\nKd 1 1 1\nmap_Kd checker.png\n");
    write("grid.obj", grid_obj(true));
    write("grid_colored.obj", grid_obj(false));
  }

  fs::path dir_;
};

TEST_F(Texture, CheckerboardGivesTheTexelColourAtEveryVertex) {
  write_checker_scene();
  const TexturedMesh m = read_textured_obj(dir_ / "grid.obj");
  ASSERT_EQ(m.file.mesh.num_vertices(), std::size_t(kSide * kSide));
  for (int j = 0; j < kSide; ++j) {
    for (int i = 0; i < kSide; ++i) {
      const Rgb& c = m.file.mesh.colors[j * kSide + i];
      const Texel t = checker(i, j);
      EXPECT_EQ(c.r, float_precision(t[0] / 255.0)) << i << "," << j;
      EXPECT_EQ(c.g, float_precision(t[1] / 255.0));
      EXPECT_EQ(c.b, float_precision(t[2] / 255.0));
    }
  }
}

TEST_F(Texture, ReadMeshGivesTheSameCmdmAsTheVertexColouredMesh) {
  write_checker_scene();
  const ColoredMesh textured = read_mesh(dir_ / "grid.obj").mesh;
  const ColoredMesh colored = read_mesh(dir_ / "grid_colored.obj").mesh;
  ColoredMesh distorted = colored;
  for (std::size_t v = 0; v < distorted.colors.size(); v += 3) distorted.colors[v].g *= 0.5;
  const double a = compute_cmdm(textured, distorted).score;
  const double b = compute_cmdm(colored, distorted).score;
  EXPECT_GT(b, 0);
  EXPECT_EQ(a, b);
}

TEST_F(Texture, SeamVertexGetsTheMeanOfItsUvs) {
  write_png("two.png", 2, 1, {{0, 0, 0}, {255, 255, 255}});
  write("two.mtl", "newmtl m\nmap_Kd two.png\n");
  // Vertex 1 is used with UV 1 (black texel) by one face and UV 3 (white texel) by the other.
  write("seam.obj",
        "mtllib two.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
        "vt 0.25 0.5\nvt 0.75 0.5\nvt 0.25 0.5\n"
        "f 1/1 2/1 3/1\nf 2/2 4/2 3/3\n");
  const TexturedMesh m = read_textured_obj(dir_ / "seam.obj");
  EXPECT_EQ(m.file.mesh.colors[0].r, 0.0);
  EXPECT_EQ(m.file.mesh.colors[1].r, 0.5);  // black and white
  EXPECT_EQ(m.file.mesh.colors[3].r, 1.0);
  EXPECT_EQ(m.file.mesh.colors[2].r, 0.0);  // two UVs (1 and 3), both on the black texel
}

TEST(TextureLookup, IsBilinearBetweenTexelCentresAndWraps) {
  const TextureImage image{2, 1, {{0, 0, 0}, {1, 1, 1}}};
  EXPECT_EQ(sample_texture(image, {0.25, 0.5}).r, 0.0);
  EXPECT_EQ(sample_texture(image, {0.75, 0.5}).r, 1.0);
  EXPECT_DOUBLE_EQ(sample_texture(image, {0.5, 0.5}).r, 0.5);
  EXPECT_DOUBLE_EQ(sample_texture(image, {0.625, 0.1}).r, 0.75);
  EXPECT_DOUBLE_EQ(sample_texture(image, {1.0, 0.5}).r, 0.5);  // wraps to texel 0
  EXPECT_DOUBLE_EQ(sample_texture(image, {1.25, 3.5}).r, 0.0);
}

TEST_F(Texture, SamplesTakeTheTextureColourAtTheirOwnUv) {
  write_checker_png();
  write("checker.mtl", "newmtl board\nmap_Kd checker.png\n");
  // One quad covering the whole texture: uv = (x, y) / 2.
  write("quad.obj",
        "mtllib checker.mtl\nusemtl board\nv 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n");
  const TexturedMesh m = read_textured_obj(dir_ / "quad.obj");
  const ColoredCloud cloud = sample_surface(m, {2000, 0, 5});
  ASSERT_EQ(cloud.size(), 2000u);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Rgb expected =
        sample_texture(m.textures[0], {cloud.positions[i][0] / 2, cloud.positions[i][1] / 2});
    ASSERT_NEAR(cloud.colors[i].r, expected.r, 1e-9) << i;
    ASSERT_NEAR(cloud.colors[i].b, expected.b, 1e-9) << i;
  }
  // The same points as the untextured sampling of the same geometry.
  const ColoredCloud plain = sample_surface(m.file.mesh, {2000, 0, 5});
  EXPECT_EQ(plain.positions, cloud.positions);
}

TEST_F(Texture, ErrorsNameTheFileAtFault) {
  const auto message = [&](const fs::path& obj) -> std::string {
    try {
      read_mesh(obj);
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n";
  write("no_mtl.obj", "mtllib absent.mtl\nusemtl m\n" + tri + "f 1/1 2/1 3/1\n");
  EXPECT_NE(message(dir_ / "no_mtl.obj").find("absent.mtl"), std::string::npos);
  write("missing.mtl", "newmtl m\nmap_Kd absent.png\n");
  write("missing_tex.obj", "mtllib missing.mtl\nusemtl m\n" + tri + "f 1/1 2/1 3/1\n");
  EXPECT_NE(message(dir_ / "missing_tex.obj").find("absent.png"), std::string::npos);
  write("bad.png", "this is not an image");
  write("bad.mtl", "newmtl m\nmap_Kd bad.png\n");
  write("bad_tex.obj", "mtllib bad.mtl\nusemtl m\n" + tri + "f 1/1 2/1 3/1\n");
  EXPECT_NE(message(dir_ / "bad_tex.obj").find("bad.png: cannot decode"), std::string::npos);
  write("no_uv.obj", "mtllib bad.mtl\nusemtl m\n" + tri + "f 1 2 3\n");
  EXPECT_NE(message(dir_ / "no_uv.obj").find("no_uv.obj: line 7: face corner '1' has no texture"),
            std::string::npos)
      << message(dir_ / "no_uv.obj");
  // read_mesh needs colours: a texture that is not there is an error there (a warning when the
  // registry reads the mesh, texture_sources_test.cpp).
  EXPECT_THROW(read_mesh(dir_ / "missing_tex.obj"), FormatError);
  EXPECT_THROW(read_mesh(dir_ / "bad_tex.obj"), FormatError);
}

TEST_F(Texture, MaterialWithoutMapUsesKdAndVertexColoursWin) {
  write("kd.mtl", "newmtl m\nKd 0.25 0.5 1\n");
  write("kd.obj", "mtllib kd.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n");
  const ColoredMesh m = read_mesh(dir_ / "kd.obj").mesh;
  EXPECT_EQ(m.colors[2].g, 0.5);
  // An OBJ with vertex colours keeps them even when it names an MTL.
  write("vc.obj", "mtllib kd.mtl\nv 0 0 0 1 0 0\nv 1 0 0 1 0 0\nv 0 1 0 1 0 0\nf 1 2 3\n");
  EXPECT_FALSE(obj_is_textured("mtllib kd.mtl\nv 0 0 0 1 0 0\n"));
  EXPECT_EQ(read_mesh(dir_ / "vc.obj").mesh.colors[0].r, 1.0);
}

}  // namespace
}  // namespace qm3d::mesh
