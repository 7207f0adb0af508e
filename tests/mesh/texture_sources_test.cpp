// Where a textured mesh's colours come from (issue 39): texture maps in BMP, TGA and JPEG as
// well as PNG; PLY meshes with texture coordinates and `comment TextureFile`; a map given on the
// command line (ReadOptions::texture, --ref-texture / --dist-texture) replacing the materials';
// a mesh with texture coordinates but no usable texture read untextured with one warning.
#include <gtest/gtest.h>
#include <stb/stb_image_write.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/mesh/metrics.h"
#include "qm3d/mesh/texture.h"

namespace qm3d::mesh {
namespace {

namespace fs = std::filesystem;

constexpr int kSide = 6;  // texels per side, and grid vertices per side
using Texel = std::array<unsigned char, 3>;

Texel texel_at(int i, int j) {
  return {static_cast<unsigned char>(40 * i + 7), static_cast<unsigned char>(200 - 30 * j),
          static_cast<unsigned char>((i * j * 37) % 256)};
}

std::vector<Texel> image() {
  std::vector<Texel> t;
  for (int j = 0; j < kSide; ++j) {
    for (int i = 0; i < kSide; ++i) t.push_back(texel_at(i, j));
  }
  return t;
}

// UV of grid vertex (i, j): off the texel centres, so that bilinear lookups mix four texels.
std::array<double, 2> uv_of(int i, int j) { return {(i + 0.3) / kSide, 1 - (j + 0.65) / kSide}; }

class TextureSources : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_texsrc_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const auto t = image();
    const std::string png = (dir_ / "map.png").string(), bmp = (dir_ / "map.bmp").string(),
                      tga = (dir_ / "map.tga").string(), jpg = (dir_ / "map.jpg").string();
    ASSERT_NE(stbi_write_png(png.c_str(), kSide, kSide, 3, t.data(), kSide * 3), 0);
    ASSERT_NE(stbi_write_bmp(bmp.c_str(), kSide, kSide, 3, t.data()), 0);
    ASSERT_NE(stbi_write_tga(tga.c_str(), kSide, kSide, 3, t.data()), 0);
    ASSERT_NE(stbi_write_jpg(jpg.c_str(), kSide, kSide, 3, t.data(), 100), 0);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return dir_ / name;
  }

