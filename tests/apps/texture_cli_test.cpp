// Issue 39 end to end through the tool's JSON: --ref-texture / --dist-texture (ibsm, mesh psnr,
// sample, texture-to-vertex, batch list columns), PLY meshes with `comment TextureFile`, BMP maps,
// the warning for texture coordinates without a usable texture, PCD clouds with NaN points,
// psnr --conventions mmetric on clouds, and bad textures refused with one line naming the file.
#include <gtest/gtest.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_runner.h"
#include "mpeg_reference.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

constexpr int kSide = 12;   // grid vertices per side
constexpr int kTexels = 8;  // texels per side of the map

class TextureCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_texture_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
    std::vector<unsigned char> t;
    for (int j = 0; j < kTexels; ++j) {
      for (int i = 0; i < kTexels; ++i) {
        t.insert(t.end(),
                 {static_cast<unsigned char>(30 * i), static_cast<unsigned char>(250 - 25 * j),
                  static_cast<unsigned char>((i + j) % 2 ? 40 : 220)});
      }
    }
    ASSERT_NE(stbi_write_png(path("map.png").c_str(), kTexels, kTexels, 3, t.data(), kTexels * 3),
              0);
    ASSERT_NE(stbi_write_bmp(path("map.bmp").c_str(), kTexels, kTexels, 3, t.data()), 0);
    write("map.mtl", "newmtl m\nmap_Kd map.png\n");
    write("bmp.mtl", "newmtl m\nmap_Kd map.bmp\n");
    write("ref.obj", grid_obj("mtllib map.mtl\nusemtl m\n", 0));
    write("dist.obj", grid_obj("mtllib bmp.mtl\nusemtl m\n", 0.05));
    write("bare.obj", grid_obj("", 0.05));  // no mtllib (mmetric's plane_qp8.obj)
    write("dist.ply", grid_ply("comment TextureFile map.png\n", 0.05));
  }
  void TearDown() override { fs::remove_all(dir_); }

  test::CliRun qm3d(const std::string& args) { return test::run_qm3d(args, dir_, dir_ / "io", ""); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }

  static double z(int i, int j, double noise) {
    return 0.8 * std::sin(0.6 * i) * std::cos(0.5 * j) + noise * std::sin(7.0 * i + 3.0 * j);
  }
  static double u(int i) { return (i + 0.25) / (kSide - 0.5); }
  static double v(int j) { return 1 - (j + 0.4) / (kSide - 0.2); }

  static std::string faces(bool with_uvs, int base) {
    std::ostringstream o;
    const auto corner = [&](int k) {
      return std::to_string(k + base) + (with_uvs ? "/" + std::to_string(k + base) : "");
    };
    for (int j = 0; j + 1 < kSide; ++j) {
      for (int i = 0; i + 1 < kSide; ++i) {
        const int a = j * kSide + i, b = a + 1, c = a + kSide, d = c + 1;
        o << "f " << corner(a) << " " << corner(b) << " " << corner(d) << "\n";
        o << "f " << corner(a) << " " << corner(d) << " " << corner(c) << "\n";
      }
    }
    return o.str();
  }

  static std::string grid_obj(const std::string& head, double noise) {
    std::ostringstream o;
    o.precision(17);
    o << head;
    for (int j = 0; j < kSide; ++j) {
      for (int i = 0; i < kSide; ++i) {
        o << "v " << i << " " << j << " " << z(i, j, noise) << "\nvt " << u(i) << " " << v(j)
          << "\n";
      }
    }
    return o.str() + faces(true, 1);
  }

  static std::string grid_ply(const std::string& comments, double noise) {
    std::ostringstream o;
    o.precision(17);
    o << "ply\nformat ascii 1.0\n"
      << comments << "element vertex " << kSide * kSide
      << "\nproperty double x\nproperty double y\nproperty double z\nproperty double texture_u\n"
         "property double texture_v\nelement face "
      << 2 * (kSide - 1) * (kSide - 1) << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int j = 0; j < kSide; ++j) {
      for (int i = 0; i < kSide; ++i) {
        o << i << " " << j << " " << z(i, j, noise) << " " << u(i) << " " << v(j) << "\n";
      }
    }
    std::string f = faces(false, 0);
    std::string out;
    std::istringstream lines(f);
    for (std::string line; std::getline(lines, line);) out += "3" + line.substr(1) + "\n";
    return o.str() + out;
  }

  nlohmann::json json_of(const std::string& args) {
    const test::CliRun r = qm3d(args + " --json");
    EXPECT_EQ(r.code, 0) << args << "\n" << r.err;
    return r.code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
  }

  fs::path dir_;
};

const std::string kIbsm = "ibsm --resolution 256 --views 4 --no-ssim";

