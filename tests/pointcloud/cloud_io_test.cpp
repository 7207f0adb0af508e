#include "qm3d/pointcloud/cloud_io.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstring>
#include <fstream>

#include "qm3d/common/error.h"
#include "qm3d/common/ply.h"
#include "qm3d/pointcloud/pcqm.h"
#include "reference_data.h"
#include "test_paths.h"

namespace qm3d::pointcloud {
namespace {

using test_data::cloud;
using test_data::head;
using test_data::temp_dir;

constexpr const char* kRefFile = "sphere_50k_ref.ply";
constexpr const char* kDistFile = "sphere_50k_cnoise10.ply";

std::array<std::uint8_t, 3> to_bytes(const Rgb& c) {
  return {std::uint8_t(std::lround(c.r * 255)), std::uint8_t(std::lround(c.g * 255)),
          std::uint8_t(std::lround(c.b * 255))};
}

ply::WriteData write_data(const ColoredCloud& c) {
  ply::WriteData d;
  d.positions = c.positions;
  for (const Rgb& rgb : c.colors) d.colors.push_back(to_bytes(rgb));
  return d;
}

// A PLY with colours named r g b (ply::write always writes red green blue).
void write_rgb_named_ply(const std::filesystem::path& path, const ColoredCloud& c) {
  std::ofstream out(path);
  out << "ply\nformat ascii 1.0\nelement vertex " << c.size()
      << "\nproperty float x\nproperty float y\nproperty float z\n"
         "property uchar r\nproperty uchar g\nproperty uchar b\nend_header\n";
  out.precision(17);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const auto b = to_bytes(c.colors[i]);
    out << c.positions[i][0] << ' ' << c.positions[i][1] << ' ' << c.positions[i][2] << ' '
        << int(b[0]) << ' ' << int(b[1]) << ' ' << int(b[2]) << '\n';
  }
}

void expect_same_cloud(const ColoredCloud& a, const ColoredCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.positions, b.positions);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.colors[i].r, b.colors[i].r) << i;
    ASSERT_EQ(a.colors[i].g, b.colors[i].g) << i;
    ASSERT_EQ(a.colors[i].b, b.colors[i].b) << i;
  }
}

double score(const ColoredCloud& ref, const ColoredCloud& dist) {
  PcqmOptions o;
  o.data_dir = test::tables_dir();
  o.per_element = false;
  return compute_pcqm(ref, dist, o).score;
}

TEST(ReadCloud, BinaryPlyColoursAreBytesOver255) {
  const ColoredCloud& c = cloud(kRefFile);
  ASSERT_EQ(c.size(), 50000u);
  ASSERT_EQ(c.colors.size(), 50000u);
  for (const Rgb& rgb : c.colors) {
    for (double v : {rgb.r, rgb.g, rgb.b}) {
      EXPECT_EQ(v, std::round(v * 255) / 255.0);
    }
  }
  // float x y z keep their exact value.
  for (const Vec3& p : c.positions) {
    for (double v : p) ASSERT_EQ(v, double(float(v)));
  }
}

// SPEC-PCQM §9.1: the reference (tinyply) reads an ASCII value declared `float` as a float32;
// a value declared `double` keeps its double precision. Meshes keep the double parse (MEPP2).
TEST(ReadCloud, AsciiFloatPropertiesAreReadAtFloatPrecision) {
  const auto dir = temp_dir("ascii_float");
  std::ofstream(dir / "cloud.ply") << "ply\nformat ascii 1.0\nelement vertex 2\n"
                                      "property float x\nproperty float y\nproperty double z\n"
                                      "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                                      "end_header\n0.1 1.3 0.1 1 2 3\n-2.7 1e-3 0.7 4 5 6\n";
  const ColoredCloud c = read_cloud(dir / "cloud.ply");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[0][0], double(0.1f));
  EXPECT_NE(c.positions[0][0], 0.1);
  EXPECT_EQ(c.positions[0][1], double(1.3f));
  EXPECT_EQ(c.positions[0][2], 0.1);  // declared double
  EXPECT_EQ(c.positions[1][0], double(-2.7f));
  EXPECT_EQ(c.positions[1][1], double(1e-3f));
  // The same bytes read as a mesh's vertices keep the double parse.
  EXPECT_EQ(ply::read(dir / "cloud.ply").positions[0][0], 0.1);
  EXPECT_EQ(ply::read(dir / "cloud.ply", ply::AsciiFloat::kAsDeclared).positions[0][0],
            double(0.1f));
}