  // The grid with per-vertex UVs: OBJ text (with `mtllib` / `usemtl` lines as given).
  static std::string grid_obj(const std::string& material_lines) {
    std::ostringstream o;
    o.precision(17);
    o << material_lines;
    for (int j = 0; j < kSide; ++j) {
      for (int i = 0; i < kSide; ++i) {
        o << "v " << i << " " << j << " " << 0.2 * std::sin(i + j) << "\n";
        o << "vt " << uv_of(i, j)[0] << " " << uv_of(i, j)[1] << "\n";
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

  // The same grid as an ASCII PLY: per-vertex UVs named `u_name` / `v_name`, or per-corner
  // `texcoord` lists; `comment` lines in the header.
  static std::string grid_ply(const std::string& comments, const std::string& u_name,
                              const std::string& v_name, bool per_corner) {
    std::ostringstream o;
    o.precision(17);
    const int faces = 2 * (kSide - 1) * (kSide - 1);
    o << "ply\nformat ascii 1.0\n"
      << comments << "element vertex " << kSide * kSide
      << "\nproperty double x\nproperty double y\nproperty double z\n";
    if (!per_corner) o << "property double " << u_name << "\nproperty double " << v_name << "\n";
    o << "element face " << faces << "\nproperty list uchar int vertex_indices\n";
    if (per_corner) o << "property list uchar float texcoord\n";
    o << "end_header\n";
    for (int j = 0; j < kSide; ++j) {
      for (int i = 0; i < kSide; ++i) {
        o << i << " " << j << " " << 0.2 * std::sin(i + j);
        if (!per_corner) o << " " << uv_of(i, j)[0] << " " << uv_of(i, j)[1];
        o << "\n";
      }
    }
    const auto corner_uvs = [&](std::initializer_list<int> vs) {
      std::string s = "6";
      for (int v : vs) {
        s += " " + std::to_string(static_cast<float>(uv_of(v % kSide, v / kSide)[0])) + " " +
             std::to_string(static_cast<float>(uv_of(v % kSide, v / kSide)[1]));
      }
      return s;
    };
    for (int j = 0; j + 1 < kSide; ++j) {
      for (int i = 0; i + 1 < kSide; ++i) {
        const int a = j * kSide + i, b = a + 1, c = a + kSide, d = c + 1;
        o << "3 " << a << " " << b << " " << d;
        if (per_corner) o << " " << corner_uvs({a, b, d});
        o << "\n3 " << a << " " << d << " " << c;
        if (per_corner) o << " " << corner_uvs({a, d, c});
        o << "\n";
      }
    }
    return o.str();
  }

  TexturedMesh textured(const fs::path& path, const ReadOptions& options = {},
                        std::vector<std::string>* warnings = nullptr) {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    const MeshFormat f = path.extension() == ".ply" ? MeshFormat::kPly : MeshFormat::kObj;
    auto m = read_textured_mesh(bytes, f, path, options, warnings);
    if (!m) {
      ADD_FAILURE() << path << " not read as a textured mesh";
      return {};
    }
    return std::move(*m);
  }

  // The reference: the OBJ with its MTL naming map.png.
  std::vector<Rgb> obj_png_colours() {
    write("png.mtl", "newmtl m\nmap_Kd map.png\n");
    return textured(write("png.obj", grid_obj("mtllib png.mtl\nusemtl m\n"))).file.mesh.colors;
  }

  fs::path dir_;
};

void expect_same_colours(const std::vector<Rgb>& a, const std::vector<Rgb>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t v = 0; v < a.size(); ++v) {
    ASSERT_EQ(a[v].r, b[v].r) << v;
    ASSERT_EQ(a[v].g, b[v].g) << v;
    ASSERT_EQ(a[v].b, b[v].b) << v;
  }
}

TEST_F(TextureSources, BmpAndTgaMapsGiveThePngMapsColours) {
  const auto png = obj_png_colours();
  for (const std::string ext : {"bmp", "tga"}) {
    write(ext + ".mtl", "newmtl m\nmap_Kd map." + ext + "\n");
    const auto m = textured(write(ext + ".obj", grid_obj("mtllib " + ext + ".mtl\nusemtl m\n")));
    SCOPED_TRACE(ext);
    expect_same_colours(m.file.mesh.colors, png);
  }
}

TEST_F(TextureSources, JpegMapIsReadWithinItsCompressionError) {
  const TextureImage jpg = read_texture(dir_ / "map.jpg"), png = read_texture(dir_ / "map.png");
  ASSERT_EQ(jpg.width, png.width);
  ASSERT_EQ(jpg.height, png.height);
  for (std::size_t i = 0; i < png.texels.size(); ++i) {
    EXPECT_NEAR(jpg.texels[i].r, png.texels[i].r, 24 / 255.0) << i;
  }
}

TEST_F(TextureSources, ImagesOverTheTexelLimitAreRefusedBeforeDecodingInEveryFormat) {
  // A 54-byte BMP header claiming 20000 x 20000 texels (no pixel data).
  std::string bmp(54, '\0');
  const auto put32 = [&bmp](std::size_t at, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) bmp[at + k] = static_cast<char>((v >> (8 * k)) & 0xff);
  };
  bmp[0] = 'B';
  bmp[1] = 'M';
  put32(10, 54);
  put32(14, 40);
  put32(18, 20000);
  put32(22, 20000);
  bmp[26] = 1;
  bmp[28] = 24;
  const fs::path big = write("big.bmp", bmp);
  try {
    read_texture(big);
    ADD_FAILURE() << "no error";
  } catch (const FormatError& e) {
    EXPECT_EQ(std::string(e.what()), big.string() +
                                         ": texture image of 20000 x 20000 texels, more than the "
                                         "16384 x 16384 qm3d reads");
  }
  const fs::path bad = write("bad.tga", "not a targa");
  try {
    read_texture(bad);
    ADD_FAILURE() << "no error";
  } catch (const FormatError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(bad.string() + ": cannot decode the texture image", 0),
              0u)
        << e.what();
  }
}

TEST_F(TextureSources, PlyWithTextureFileGivesTheObjColours) {
  const auto obj = obj_png_colours();
  const std::string comment = "comment TextureFile map.png\n";
  for (const auto& [u, v] :
       {std::pair<std::string, std::string>{"texture_u", "texture_v"}, {"s", "t"}, {"u", "v"}}) {
    SCOPED_TRACE(u);
    expect_same_colours(
        textured(write(u + ".ply", grid_ply(comment, u, v, false))).file.mesh.colors, obj);
  }
  // Per-corner texcoord lists are float32 in the file: the same texels at those UVs.
  const TexturedMesh corners = textured(write("corners.ply", grid_ply(comment, "", "", true)));
  ASSERT_EQ(corners.triangle_uvs.size(), corners.file.mesh.triangles.size());
  const auto& c = corners.file.mesh.colors;
  ASSERT_EQ(c.size(), obj.size());
  for (std::size_t v = 0; v < c.size(); ++v) EXPECT_NEAR(c[v].g, obj[v].g, 1e-5) << v;
}