TEST_F(TextureCli, DistTextureGivesAMeshWithoutMtllibItsMap) {
  const nlohmann::json textured = json_of(kIbsm + " ref.obj dist.obj");
  const nlohmann::json given = json_of(kIbsm + " ref.obj bare.obj --dist-texture map.png");
  EXPECT_EQ(given["features"], textured["features"]);
  EXPECT_GT(textured["features"]["rgb_psnr"].get<double>(), 20.0);
  // Without the map: a warning naming the mesh and the option, not an error.
  const test::CliRun r = qm3d(kIbsm + " ref.obj bare.obj --json");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("bare.obj: no mtllib: the OBJ names no material file; read without its "
                       "texture (give its map with --dist-texture)"),
            std::string::npos)
      << r.err;
}

TEST_F(TextureCli, PlyWithTextureFileAndBmpMapScoreAsTheObjWithPng) {
  write("png.obj", grid_obj("mtllib map.mtl\nusemtl m\n", 0.05));
  const std::string psnr = "psnr --grid-size 64 --bilinear";
  const nlohmann::json obj = json_of(psnr + " ref.obj png.obj");
  EXPECT_EQ(json_of(psnr + " ref.obj dist.obj")["features"], obj["features"]);  // BMP map
  EXPECT_EQ(json_of(psnr + " ref.obj dist.ply")["features"], obj["features"]);  // TextureFile
  EXPECT_EQ(json_of(kIbsm + " ref.obj dist.ply")["features"],
            json_of(kIbsm + " ref.obj png.obj")["features"]);
  // The reference's map replaced: scored against itself with another map.
  const nlohmann::json other = json_of(psnr + " ref.obj png.obj --ref-texture map.bmp");
  EXPECT_EQ(other["features"], obj["features"]);
}

TEST_F(TextureCli, SampleAndTextureToVertexTakeTexture) {
  ASSERT_EQ(qm3d("texture-to-vertex dist.obj -o a.ply").code, 0);
  const test::CliRun r = qm3d("texture-to-vertex bare.obj --texture map.png -o b.ply");
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream a(path("a.ply"), std::ios::binary), b(path("b.ply"), std::ios::binary);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}),
            std::string(std::istreambuf_iterator<char>(b), {}));
  ASSERT_EQ(qm3d("sample dist.ply --mode grid --grid-size 32 -o g1.ply").code, 0);
  ASSERT_EQ(qm3d("sample bare.obj --texture map.bmp --mode grid --grid-size 32 -o g2.ply").code, 0);
  std::ifstream g1(path("g1.ply"), std::ios::binary), g2(path("g2.ply"), std::ios::binary);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(g1), {}),
            std::string(std::istreambuf_iterator<char>(g2), {}));
  const test::CliRun none = qm3d("texture-to-vertex bare.obj -o c.ply");
  EXPECT_NE(none.code, 0);
  EXPECT_NE(none.err.find("bare.obj: no mtllib"), std::string::npos) << none.err;
}

TEST_F(TextureCli, BatchListColumnsGiveTheMaps) {
  write("list.csv", "reference,distorted,metric,dist_texture\nref.obj,bare.obj,psnr,map.png\n");
  const test::CliRun r = qm3d("batch list.csv -o out.csv --grid-size 64 --bilinear");
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(path("out.csv"));
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  const nlohmann::json direct = json_of("psnr --grid-size 64 --bilinear ref.obj dist.obj");
  const auto split = [](const std::string& line) {
    std::vector<std::string> f;
    std::stringstream in(line);
    for (std::string item; std::getline(in, item, ',');) f.push_back(item);
    return f;
  };
  const auto names = split(header), values = split(row);
  int checked = 0;
  for (const char* name : {"d1_psnr", "d2_psnr", "c0_mse", "c1_mse", "c2_mse"}) {
    const auto at = std::find(names.begin(), names.end(), name);
    ASSERT_NE(at, names.end()) << name;
    const std::string& field = values.at(static_cast<std::size_t>(at - names.begin()));
    ASSERT_FALSE(field.empty()) << name << " (the map was not used)";
    EXPECT_EQ(std::stod(field), direct["features"][name].get<double>()) << name;
    ++checked;
  }
  EXPECT_EQ(checked, 5);
}

TEST_F(TextureCli, BadTexturesAreOneLineNamingTheFile) {
  write("bad.png", "not an image");
  for (const std::string& args : {kIbsm + " ref.obj bare.obj --dist-texture bad.png",
                                  kIbsm + " ref.obj bare.obj --dist-texture absent.png"}) {
    const test::CliRun r = qm3d(args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(args.find("bad") != std::string::npos ? "bad.png" : "absent.png"),
              std::string::npos)
        << r.err;
  }
}