TEST(ReadCloud, AsciiFloatOutOfFloatRangeIsANonFiniteCoordinate) {
  const auto dir = temp_dir("ascii_float_range");
  std::ofstream(dir / "big.ply") << "ply\nformat ascii 1.0\nelement vertex 1\n"
                                    "property float x\nproperty float y\nproperty float z\n"
                                    "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                                    "end_header\n1e39 0 0 1 2 3\n";
  try {
    read_cloud(dir / "big.ply");
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("big.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos) << e.what();
  }
}

TEST(ReadCloud, AsciiBinaryDoubleAndRgbNamedCopiesGiveTheSameScore) {
  const auto dir = temp_dir("ply");
  const ColoredCloud& ref = cloud(kRefFile);
  const ColoredCloud& dist = cloud(kDistFile);

  ply::WriteData ascii = write_data(ref);
  ascii.format = ply::Format::kAscii;
  ply::write(dir / "ref_ascii.ply", ascii);
  ply::WriteData binary = write_data(ref);
  ply::write(dir / "ref_binary.ply", binary);
  ply::WriteData as_double = write_data(ref);
  as_double.double_positions = true;
  ply::write(dir / "ref_double.ply", as_double);
  write_rgb_named_ply(dir / "ref_rgb.ply", ref);

  const double original = score(ref, dist);
  for (const char* name : {"ref_ascii.ply", "ref_binary.ply", "ref_double.ply", "ref_rgb.ply"}) {
    SCOPED_TRACE(name);
    const ColoredCloud copy = read_cloud(dir / name);
    expect_same_cloud(copy, ref);
    EXPECT_EQ(score(copy, dist), original);
  }
}

TEST(ReadCloud, ExtensionIsCaseInsensitive) {
  const auto dir = temp_dir("ext");
  const ColoredCloud small = head(cloud(kRefFile), 100);
  ply::write(dir / "UPPER.PLY", write_data(small));
  expect_same_cloud(read_cloud(dir / "UPPER.PLY"), small);
}

pcl::PointCloud<pcl::PointXYZRGB> to_pcl(const ColoredCloud& c) {
  pcl::PointCloud<pcl::PointXYZRGB> out;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const auto b = to_bytes(c.colors[i]);
    pcl::PointXYZRGB p(b[0], b[1], b[2]);
    p.x = float(c.positions[i][0]);
    p.y = float(c.positions[i][1]);
    p.z = float(c.positions[i][2]);
    out.push_back(p);
  }
  return out;
}

TEST(ReadCloud, PcdRoundTripInEveryEncoding) {
  const auto dir = temp_dir("pcd");
  const ColoredCloud& ref = cloud(kRefFile);
  const auto pcl_cloud = to_pcl(ref);
  ASSERT_EQ(pcl::io::savePCDFileBinary((dir / "binary.pcd").string(), pcl_cloud), 0);
  ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed((dir / "compressed.pcd").string(), pcl_cloud), 0);
  ASSERT_EQ(pcl::PCDWriter().writeASCII((dir / "ascii.pcd").string(), pcl_cloud, 9), 0);
  for (const char* name : {"binary.pcd", "compressed.pcd", "ascii.pcd"}) {
    SCOPED_TRACE(name);
    expect_same_cloud(read_cloud(dir / name), ref);
  }
  EXPECT_EQ(score(read_cloud(dir / "binary.pcd"), cloud(kDistFile)), score(ref, cloud(kDistFile)));
}

TEST(ReadCloud, PcdWithRgbaField) {
  const auto dir = temp_dir("rgba");
  const ColoredCloud small = head(cloud(kRefFile), 200);
  pcl::PointCloud<pcl::PointXYZRGBA> rgba;
  for (std::size_t i = 0; i < small.size(); ++i) {
    const auto b = to_bytes(small.colors[i]);
    pcl::PointXYZRGBA p;
    p.x = float(small.positions[i][0]);
    p.y = float(small.positions[i][1]);
    p.z = float(small.positions[i][2]);
    p.r = b[0];
    p.g = b[1];
    p.b = b[2];
    p.a = 77;
    rgba.push_back(p);
  }
  ASSERT_EQ(pcl::io::savePCDFileBinary((dir / "rgba.pcd").string(), rgba), 0);
  expect_same_cloud(read_cloud(dir / "rgba.pcd"), small);
}

