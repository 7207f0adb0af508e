#include "qm3d/pointcloud/cloud_io.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

#include "comma_locale.h"
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

// ---- issue 24: hostile PCD and PLY clouds ------------------------------------------------------

std::string pcd_header(const std::string& fields, const std::string& size, const std::string& type,
                       const std::string& count, std::size_t points,
                       const std::string& data = "ascii") {
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS " + fields + "\nSIZE " + size + "\nTYPE " + type +
         "\nCOUNT " + count + "\nWIDTH " + std::to_string(points) +
         "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 "
         "0 0\nPOINTS " +
         std::to_string(points) + "\nDATA " + data + "\n";
}

std::filesystem::path write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// 0xC86432 = (200, 100, 50).
const std::string kXyzRgb = pcd_header("x y z rgb", "4 4 4 4", "F F F U", "1 1 1 1", 2);

TEST(ReadCloudHostile, AsciiPcdLinesWithAValueTooManyOrTooFewAreErrorsNamingTheLine) {
  const auto dir = temp_dir("pcd_columns");
  expect_error_mentioning<FormatError>(
      write_file(dir / "many.pcd", kXyzRgb + "0.5 1.5 2.5 13132850\n0.5 1.5 2.5 13132850 7\n"),
      "line 13: 5 values, but FIELDS and COUNT declare 4");
  expect_error_mentioning<FormatError>(
      write_file(dir / "few.pcd", kXyzRgb + "0.5 1.5 2.5\n0.5 1.5 2.5 13132850\n"),
      "line 12: 3 values, but FIELDS and COUNT declare 4");
  expect_error_mentioning<FormatError>(
      write_file(dir / "word.pcd", kXyzRgb + "0.5 1.5 abc 13132850\n0.5 1.5 2.5 13132850\n"),
      "line 12: 'abc' (value 3) is not a number");
}

TEST(ReadCloudHostile, AsciiPcdPointsDisagreeingWithTheDataAreErrors) {
  const auto dir = temp_dir("pcd_points");
  const std::string line = "0.5 1.5 2.5 13132850\n";
  expect_error_mentioning<FormatError>(write_file(dir / "more.pcd", kXyzRgb + line + line + line),
                                       "line 14: more points than POINTS 2 declares");
  expect_error_mentioning<FormatError>(write_file(dir / "fewer.pcd", kXyzRgb + line + "\n\n"),
                                       "PCD data ends after 1 of the 2 points");
  // Blank lines and CRLF line ends are no points.
  const ColoredCloud c = read_cloud(write_file(dir / "crlf.pcd", kXyzRgb +
                                                                     "\n0.5 1.5 2.5 "
                                                                     "13132850\r\n\n" +
                                                                     line));
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], (Vec3{0.5, 1.5, 2.5}));
  EXPECT_EQ(c.colors[1].r, 200 / 255.0);
  EXPECT_EQ(c.colors[1].b, 50 / 255.0);
}

TEST(ReadCloudHostile, PcdCountAboveOneTakesThatManyColumns) {
  const auto dir = temp_dir("pcd_count");
  // x, y, z and rgb hold one value each: a COUNT of 2 is refused, in any encoding.
  expect_error_mentioning<FormatError>(
      write_file(dir / "rgb2.pcd", pcd_header("x y z rgb", "4 4 4 4", "F F F U", "1 1 1 2", 1) +
                                       "0.5 1.5 2.5 13132850 0\n"),
      "PCD field 'rgb' has COUNT 2");
  expect_error_mentioning<FormatError>(
      write_file(dir / "rgb2b.pcd",
                 pcd_header("x y z rgb", "4 4 4 4", "F F F U", "1 1 1 2", 1, "binary") +
                     std::string(20, '\0')),
      "PCD field 'rgb' has COUNT 2");
  // Another field of COUNT 3 takes three columns.
  const ColoredCloud c = read_cloud(write_file(
      dir / "normal.pcd", pcd_header("x normal y z rgb", "4 4 4 8 4", "F F F F F", "1 3 1 1 1", 1) +
                              "0.5 9 9 9 1.5 2.25 1.84030425e-38\n"));
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.positions[0], (Vec3{0.5, 1.5, 2.25}));
  EXPECT_EQ(c.colors[0].r, 200 / 255.0);  // a float rgb: its bits are 0x00C86432
  EXPECT_EQ(c.colors[0].g, 100 / 255.0);
}

// PCL pads binary files with zeros (up to a page): those are no points; other bytes are.
TEST(ReadCloudHostile, BinaryPcdWithDataAfterItsPointsIsAnError) {
  const auto dir = temp_dir("pcd_trailing");
  const auto pcl_cloud = to_pcl(head(cloud(kRefFile), 100));
  ASSERT_EQ(pcl::io::savePCDFileBinary((dir / "full.pcd").string(), pcl_cloud), 0);
  std::filesystem::copy_file(dir / "full.pcd", dir / "long.pcd");
  std::ofstream(dir / "long.pcd", std::ios::app | std::ios::binary) << std::string(16, '\1');
  expect_error_mentioning<FormatError>(dir / "long.pcd", "holds more data after them");
  EXPECT_EQ(read_cloud(dir / "full.pcd").size(), 100u);
}

// Patches the 4-byte compressed (at 0) or uncompressed (at 4) size of a binary_compressed PCD.
void patch_compressed_size(const std::filesystem::path& path, int at, std::uint32_t value) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const std::size_t data = text.find("DATA binary_compressed\n") + 23;
  f.seekp(static_cast<std::streamoff>(data + at));
  f.write(reinterpret_cast<const char*>(&value), 4);
}