// An organised PCD with NaN points scores as the same cloud without them, in every cloud metric
// that compare runs, with one warning giving the count.
TEST_F(TextureCli, PcdNanPointsAreDroppedForEveryMetric) {
  std::ostringstream nan_pcd, clean_pcd, other_pcd;
  const int width = 40, height = 25;
  const auto header = [&](std::ostringstream& o, int w, int h, const char* dense) {
    o << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
      << "WIDTH " << w << "\nHEIGHT " << h << "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << w * h
      << "\nDATA ascii\n";
    (void)dense;
  };
  std::ostringstream nan_body, clean_body, other_body;
  int valid = 0;
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      const float x = 0.1f * i, y = 0.1f * j, zz = 0.3f * std::sin(0.3f * i + 0.2f * j);
      const unsigned rgb =
          (static_cast<unsigned>(6 * i) << 16) | (static_cast<unsigned>(9 * j) << 8) | 77u;
      if ((i * 7 + j * 3) % 11 == 0) {
        nan_body << "nan nan nan " << rgb << "\n";
      } else {
        nan_body << x << " " << y << " " << zz << " " << rgb << "\n";
        clean_body << x << " " << y << " " << zz << " " << rgb << "\n";
        ++valid;
      }
      other_body << x << " " << y << " " << zz + 0.01f * std::cos(5.0f * i) << " "
                 << (rgb ^ 0x0f0f0fu) << "\n";
    }
  }
  header(nan_pcd, width, height, "false");
  header(clean_pcd, valid, 1, "true");
  header(other_pcd, width, height, "true");
  write("nan.pcd", nan_pcd.str() + nan_body.str());
  write("clean.pcd", clean_pcd.str() + clean_body.str());
  write("other.pcd", other_pcd.str() + other_body.str());
  const test::CliRun r = qm3d("compare nan.pcd other.pcd --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json with_nan = nlohmann::json::parse(r.out)["metrics"];
  const nlohmann::json clean = json_of("compare clean.pcd other.pcd")["metrics"];
  ASSERT_EQ(with_nan.size(), 3u);  // dlab, pcqm, psnr
  for (const auto& [metric, result] : clean.items()) {
    SCOPED_TRACE(metric);
    ASSERT_TRUE(with_nan.contains(metric));
    EXPECT_EQ(with_nan[metric]["features"], result["features"]);
    EXPECT_EQ(with_nan[metric]["score"], result["score"]);
  }
  const std::string line = "nan.pcd: " + std::to_string(width * height - valid) + " of " +
                           std::to_string(width * height) +
                           " points have a NaN or infinite coordinate";
  EXPECT_NE(r.err.find(line), std::string::npos) << r.err;
  // All NaN: an error naming the file.
  std::ostringstream all;
  header(all, 2, 1, "false");
  write("allnan.pcd", all.str() + "nan nan nan 1\nnan nan nan 2\n");
  const test::CliRun bad = qm3d("pcqm allnan.pcd other.pcd");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find("allnan.pcd: all 2 points have a NaN or infinite coordinate"),
            std::string::npos)
      << bad.err;
}

TEST_F(TextureCli, PsnrConventionsMmetricOnCloudsFromTheToolsJson) {
  for (const test::PcErrorCase& c : test::mpeg_cases("clouds_pcc/mm_pcc_clouds_reference.csv")) {
    if (c.name != "mm_cpcc_sph_dupnormals_res") continue;
    const test::CliRun r = test::run_qm3d("psnr " + c.column.at("a") + " " + c.column.at("b") +
                                              " --conventions mmetric --peak 1 --json",
                                          test::shared_data(), dir_ / "io", "");
    ASSERT_EQ(r.code, 0) << r.err;
    test::expect_pc_error_json(c, nlohmann::json::parse(r.out));
    return;
  }
  FAIL() << "case not found";
}

}  // namespace
}  // namespace qm3d

namespace qm3d {
namespace {

// mmetric's textured frame from the tool's JSON (one case; the library test runs all three).
TEST_F(TextureCli, MmetricTexturedFrameFromTheToolsJson) {
  const fs::path dir = test::reference_dir() / "mpeg" / "textured";
  for (const test::PcErrorCase& c : test::mpeg_cases("textured/mm_ibsm_textured_reference.csv")) {
    if (c.name != "bb3_qp16") continue;
    const std::string png = "basketball_player_00000003.png";
    const test::CliRun r =
        test::run_qm3d("ibsm " + c.column.at("mesh_a") + " " + c.column.at("mesh_b") +
                           " --ref-texture " + png + " --dist-texture " + png + " --no-ssim --json",
                       dir, dir_ / "io", "");
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json f = nlohmann::json::parse(r.out)["features"];
    int checked = 0;
    for (const auto& [column, text] : c.column) {
      std::string name = column == "UnmatchedPixelPercentage" ? "unmatched_pixel_percentage" : column;
      for (char& ch : name) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      if (!f.contains(name)) continue;
      const double want = std::stod(text);
      EXPECT_NEAR(f[name].get<double>(), want, 1e-8 * std::fabs(want)) << column;
      ++checked;
    }
    EXPECT_EQ(checked, 19);
    return;
  }
  FAIL() << "case bb3_qp16 not found";
}

}  // namespace
}  // namespace qm3d
