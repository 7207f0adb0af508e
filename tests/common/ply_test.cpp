#include "qm3d/common/ply.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "qm3d/common/error.h"

namespace qm3d::ply {
namespace {

// Builds PLY bytes with any property types, in any format, from double values.
struct Builder {
  Format format = Format::kAscii;
  std::string pos_type = "float";
  std::string color_type = "uchar";
  std::vector<std::string> color_names{"red", "green", "blue"};
  bool alpha = false;
  std::vector<std::array<double, 6>> vertices;  // x y z r g b
  std::vector<std::vector<long>> faces;
  std::string index_type = "int";
  long claimed_vertices = -1;

  std::string bytes() const {
    std::ostringstream o;
    const char* fmt = format == Format::kAscii                ? "ascii"
                      : format == Format::kBinaryLittleEndian ? "binary_little_endian"
                                                              : "binary_big_endian";
    o << "ply\nformat " << fmt << " 1.0\ncomment test\nelement vertex "
      << (claimed_vertices >= 0 ? claimed_vertices : long(vertices.size())) << "\n";
    for (const char* c : {"x", "y", "z"}) o << "property " << pos_type << " " << c << "\n";
    for (const auto& n : color_names) o << "property " << color_type << " " << n << "\n";
    if (alpha) o << "property " << color_type << " alpha\n";
    o << "element face " << faces.size() << "\nproperty list uchar " << index_type
      << " vertex_indices\nend_header\n";
    for (const auto& v : vertices) {
      for (int k = 0; k < 6; ++k) value(o, k < 3 ? pos_type : color_type, v[k]);
      if (alpha) value(o, color_type, 1);
      if (format == Format::kAscii) o << "\n";
    }
    for (const auto& f : faces) {
      value(o, "uchar", double(f.size()));
      for (long i : f) value(o, index_type, double(i));
      if (format == Format::kAscii) o << "\n";
    }
    return o.str();
  }

  template <typename T>
  void raw(std::ostream& o, T v) const {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (format == Format::kBinaryBigEndian) std::reverse(b, b + sizeof(T));
    o.write(b, sizeof(T));
  }