TEST_F(TextureSources, PlyTexnumberPicksOneOfSeveralTextureFiles) {
  // Two maps; every face names the second (a flat image) by texnumber.
  const std::vector<Texel> flat(kSide * kSide, Texel{10, 20, 30});
  ASSERT_NE(stbi_write_png((dir_ / "flat.png").c_str(), kSide, kSide, 3, flat.data(), kSide * 3),
            0);
  std::string ply = grid_ply("comment TextureFile map.png\ncomment TextureFile flat.png\n",
                             "texture_u", "texture_v", false);
  ply.replace(ply.find("property list uchar int vertex_indices\n"),
              std::string("property list uchar int vertex_indices\n").size(),
              "property list uchar int vertex_indices\nproperty int texnumber\n");
  std::string out;
  std::istringstream lines(ply);
  int record = -1;  // data records after end_header: the vertices, then the faces
  for (std::string line; std::getline(lines, line);) {
    if (record >= kSide * kSide) line += " 1";
    if (record >= 0 || line == "end_header") ++record;
    out += line + "\n";
  }
  const TexturedMesh m = textured(write("two.ply", out));
  ASSERT_EQ(m.textures.size(), 2u);
  for (const Rgb& c : m.file.mesh.colors) EXPECT_EQ(c.g, double(float(20 / 255.0)));
}

TEST_F(TextureSources, GivenMapReplacesEveryMaterialsMap) {
  const auto png = obj_png_colours();
  ReadOptions given;
  given.texture = dir_ / "map.png";
  // No mtllib at all (mmetric's plane_qp8.obj).
  expect_same_colours(textured(write("bare.obj", grid_obj("")), given).file.mesh.colors, png);
  // A material defined nowhere (mmetric's basketball_player_00000001_qp8_hole.obj).
  expect_same_colours(
      textured(write("undef.obj", grid_obj("usemtl Default_OBJ\n")), given).file.mesh.colors, png);
  // Several materials with other maps: every face takes the given one.
  const std::vector<Texel> flat(kSide * kSide, Texel{10, 20, 30});
  ASSERT_NE(stbi_write_png((dir_ / "flat.png").c_str(), kSide, kSide, 3, flat.data(), kSide * 3),
            0);
  write("two.mtl", "newmtl a\nmap_Kd flat.png\nnewmtl b\nKd 1 0 0\n");
  std::string two = grid_obj("mtllib two.mtl\nusemtl a\n");
  two.insert(two.find("f ", two.find("f ") + 1), "usemtl b\n");
  expect_same_colours(textured(write("two.obj", two), given).file.mesh.colors, png);
  // A PLY without TextureFile.
  expect_same_colours(
      textured(write("bare.ply", grid_ply("", "texture_u", "texture_v", false)), given)
          .file.mesh.colors,
      png);
  // A given map that is not there: an error naming it.
  given.texture = dir_ / "absent.png";
  EXPECT_THROW(textured(dir_ / "bare.obj", given), InputError);
}

TEST_F(TextureSources, TextureCoordinatesWithoutUsableTextureAreOneWarningNamingFileAndOption) {
  write("nomap.mtl", "newmtl m\nmap_Kd absent.png\n");
  const std::vector<std::pair<fs::path, std::string>> cases = {
      {write("bare.obj", grid_obj("")), "no mtllib: the OBJ names no material file"},
      {write("undef.obj", grid_obj("mtllib nomap.mtl\nusemtl Default_OBJ\n")),
       "material 'Default_OBJ' is in no mtllib"},
      {write("nomtl.obj", grid_obj("mtllib absent.mtl\nusemtl m\n")),
       "its material file " + (dir_ / "absent.mtl").string() + " is not there"},
      {write("nomap.obj", grid_obj("mtllib nomap.mtl\nusemtl m\n")),
       "the texture map " + (dir_ / "absent.png").string() + " of material 'm' is not there"},
      {write("bare.ply", grid_ply("", "texture_u", "texture_v", false)),
       "it has texture coordinates but no `comment TextureFile` line"},
      {write("nomap.ply", grid_ply("comment TextureFile absent.png\n", "s", "t", false)),
       "its texture map " + (dir_ / "absent.png").string() + " (comment TextureFile) is not there"},
  };
  Registry registry;
  register_metrics(registry);
  for (const auto& [path, why] : cases) {
    SCOPED_TRACE(path.string());
    ReadOptions o;
    o.texture_option = "--dist-texture";
    const Input in = registry.read(path, o);
    const MeshData& m = in.mesh();  // not an error: read without the texture
    EXPECT_FALSE(m.has_colors);
    std::vector<std::string> texture_lines;
    for (const auto& w : m.warnings) {
      if (w.find("texture") != std::string::npos) texture_lines.push_back(w);
    }
    ASSERT_EQ(texture_lines.size(), 1u);
    EXPECT_EQ(texture_lines[0], path.string() + ": " + why +
                                    "; read without its texture (give its map with "
                                    "--dist-texture)");
  }
}

TEST_F(TextureSources, TheRegistryReadsTheGivenMap) {
  Registry registry;
  register_metrics(registry);
  ReadOptions o;
  o.texture = dir_ / "map.bmp";
  const Input in = registry.read(write("bare.obj", grid_obj("")), o);
  ASSERT_TRUE(in.mesh().has_colors);
  expect_same_colours(in.mesh().mesh.colors, obj_png_colours());
  EXPECT_EQ(in.read_options().texture, dir_ / "map.bmp");
}

}  // namespace
}  // namespace qm3d::mesh