TEST(ReadCloud, PcdWithDoubleCoordinatesAndUintColour) {
  const auto dir = temp_dir("pcd64");
  const ColoredCloud small = head(cloud(kRefFile), 50);
  pcl::PCLPointCloud2 c;
  c.width = std::uint32_t(small.size());
  c.height = 1;
  c.point_step = 3 * 8 + 4;
  c.row_step = c.point_step * c.width;
  for (std::uint32_t a = 0; a < 3; ++a) {
    pcl::PCLPointField f;
    f.name = std::string(1, char('x' + a));
    f.offset = 8 * a;
    f.datatype = pcl::PCLPointField::FLOAT64;
    f.count = 1;
    c.fields.push_back(f);
  }
  pcl::PCLPointField rgb;
  rgb.name = "rgb";
  rgb.offset = 24;
  rgb.datatype = pcl::PCLPointField::UINT32;
  rgb.count = 1;
  c.fields.push_back(rgb);
  c.data.resize(c.row_step);
  ColoredCloud expected = small;
  for (std::size_t i = 0; i < small.size(); ++i) {
    for (int a = 0; a < 3; ++a) expected.positions[i][a] += 1e-12 * double(i);  // not floats
    std::memcpy(&c.data[i * c.point_step], expected.positions[i].data(), 24);
    const auto b = to_bytes(small.colors[i]);
    const std::uint32_t packed = (0xffu << 24) | (b[0] << 16) | (b[1] << 8) | b[2];
    std::memcpy(&c.data[i * c.point_step + 24], &packed, 4);
  }
  ASSERT_EQ(pcl::PCDWriter().writeBinary((dir / "double.pcd").string(), c), 0);
  expect_same_cloud(read_cloud(dir / "double.pcd"), expected);
}

template <typename E>
void expect_error_mentioning(const std::filesystem::path& path, const std::string& text) {
  try {
    read_cloud(path);
    ADD_FAILURE() << "no exception for " << path;
  } catch (const E& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find(text), std::string::npos) << what;
  }
}

TEST(ReadCloudErrors, NoColours) {
  const auto dir = temp_dir("nocolour");
  ply::WriteData d;
  d.positions = head(cloud(kRefFile), 10).positions;
  ply::write(dir / "plain.ply", d);
  expect_error_mentioning<FormatError>(dir / "plain.ply", "no vertex colours");

  pcl::PointCloud<pcl::PointXYZ> xyz;
  for (const Vec3& p : d.positions)
    xyz.push_back(pcl::PointXYZ(float(p[0]), float(p[1]), float(p[2])));
  ASSERT_EQ(pcl::io::savePCDFileBinary((dir / "plain.pcd").string(), xyz), 0);
  expect_error_mentioning<FormatError>(dir / "plain.pcd", "no vertex colours");
}

TEST(ReadCloudErrors, UnknownExtension) {
  const auto dir = temp_dir("unknown");
  std::ofstream(dir / "cloud.xyz") << "0 0 0\n";
  expect_error_mentioning<FormatError>(dir / "cloud.xyz", "unknown point-cloud extension");
  expect_error_mentioning<FormatError>(dir / "cloud", "unknown point-cloud extension");
}

TEST(ReadCloudErrors, MissingOrMalformedFiles) {
  const auto dir = temp_dir("missing");
  expect_error_mentioning<InputError>(dir / "absent.pcd", "not found");
  EXPECT_THROW(read_cloud(dir / "absent.ply"), InputError);
  std::ofstream(dir / "garbage.pcd") << "this is not a point cloud\n";
  expect_error_mentioning<FormatError>(dir / "garbage.pcd", "not a PCD file");

  // A binary PCD cut in the middle of its data.
  const auto pcl_cloud = to_pcl(head(cloud(kRefFile), 1000));
  ASSERT_EQ(pcl::io::savePCDFileBinary((dir / "full.pcd").string(), pcl_cloud), 0);
  const auto size = std::filesystem::file_size(dir / "full.pcd");
  std::filesystem::copy_file(dir / "full.pcd", dir / "cut.pcd");
  std::filesystem::resize_file(dir / "cut.pcd", size - 4000);
  EXPECT_THROW(read_cloud(dir / "cut.pcd"), FormatError);
}

// Found by fuzz_pcd: a header with COUNT 0 made PCL's readHeader throw a std::exception that
// escaped as an internal error. It must be a FormatError naming the file.
TEST(ReadCloudErrors, FuzzRegressionZeroFieldCount) {
  expect_error_mentioning<FormatError>(
      std::filesystem::path(QM3D_TEST_DATA_DIR) / "regression_zero_count.pcd", "PCD");
}

// Found by fuzz_pcd (ASan heap-buffer-overflow): SIZE/COUNT/TYPE that disagree put a field
// beyond the point record.
TEST(ReadCloudErrors, FuzzRegressionFieldBeyondRecord) {
  EXPECT_THROW(read_cloud(std::filesystem::path(QM3D_TEST_DATA_DIR) / "regression_field_overflow.pcd"),
               FormatError);
}

// A header claiming far more points than the file holds fails before PCL allocates them.
TEST(ReadCloudErrors, PcdHeaderClaimingTooManyPoints) {
  const auto dir = temp_dir("huge");
  std::ofstream(dir / "huge.pcd") << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\n"
                                     "TYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 2147483647\nHEIGHT 1\n"
                                     "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2147483647\nDATA ascii\n0 0 0 1\n";
  expect_error_mentioning<FormatError>(dir / "huge.pcd", "too short");
}

}  // namespace
}  // namespace qm3d::pointcloud