  void value(std::ostream& o, const std::string& t, double v) const {
    if (format == Format::kAscii) {
      o.precision(17);
      o << v << " ";
      return;
    }
    if (t == "char")
      raw<std::int8_t>(o, std::int8_t(v));
    else if (t == "uchar")
      raw<std::uint8_t>(o, std::uint8_t(v));
    else if (t == "short")
      raw<std::int16_t>(o, std::int16_t(v));
    else if (t == "ushort")
      raw<std::uint16_t>(o, std::uint16_t(v));
    else if (t == "int")
      raw<std::int32_t>(o, std::int32_t(v));
    else if (t == "uint")
      raw<std::uint32_t>(o, std::uint32_t(v));
    else if (t == "float")
      raw<float>(o, float(v));
    else
      raw<double>(o, v);
  }
};

Builder triangle() {
  Builder b;
  b.vertices = {{0.5, -1.25, 2, 0, 128, 255}, {1, 0, 0, 255, 0, 1}, {0, 1, -3, 10, 20, 30}};
  b.faces = {{0, 1, 2}};
  return b;
}

std::string error_of(const std::string& bytes) {
  try {
    parse(bytes, "t.ply");
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

TEST(Ply, RoundTripsEveryPositionTypeInEveryFormat) {
  for (Format f : {Format::kAscii, Format::kBinaryLittleEndian, Format::kBinaryBigEndian}) {
    for (const char* t : {"char", "uchar", "short", "ushort", "int", "uint", "float", "double"}) {
      SCOPED_TRACE(std::string(t) + " format " + std::to_string(int(f)));
      Builder b = triangle();
      b.format = f;
      b.pos_type = t;
      for (auto& v : b.vertices) {  // values every type can hold exactly
        for (int k = 0; k < 3; ++k) v[k] = std::fabs(std::round(v[k]));
      }
      const Content c = parse(b.bytes(), "t.ply");
      ASSERT_EQ(c.positions.size(), 3u);
      for (int i = 0; i < 3; ++i) {
        for (int k = 0; k < 3; ++k) EXPECT_EQ(c.positions[i][k], b.vertices[i][k]);
      }
      ASSERT_EQ(c.face_offsets.size(), 2u);
      EXPECT_EQ(c.face_indices, (std::vector<std::uint32_t>{0, 1, 2}));
    }
  }
}

TEST(Ply, AsciiPositionsKeepDoublePrecisionWhateverTheDeclaredType) {
  Builder b = triangle();
  b.vertices[0][0] = 0.552012827;  // not representable as float
  EXPECT_EQ(parse(b.bytes(), "t.ply").positions[0][0], 0.552012827);
}

TEST(Ply, ColourTypesAreNormalisedToUnitRange) {
  for (Format f : {Format::kAscii, Format::kBinaryLittleEndian, Format::kBinaryBigEndian}) {
    Builder b = triangle();
    b.format = f;
    EXPECT_EQ(parse(b.bytes(), "t.ply").colors[0].b, 1.0);
    EXPECT_EQ(parse(b.bytes(), "t.ply").colors[0].g, 128 / 255.0);
    b.color_type = "ushort";
    b.vertices[0][4] = 65535;
    EXPECT_EQ(parse(b.bytes(), "t.ply").colors[0].g, 1.0);
    EXPECT_EQ(parse(b.bytes(), "t.ply").colors[2].r, 10 / 65535.0);
    b = triangle();
    b.format = f;
    b.color_type = "float";
    for (auto& v : b.vertices) v[3] = v[4] = v[5] = 0.25;
    EXPECT_EQ(parse(b.bytes(), "t.ply").colors[1].g, 0.25);
    EXPECT_EQ(parse(b.bytes(), "t.ply").color_encoding, ColorEncoding::kFloat);
  }
}

TEST(Ply, FloatColoursAbove1AreRead0To255LikeMepp2) {
  Builder b = triangle();
  b.color_type = "float";
  EXPECT_EQ(parse(b.bytes(), "t.ply").colors[0].g, 128 / 255.0);
}

TEST(Ply, ColourNamesRgbAndDiffuseAndAlphaIgnored) {
  Builder b = triangle();
  b.color_names = {"r", "g", "b"};
  EXPECT_EQ(parse(b.bytes(), "t.ply").colors[2].g, 20 / 255.0);
  b.color_names = {"diffuse_red", "diffuse_green", "diffuse_blue"};
  b.alpha = true;
  b.format = Format::kBinaryLittleEndian;
  EXPECT_EQ(parse(b.bytes(), "t.ply").colors[2].b, 30 / 255.0);
}

TEST(Ply, NoColoursGivesEmptyColours) {
  Builder b = triangle();
  b.color_names = {"nx", "ny", "nz"};
  const Content c = parse(b.bytes(), "t.ply");
  EXPECT_TRUE(c.colors.empty());
  EXPECT_EQ(c.color_encoding, ColorEncoding::kNone);
}

TEST(Ply, MalformedInputsAreNamedErrors) {
  EXPECT_NE(error_of("").find("t.ply: PLY: not a PLY file"), std::string::npos);
  EXPECT_NE(error_of("x").find("not a PLY file"), std::string::npos);
  EXPECT_NE(error_of("ply\nformat ascii 1.0\n").find("no end_header"), std::string::npos);

  Builder b = triangle();
  b.format = Format::kBinaryLittleEndian;
  std::string bytes = b.bytes();
  EXPECT_NE(error_of(bytes.substr(0, bytes.size() - 5)).find("file is truncated in face 0"),
            std::string::npos);
  EXPECT_NE(error_of(bytes.substr(0, bytes.size() - 30)).find("too short"), std::string::npos);

  b = triangle();
  b.claimed_vertices = 2147483648L;  // 2^31: must fail before allocating
  EXPECT_NE(error_of(b.bytes()).find("header declares 2147483648 vertex elements"),
            std::string::npos);

  b = triangle();
  b.faces = {{0, 1, 7}};
  EXPECT_NE(error_of(b.bytes()).find("face 0 refers to vertex 7, but there are 3 vertices"),
            std::string::npos);
  b.faces = {{0, -1, 2}};
  EXPECT_NE(error_of(b.bytes()).find("face 0 refers to vertex -1"), std::string::npos);
  // An ASCII index beyond every integer type is reported in full (the fuzzer found it being
  // converted to long long, which is undefined).
  const std::string huge_index =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 22222222222222222222222222222222222\n";
  EXPECT_NE(error_of(huge_index).find("face 0 refers to vertex 222222222222222"), std::string::npos)
      << error_of(huge_index);

  b = triangle();
  bytes = b.bytes();
  bytes.replace(bytes.find("0.5"), 3, "abc");
  EXPECT_NE(error_of(bytes).find("vertex 0: 'abc' is not a number"), std::string::npos);

  b = triangle();
  bytes = b.bytes();
  bytes.replace(bytes.find("0.5"), 3, "nan");
  EXPECT_NE(error_of(bytes).find("vertex 0 has a non-finite coordinate"), std::string::npos);

  b = triangle();
  b.color_type = "int";
  EXPECT_NE(error_of(b.bytes()).find("unsupported colour type 'int'"), std::string::npos);

  b = triangle();
  bytes = b.bytes();
  bytes.replace(bytes.find("ascii"), 5, "utf16");
  EXPECT_NE(error_of(bytes).find("unknown format 'utf16'"), std::string::npos);
}

TEST(Ply, AsciiRecordsMustHaveTheDeclaredValueCount) {
  Builder b = triangle();
  std::string bytes = b.bytes();
  const auto first_data = bytes.find("end_header\n") + 11;
  const auto eol = bytes.find('\n', first_data);
  std::string extra = bytes;
  extra.insert(eol, " 7");
  EXPECT_NE(error_of(extra).find("vertex 0 has more values than the header declares"),
            std::string::npos);
}

TEST(Ply, WriterRoundTripsThroughTheReader) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("qm3d_ply_write_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (Format f : {Format::kAscii, Format::kBinaryLittleEndian}) {
    WriteData d;
    d.format = f;
    d.double_positions = true;
    d.positions = {{0.1, 0.2, 0.3}, {1, 2, 3}, {-1, 0, 5}};
    d.colors = {{{255, 0, 0}}, {{0, 255, 0}}, {{0, 0, 255}}};
    d.scalar_names = {"distortion", "quality"};
    d.scalars = {0.5f, 0.25f, 0.0f};
    d.triangles = {{0, 1, 2}};
    write(dir / "out.ply", d);
    const Content c = read(dir / "out.ply");
    EXPECT_EQ(c.positions[0][1], 0.2);
    EXPECT_EQ(c.colors[1].g, 1.0);
    EXPECT_EQ(c.face_indices, (std::vector<std::uint32_t>{0, 1, 2}));
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace qm3d::ply