// Issue 24: a header claiming 4 GB uncompressed made PCL allocate 8.4 GB before its error.
TEST(ReadCloudHostile, CompressedPcdSizesAreCheckedBeforeAnythingIsAllocated) {
  const auto dir = temp_dir("pcd_lzf");
  const auto pcl_cloud = to_pcl(head(cloud(kRefFile), 100));
  ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed((dir / "ok.pcd").string(), pcl_cloud), 0);
  EXPECT_EQ(read_cloud(dir / "ok.pcd").size(), 100u);
  std::filesystem::copy_file(dir / "ok.pcd", dir / "huge.pcd");
  patch_compressed_size(dir / "huge.pcd", 4, 0xFFFFFFF0u);
  expect_error_mentioning<FormatError>(
      dir / "huge.pcd", "claims 4294967280 bytes uncompressed, but POINTS 100 x 16 bytes");
  std::filesystem::copy_file(dir / "ok.pcd", dir / "long.pcd");
  patch_compressed_size(dir / "long.pcd", 0, 0x7FFFFFFFu);
  expect_error_mentioning<FormatError>(dir / "long.pcd", "claims 2147483647 compressed bytes");
}

// Issue 24: after setlocale(LC_ALL, "de_DE.UTF-8") ASCII PCD was read with y = z = 0, and
// ASCII PLY clouds did not parse.
TEST(ReadCloudHostile, CommaDecimalLocaleChangesNoNumber) {
  const auto dir = temp_dir("pcd_locale");
  const ColoredCloud small = head(cloud(kRefFile), 300);
  const auto pcl_cloud = to_pcl(small);
  ASSERT_EQ(pcl::PCDWriter().writeASCII((dir / "ascii.pcd").string(), pcl_cloud, 9), 0);
  ASSERT_EQ(pcl::io::savePCDFileBinary((dir / "binary.pcd").string(), pcl_cloud), 0);
  ply::WriteData ascii = write_data(small);
  ascii.format = ply::Format::kAscii;
  ply::write(dir / "ascii.ply", ascii);
  QM3D_WITH_COMMA_LOCALE(comma, dir);
  for (const char* name : {"ascii.pcd", "binary.pcd", "ascii.ply"}) {
    SCOPED_TRACE(name);
    expect_same_cloud(read_cloud(dir / name), small);
  }
}

TEST(ReadCloudHostile, FloatCoordinatesFarFromTheOriginAreAWarning) {
  const auto dir = temp_dir("pcd_far");
  std::string far = pcd_header("x y z rgb", "4 4 4 4", "F F F U", "1 1 1 1", 100);
  std::string near = far, as_double = pcd_header("x y z rgb", "8 8 8 4", "F F F U", "1 1 1 1", 100);
  for (int i = 0; i < 100; ++i) {  // a 1 x 1 grid of points 0.1 apart
    const std::string yz = " " + std::to_string(0.1 * (i / 10)) + " 0 13132850\n";
    far += std::to_string(1e7 + 0.1 * (i % 10)) + yz;
    as_double += std::to_string(1e7 + 0.1 * (i % 10)) + yz;
    near += std::to_string(0.1 * (i % 10)) + yz;
  }
  const CloudData d = read_cloud_data(write_file(dir / "far.pcd", far), CloudFormat::kPcd);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_NE(d.warnings[0].find("far.pcd: coordinates stored as float32: at |coordinate| 10000001 "
                               "the float32 step is 1"),
            std::string::npos)
      << d.warnings[0];
  EXPECT_TRUE(
      read_cloud_data(write_file(dir / "near.pcd", near), CloudFormat::kPcd).warnings.empty());
  EXPECT_TRUE(read_cloud_data(write_file(dir / "double.pcd", as_double), CloudFormat::kPcd)
                  .warnings.empty());
}

TEST(ReadCloudHostile, PlyFloatColourScaleIsAnOptionWithAWarning) {
  const auto dir = temp_dir("ply_scale");
  std::string text =
      "ply\nformat ascii 1.0\nelement vertex 100\nproperty float x\nproperty float "
      "y\nproperty float z\nproperty float red\nproperty float green\nproperty float "
      "blue\nend_header\n";
  for (int i = 0; i < 100; ++i) {
    text += std::to_string(i) + " " + std::to_string(i % 3) + " 0 0.5 " +
            (i == 7 ? "1.0000001" : "0.25") + " 1\n";
  }
  const auto path = write_file(dir / "c.ply", text);
  const CloudData automatic = read_cloud_data(path, CloudFormat::kPly);
  EXPECT_EQ(automatic.cloud.colors[0].r, 1 / 255.0);  // the reference's rule
  ASSERT_EQ(automatic.warnings.size(), 1u);
  // (1.0000001 as float32: clouds read ASCII `float` values as the reference does)
  EXPECT_EQ(automatic.warnings[0], path.string() +
                                       ": 1 of 300 colour values above 1 (max "
                                       "1.0000001192092896): read as 0..255 like the reference; "
                                       "--colour-scale unit reads them as 0..1");
  ReadOptions unit;
  unit.colour_scale = ColourScale::kUnit;
  const CloudData chosen = read_cloud_data(path, CloudFormat::kPly, unit);
  EXPECT_EQ(chosen.cloud.colors[0].r, 0.5);
  EXPECT_EQ(chosen.cloud.colors[7].g, 1.0);
}

}  // namespace
}  // namespace qm3d::pointcloud
