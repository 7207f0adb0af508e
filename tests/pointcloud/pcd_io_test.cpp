// qm3d's PCD reader (pointcloud_metric/src/pcd_io.h) against PCL 1.13's PCDReader, the reader it
// replaces, on files of every kind PCL writes: ascii, binary and binary_compressed; float and
// double coordinates; rgb declared F, U or I and rgba; fields before, between and after x y z,
// of other sizes and of COUNT > 1; organised clouds with NaN points; large clouds. Only this test
// links PCL; the tool and the libraries do not.
#include "pcd_io.h"

#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <pcl/filters/impl/filter.hpp>  // removeNaNFromPointCloud (pcl_filters is not linked)
#include <random>
#include <string>
#include <vector>

#include "qm3d/common/error.h"
#include "qm3d/pointcloud/cloud_io.h"
#include "reference_data.h"

namespace qm3d::pointcloud {
namespace {

using detail::PcdPoints;
using detail::read_pcd_points;
using test_data::temp_dir;

enum class Encoding { kAscii, kBinary, kCompressed };
constexpr Encoding kEncodings[] = {Encoding::kAscii, Encoding::kBinary, Encoding::kCompressed};

const char* name_of(Encoding e) {
  return e == Encoding::kAscii ? "ascii" : e == Encoding::kBinary ? "binary" : "compressed";
}

const pcl::PCLPointField* find_field(const pcl::PCLPointCloud2& c, const std::string& name) {
  for (const auto& f : c.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

// What PCL's reader gives: x, y, z and the packed colour taken from its PCLPointCloud2 exactly as
// qm3d's reader did while it read PCD through PCL.
PcdPoints read_with_pcl(const std::filesystem::path& path) {
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  pcl::PCLPointCloud2 c;
  PcdPoints out;
  if (pcl::PCDReader().read(path.string(), c) < 0) {
    ADD_FAILURE() << "PCL cannot read " << path;
    return out;
  }
  const pcl::PCLPointField* xyz[3] = {find_field(c, "x"), find_field(c, "y"), find_field(c, "z")};
  const pcl::PCLPointField* rgb =
      find_field(c, "rgb") ? find_field(c, "rgb") : find_field(c, "rgba");
  if (!xyz[0] || !xyz[1] || !xyz[2] || !rgb) {
    ADD_FAILURE() << "PCL reads no x, y, z or rgb in " << path;
    return out;
  }
  const std::size_t n = std::size_t(c.width) * c.height;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* point = c.data.data() + i * c.point_step;
    Vec3 p{};
    for (int a = 0; a < 3; ++a) {
      if (xyz[a]->datatype == pcl::PCLPointField::FLOAT64) {
        std::memcpy(&p[a], point + xyz[a]->offset, 8);
      } else {
        float v;
        std::memcpy(&v, point + xyz[a]->offset, 4);
        p[a] = v;
      }
    }
    std::uint32_t bits;
    std::memcpy(&bits, point + rgb->offset, 4);
    out.cloud.positions.push_back(p);
    out.cloud.colors.push_back(
        Rgb{((bits >> 16) & 0xffu) / 255.0, ((bits >> 8) & 0xffu) / 255.0, (bits & 0xffu) / 255.0});
  }
  return out;
}

bool same_value(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

// Every position (NaN where PCL has NaN) and every colour channel identical.
void expect_same_as_pcl(const std::filesystem::path& path) {
  SCOPED_TRACE(path.string());
  const PcdPoints ours = read_pcd_points(path);
  const PcdPoints pcl = read_with_pcl(path);
  ASSERT_EQ(ours.cloud.size(), pcl.cloud.size());
  ASSERT_EQ(ours.cloud.colors.size(), pcl.cloud.colors.size());
  for (std::size_t i = 0; i < ours.cloud.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      ASSERT_TRUE(same_value(ours.cloud.positions[i][a], pcl.cloud.positions[i][a]))
          << "point " << i << " axis " << a << ": " << ours.cloud.positions[i][a] << " vs "
          << pcl.cloud.positions[i][a];
    }
    ASSERT_EQ(ours.cloud.colors[i].r, pcl.cloud.colors[i].r) << i;
    ASSERT_EQ(ours.cloud.colors[i].g, pcl.cloud.colors[i].g) << i;
    ASSERT_EQ(ours.cloud.colors[i].b, pcl.cloud.colors[i].b) << i;
  }
}

int write_ascii(pcl::PCDWriter& w, const std::string& path, const pcl::PCLPointCloud2& c) {
  return w.writeASCII(path, c, Eigen::Vector4f::Zero(), Eigen::Quaternionf::Identity(), 9);
}
template <typename Point>
int write_ascii(pcl::PCDWriter& w, const std::string& path, const pcl::PointCloud<Point>& c) {
  return w.writeASCII(path, c, 9);
}

template <typename Cloud>
std::filesystem::path write_pcl(const std::filesystem::path& path, const Cloud& c, Encoding e) {
  pcl::PCDWriter w;
  const int rc = e == Encoding::kAscii    ? write_ascii(w, path.string(), c)
                 : e == Encoding::kBinary ? w.writeBinary(path.string(), c)
                                          : w.writeBinaryCompressed(path.string(), c);
  EXPECT_EQ(rc, 0) << path;
  return path;
}

std::uint32_t random_rgb(std::mt19937& rng) { return rng() & 0xffffffu; }

pcl::PointCloud<pcl::PointXYZRGB> random_xyzrgb(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coord(-2.0f, 2.0f);
  pcl::PointCloud<pcl::PointXYZRGB> c;
  for (std::size_t i = 0; i < n; ++i) {
    pcl::PointXYZRGB p;
    p.x = coord(rng);
    p.y = coord(rng);
    p.z = i % 7 == 0 ? 0.5f : coord(rng);  // repeated values: LZF back references
    p.rgb = 0;
    p.rgba = random_rgb(rng);
    c.push_back(p);
  }
  return c;
}

TEST(PcdReaderVsPcl, XyzRgbInEveryEncoding) {
  const auto dir = temp_dir("pcd_vs_xyzrgb");
  const auto c = random_xyzrgb(3000, 1);
  for (const Encoding e : kEncodings) {
    expect_same_as_pcl(write_pcl(dir / (std::string(name_of(e)) + ".pcd"), c, e));
  }
}

TEST(PcdReaderVsPcl, ReferenceSphereInEveryEncoding) {
  const auto dir = temp_dir("pcd_vs_sphere");
  const ColoredCloud& sphere = test_data::cloud("sphere_50k_ref.ply");
  pcl::PointCloud<pcl::PointXYZRGB> c;
  for (std::size_t i = 0; i < sphere.size(); ++i) {
    pcl::PointXYZRGB p(std::uint8_t(std::lround(sphere.colors[i].r * 255)),
                       std::uint8_t(std::lround(sphere.colors[i].g * 255)),
                       std::uint8_t(std::lround(sphere.colors[i].b * 255)));
    p.x = float(sphere.positions[i][0]);
    p.y = float(sphere.positions[i][1]);
    p.z = float(sphere.positions[i][2]);
    c.push_back(p);
  }
  for (const Encoding e : kEncodings) {
    const auto path = write_pcl(dir / (std::string(name_of(e)) + ".pcd"), c, e);
    expect_same_as_pcl(path);
    EXPECT_EQ(read_cloud(path).positions, sphere.positions) << name_of(e);  // float32 in the PLY
  }
}

TEST(PcdReaderVsPcl, XyzRgbaInEveryEncoding) {
  const auto dir = temp_dir("pcd_vs_rgba");
  std::mt19937 rng(2);
  pcl::PointCloud<pcl::PointXYZRGBA> c;
  for (int i = 0; i < 500; ++i) {
    pcl::PointXYZRGBA p;
    p.x = float(i) * 0.01f;
    p.y = std::sin(float(i));
    p.z = -float(i);
    p.rgba = rng();  // alpha in the top byte, ignored
    c.push_back(p);
  }
  for (const Encoding e : kEncodings) {
    expect_same_as_pcl(write_pcl(dir / (std::string(name_of(e)) + ".pcd"), c, e));
  }
}

pcl::PCLPointField field(const std::string& name, std::uint8_t type, std::uint32_t count = 1) {
  pcl::PCLPointField f;
  f.name = name;
  f.datatype = type;
  f.count = count;
  return f;
}

std::size_t type_bytes(std::uint8_t type) {
  switch (type) {
    case pcl::PCLPointField::INT8:
    case pcl::PCLPointField::UINT8:
      return 1;
    case pcl::PCLPointField::INT16:
    case pcl::PCLPointField::UINT16:
      return 2;
    case pcl::PCLPointField::FLOAT64:
      return 8;
    default:
      return 4;
  }
}

// A PCLPointCloud2 with `fields` (offsets laid out in order) and n points of random bytes, where
// x, y, z get finite coordinates and the colour field random 0x00RRGGBB.
pcl::PCLPointCloud2 mixed_cloud(std::vector<pcl::PCLPointField> fields, std::size_t n,
                                unsigned seed) {
  pcl::PCLPointCloud2 c;
  std::uint32_t offset = 0;
  for (auto& f : fields) {
    f.offset = offset;
    offset += std::uint32_t(type_bytes(f.datatype) * f.count);
  }
  c.fields = fields;
  c.point_step = offset;
  c.width = std::uint32_t(n);
  c.height = 1;
  c.row_step = c.point_step * c.width;
  c.is_dense = true;
  c.data.resize(std::size_t(c.row_step));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coord(-100.0, 100.0);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint8_t* point = c.data.data() + i * c.point_step;
    for (const auto& f : fields) {
      std::uint8_t* at = point + f.offset;
      if (f.name == "x" || f.name == "y" || f.name == "z") {
        const double v = coord(rng);
        const float vf = float(v);
        f.datatype == pcl::PCLPointField::FLOAT64 ? std::memcpy(at, &v, 8)
                                                  : std::memcpy(at, &vf, 4);
      } else if (f.name == "rgb" || f.name == "rgba") {
        const std::uint32_t bits = random_rgb(rng);
        std::memcpy(at, &bits, 4);
      } else {  // other fields: small integers, as bytes that are valid in any type
        for (std::size_t b = 0; b < type_bytes(f.datatype) * f.count; ++b) at[b] = 0;
        at[0] = std::uint8_t(rng() % 100);
      }
    }
  }
  return c;
}

TEST(PcdReaderVsPcl, DoubleCoordinatesAndOtherFieldsAroundThemInEveryEncoding) {
  const auto dir = temp_dir("pcd_vs_mixed");
  using F = pcl::PCLPointField;
  const std::vector<std::vector<F>> layouts = {
      // rgb first (TYPE U), a COUNT-3 normal, 1-, 2- and 8-byte fields between the coordinates
      {field("rgb", F::UINT32), field("normal", F::FLOAT32, 3), field("x", F::FLOAT64),
       field("intensity", F::UINT8), field("y", F::FLOAT64), field("label", F::INT16),
       field("z", F::FLOAT64), field("curvature", F::FLOAT64, 2)},
      // float coordinates, rgba declared I, a field of COUNT 5 at the end
      {field("x", F::FLOAT32), field("y", F::FLOAT32), field("z", F::FLOAT32),
       field("rgba", F::INT32), field("histogram", F::UINT16, 5)},
      // mixed float and double coordinates, rgb declared F (its bits are the colour)
      {field("z", F::FLOAT32), field("rgb", F::FLOAT32), field("y", F::FLOAT64),
       field("x", F::FLOAT32)},
  };
  for (std::size_t k = 0; k < layouts.size(); ++k) {
    const pcl::PCLPointCloud2 c = mixed_cloud(layouts[k], 700, unsigned(k));
    for (const Encoding e : kEncodings) {
      expect_same_as_pcl(
          write_pcl(dir / ("layout" + std::to_string(k) + "_" + name_of(e) + ".pcd"), c, e));
    }
  }
}

// The tool's cloud against PCL's own pipeline: pcl::io::loadPCDFile, then
// pcl::removeNaNFromPointCloud. The same points in the same order, one warning giving the count.
void expect_nan_points_dropped_as_pcl(const std::filesystem::path& path, std::size_t dropped) {
  SCOPED_TRACE(path.string());
  pcl::PointCloud<pcl::PointXYZRGB> loaded, filtered;
  ASSERT_EQ(pcl::io::loadPCDFile(path.string(), loaded), 0);
  EXPECT_FALSE(loaded.is_dense);  // what makes removeNaNFromPointCloud look at the points
  pcl::Indices kept;
  pcl::removeNaNFromPointCloud(loaded, filtered, kept);
  const CloudData ours = read_cloud_data(path, CloudFormat::kPcd);
  ASSERT_EQ(ours.cloud.size(), filtered.size());
  EXPECT_EQ(loaded.size() - filtered.size(), dropped);
  for (std::size_t i = 0; i < filtered.size(); ++i) {
    const auto& p = filtered[i];
    ASSERT_EQ(ours.cloud.positions[i], (Vec3{p.x, p.y, p.z})) << i;
    ASSERT_EQ(ours.cloud.colors[i].r, p.r / 255.0) << i;
    ASSERT_EQ(ours.cloud.colors[i].g, p.g / 255.0) << i;
    ASSERT_EQ(ours.cloud.colors[i].b, p.b / 255.0) << i;
  }
  ASSERT_EQ(ours.warnings.size(), 1u);
  EXPECT_EQ(ours.warnings[0], path.string() + ": " + std::to_string(dropped) + " of " +
                                  std::to_string(loaded.size()) +
                                  " points have a NaN or infinite coordinate (invalid "
                                  "measurements of an organised cloud): dropped, as "
                                  "pcl::removeNaNFromPointCloud does");
}

pcl::PointCloud<pcl::PointXYZRGB> organised_with_nans() {
  pcl::PointCloud<pcl::PointXYZRGB> c = random_xyzrgb(16 * 8, 3);
  c.width = 16;
  c.height = 8;
  c.is_dense = false;
  for (std::size_t i : {5u, 6u, 40u, 127u}) {  // invalid pixels of a depth camera
    c[i].x = c[i].y = c[i].z = std::numeric_limits<float>::quiet_NaN();
  }
  return c;
}

TEST(PcdReaderVsPcl, OrganisedCloudWithNanPointsInEveryEncoding) {
  const auto dir = temp_dir("pcd_vs_organised");
  const auto c = organised_with_nans();
  for (const Encoding e : kEncodings) {
    const auto path = write_pcl(dir / (std::string(name_of(e)) + ".pcd"), c, e);
    expect_same_as_pcl(path);
    EXPECT_EQ(read_pcd_points(path).cloud.size(), 128u);
    EXPECT_TRUE(std::isnan(read_pcd_points(path).cloud.positions[5][0]));
    expect_nan_points_dropped_as_pcl(path, 4);
  }
}

// A cloud of NaN points only: an error naming the file (PCL would leave an empty cloud).
TEST(PcdReaderVsPcl, AllNanCloudIsAnErrorNamingTheFile) {
  const auto dir = temp_dir("pcd_all_nan");
  pcl::PointCloud<pcl::PointXYZRGB> c = organised_with_nans();
  for (auto& p : c) p.x = std::numeric_limits<float>::quiet_NaN();
  for (const Encoding e : kEncodings) {
    const auto path = write_pcl(dir / (std::string(name_of(e)) + ".pcd"), c, e);
    try {
      read_cloud_data(path, CloudFormat::kPcd);
      ADD_FAILURE() << "no error for " << path;
    } catch (const FormatError& err) {
      EXPECT_EQ(
          std::string(err.what()),
          path.string() + ": all 128 points have a NaN or infinite coordinate (no valid point)");
    }
  }
}

TEST(PcdReaderVsPcl, OrganisedCloudWithoutNans) {
  const auto dir = temp_dir("pcd_vs_grid");
  pcl::PointCloud<pcl::PointXYZRGB> c = random_xyzrgb(32 * 4, 4);
  c.width = 32;
  c.height = 4;
  for (const Encoding e : kEncodings) {
    const auto path = write_pcl(dir / (std::string(name_of(e)) + ".pcd"), c, e);
    expect_same_as_pcl(path);
    EXPECT_EQ(read_cloud(path).size(), 128u);
  }
}

TEST(PcdReaderVsPcl, LargeCloudsBinaryAndCompressed) {
  const auto dir = temp_dir("pcd_vs_large");
  const auto c = random_xyzrgb(400000, 5);  // 6.4 MB of records
  for (const Encoding e : {Encoding::kBinary, Encoding::kCompressed}) {
    expect_same_as_pcl(write_pcl(dir / (std::string(name_of(e)) + ".pcd"), c, e));
  }
}

TEST(PcdReaderVsPcl, XyzOnlyIsNoColoursInEveryEncoding) {
  const auto dir = temp_dir("pcd_vs_xyz");
  pcl::PointCloud<pcl::PointXYZ> c;
  for (int i = 0; i < 50; ++i) c.push_back(pcl::PointXYZ(float(i), 1.0f, 2.0f));
  for (const Encoding e : kEncodings) {
    const auto path = write_pcl(dir / (std::string(name_of(e)) + ".pcd"), c, e);
    try {
      read_cloud(path);
      ADD_FAILURE() << "no error for " << path;
    } catch (const FormatError& err) {
      EXPECT_EQ(std::string(err.what()),
                path.string() +
                    ": no vertex colours (PCQM needs one colour per point; expected "
                    "a packed 'rgb' or 'rgba' PCD field)");
    }
  }
}

// ---- malformed binary data: one line naming the file ---------------------------------------

std::string file_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::filesystem::path write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Where the data of a PCD written by PCL starts (after its DATA line).
std::size_t data_start(const std::string& text) {
  const std::size_t line = text.find("\nDATA ");
  return text.find('\n', line + 1) + 1;
}

void expect_one_line_error(const std::filesystem::path& path, const std::string& text) {
  try {
    read_cloud(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const FormatError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path.string() + ": ", 0), 0u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find(text), std::string::npos) << what;
  }
}

TEST(PcdReaderErrors, CorruptLzfStreamIsAnError) {
  const auto dir = temp_dir("pcd_lzf_corrupt");
  const std::string ok =
      file_text(write_pcl(dir / "ok.pcd", random_xyzrgb(1000, 6), Encoding::kCompressed));
  const std::size_t data = data_start(ok);
  // A back reference before the start of the output as the first LZF token.
  std::string bad = ok;
  bad[data + 8] = char(0xE0);
  bad[data + 9] = char(0xFF);
  bad[data + 10] = char(0xFF);
  expect_one_line_error(write_text(dir / "backref.pcd", bad),
                        "PCD binary_compressed data is corrupt (its LZF stream does not "
                        "decompress into the 16000 bytes it declares)");
  // A stream cut short: the compressed size says 100 bytes fewer.
  std::string cut = ok;
  std::uint32_t compressed;
  std::memcpy(&compressed, cut.data() + data, 4);
  compressed -= 100;
  std::memcpy(cut.data() + data, &compressed, 4);
  expect_one_line_error(write_text(dir / "cut.pcd", cut), "PCD binary_compressed data is corrupt");
}

TEST(PcdReaderErrors, PaddingFieldInCompressedDataIsAnError) {
  const auto dir = temp_dir("pcd_lzf_padding");
  const std::string header =
      "VERSION 0.7\nFIELDS x y z _ rgb\nSIZE 4 4 4 4 4\nTYPE F F F U U\nCOUNT 1 1 1 1 1\n"
      "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary_compressed\n";
  // 20 bytes stored as one LZF literal run (control byte 19 = 20 literals).
  std::string body(4 + 4 + 1 + 20, '\0');
  const std::uint32_t sizes[2] = {21, 20};
  std::memcpy(body.data(), sizes, 8);
  body[8] = char(19);
  expect_one_line_error(write_text(dir / "pad.pcd", header + body),
                        "binary_compressed data with a padding field '_' is not supported");
}

TEST(PcdReaderErrors, TruncatedBinaryFilesAreErrors) {
  const auto dir = temp_dir("pcd_truncated");
  for (const Encoding e : {Encoding::kBinary, Encoding::kCompressed}) {
    const std::string ok =
        file_text(write_pcl(dir / (std::string(name_of(e)) + ".pcd"), random_xyzrgb(200, 7), e));
    std::uint32_t compressed = 0;
    std::memcpy(&compressed, ok.data() + data_start(ok), 4);
    // 50 bytes short of the last point (binary) or of the end of the LZF stream
    const std::size_t end = data_start(ok) + (e == Encoding::kBinary ? 200 * 16 : 8 + compressed);
    const auto path =
        write_text(dir / (std::string("cut_") + name_of(e) + ".pcd"), ok.substr(0, end - 50));
    expect_one_line_error(path, e == Encoding::kBinary ? "is too short to hold them" : "truncated");
  }
}

}  // namespace
}  // namespace qm3d::pointcloud
