#include "qm3d/common/ply.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "comma_locale.h"
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
  EXPECT_NE(error_of(huge_index)
                .find("face 0 (line 13): item of 'vertex_indices' "
                      "22222222222222222222222222222222222 is out of range for int"),
            std::string::npos)
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

// A two-vertex ASCII PLY whose second vertex (line 12, 13 with 'q') is `0 0 0 VALUE 0 0`, the
// colours of type `type`, or `0 0 0 1 2 3 VALUE` with VALUE an extra property 'q' of type `type`.
std::string ascii_value(const std::string& type, const std::string& value, bool as_colour) {
  const std::string colour_type = as_colour ? type : "uchar";
  std::string h =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nproperty " +
      colour_type + " red\nproperty " + colour_type + " green\nproperty " + colour_type + " blue\n";
  if (!as_colour) h += "property " + type + " q\n";
  h += "end_header\n";
  return as_colour ? h + "0 0 0 1 2 3\n0 0 0 " + value + " 0 0\n"
                   : h + "0 0 0 1 2 3 0\n0 0 0 1 2 3 " + value + "\n";
}

// Issue 24: `uchar 300`, `-1`, `ushort 70000` were accepted (300 became a colour of 1.18).
TEST(PlyHostile, AsciiIntegersOutsideTheirDeclaredTypeAreErrors) {
  const std::pair<const char*, const char*> bad[] = {
      {"uchar", "300"},    {"uchar", "-1"},       {"uchar", "256"},       {"ushort", "70000"},
      {"ushort", "-1"},    {"char", "128"},       {"char", "-129"},       {"short", "32768"},
      {"short", "-32769"}, {"int", "2147483648"}, {"uint", "4294967296"}, {"uint", "-1"}};
  for (const auto& [type, value] : bad) {
    for (const bool as_colour : {true, false}) {
      const std::string t = type;
      if (as_colour && t != "uchar" && t != "ushort") continue;  // not colour types
      SCOPED_TRACE(t + " " + value + (as_colour ? " colour" : " extra"));
      const std::string e = error_of(ascii_value(type, value, as_colour));
      EXPECT_NE(e.find(std::string("t.ply: PLY: vertex 1 (line ") + (as_colour ? "12" : "13") +
                       "): property '" + (as_colour ? "red" : "q") + "' " + value +
                       " is out of range for " + type),
                std::string::npos)
          << e;
    }
  }
  // The limits themselves are values of their type.
  EXPECT_EQ(error_of(ascii_value("uchar", "255", true)), "");
  EXPECT_EQ(error_of(ascii_value("ushort", "65535", true)), "");
  for (const auto& [type, value] : {std::pair<const char*, const char*>{"char", "-128"},
                                    {"short", "-32768"},
                                    {"int", "-2147483648"},
                                    {"uint", "4294967295"}}) {
    EXPECT_EQ(error_of(ascii_value(type, value, false)), "") << type;
  }
}

TEST(PlyHostile, AsciiListLengthsAndIndicesOutsideTheirTypeAreErrors) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n";
  std::string e = error_of(head + "256 0 1 2\n");
  EXPECT_NE(e.find("face 0 (line 13): list length of 'vertex_indices' 256 is out of range for "
                   "uchar (0..255)"),
            std::string::npos)
      << e;
  e = error_of(head + "3 0 -1 2\n");
  EXPECT_NE(e.find("face 0 (line 13): item of 'vertex_indices' -1 is out of range for uint"),
            std::string::npos)
      << e;
  e = error_of(head + "3 0 1.5 2\n");
  EXPECT_NE(e.find("'1.5' is not an integer (uint)"), std::string::npos) << e;
}

Builder float_colours(double odd_value) {
  Builder b;
  b.color_type = "float";
  for (int i = 0; i < 200; ++i) b.vertices.push_back({double(i), double(i % 7), 0, 0.5, 0.25, 1});
  b.vertices[3][4] = odd_value;
  return b;
}

// Issue 24: one value of 1.0000001 switched the whole file to 0..255 without a word.
TEST(PlyHostile, FloatColourScaleIsReportedWhenFewValuesDecideAndCanBeChosen) {
  const std::string bytes = float_colours(1.0000001).bytes();
  const Content automatic = parse(bytes, "t.ply");
  EXPECT_EQ(automatic.colors[0].r, 1 / 255.0);  // MEPP2's rule kept by default: 0.5 -> 1/255
  ASSERT_EQ(automatic.warnings.size(), 1u);
  EXPECT_EQ(automatic.warnings[0],
            "t.ply: 1 of 600 colour values above 1 (max 1.0000001): read as 0..255 like the "
            "reference; --colour-scale unit reads them as 0..1");

  const Content unit = parse(bytes, "t.ply", AsciiFloat::kDouble, ColourScale::kUnit);
  EXPECT_EQ(unit.colors[0].r, 0.5);
  EXPECT_EQ(unit.colors[3].g, 1.0);  // clamped
  ASSERT_EQ(unit.warnings.size(), 1u);
  EXPECT_NE(unit.warnings[0].find("clamped to 1"), std::string::npos);

  const Content byte =
      parse(float_colours(0.5).bytes(), "t.ply", AsciiFloat::kDouble, ColourScale::kByte);
  EXPECT_EQ(byte.colors[0].b, 1 / 255.0);
  EXPECT_TRUE(byte.warnings.empty());
}

TEST(PlyHostile, ClearColourScalesGiveNoWarning) {
  EXPECT_TRUE(parse(float_colours(0.75).bytes(), "t.ply").warnings.empty());  // all 0..1
  Builder b = float_colours(0.75);
  for (auto& v : b.vertices) v[3] = 200;  // a 0..255 file: a third of its values above 1
  const Content c = parse(b.bytes(), "t.ply");
  EXPECT_TRUE(c.warnings.empty());
  EXPECT_EQ(c.colors[0].r, 200 / 255.0);
}

Builder far_cloud(const std::string& pos_type, Format format, double offset) {
  Builder b;
  b.format = format;
  b.pos_type = pos_type;
  b.faces.clear();
  for (int i = 0; i < 100; ++i) {  // a 1 x 1 grid of 10 x 10 points, spacing 0.1
    b.vertices.push_back({offset + 0.1 * (i % 10), 0.1 * (i / 10), 0, 1, 2, 3});
  }
  return b;
}

// Issue 24: coordinates declared float at an offset of 1e7 lose their detail (the float32 step
// there is 1, the points are 0.1 apart) without a word.
TEST(PlyHostile, Float32RoundingLargeAgainstTheSpacingIsAWarning) {
  const Content binary =
      parse(far_cloud("float", Format::kBinaryLittleEndian, 1e7).bytes(), "t.ply");
  ASSERT_EQ(binary.warnings.size(), 1u);
  EXPECT_NE(binary.warnings[0].find("t.ply: coordinates stored as float32: at |coordinate| "
                                    "10000001 the float32 step is 1, more than 1/8 of the "
                                    "typical point spacing"),
            std::string::npos)
      << binary.warnings[0];
  // ASCII read as declared (clouds) rounds too; the double parse (meshes) keeps the detail.
  const std::string ascii = far_cloud("float", Format::kAscii, 1e7).bytes();
  EXPECT_EQ(parse(ascii, "t.ply", AsciiFloat::kAsDeclared).warnings.size(), 1u);
  EXPECT_TRUE(parse(ascii, "t.ply", AsciiFloat::kDouble).warnings.empty());
  // Declared double, or near the origin: nothing to say.
  EXPECT_TRUE(parse(far_cloud("double", Format::kBinaryLittleEndian, 1e7).bytes(), "t.ply")
                  .warnings.empty());
  EXPECT_TRUE(
      parse(far_cloud("float", Format::kBinaryLittleEndian, 0).bytes(), "t.ply").warnings.empty());
  // At 1e5 the step (1/128) is below 1/8 of the spacing (0.1 x 1.41 / 10): still fine.
  EXPECT_TRUE(parse(far_cloud("float", Format::kBinaryLittleEndian, 1e5).bytes(), "t.ply")
                  .warnings.empty());
}

// Issue 24: after setlocale(LC_ALL, "de_DE.UTF-8") (Python's locale.setlocale) strtod stopped at
// the '.', so ASCII PLY clouds failed to parse.
TEST(PlyHostile, NumbersAreParsedAndWrittenTheSameInACommaDecimalLocale) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("qm3d_ply_locale_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    QM3D_WITH_COMMA_LOCALE(comma, dir);
    Builder b = triangle();
    for (AsciiFloat f : {AsciiFloat::kDouble, AsciiFloat::kAsDeclared}) {
      const Content c = parse(b.bytes(), "t.ply", f);
      EXPECT_EQ(c.positions[0][0], 0.5);
      EXPECT_EQ(c.positions[0][1], -1.25);
    }
    b.color_type = "float";
    b.vertices[0][3] = 0.75;
    EXPECT_EQ(parse(b.bytes(), "t.ply").colors[0].r, std::floor(0.75 + 0.5) / 255.0);
    WriteData d;
    d.format = Format::kAscii;
    d.positions = {{0.5, 1.25, 2}};
    d.scalar_names = {"distortion"};
    d.scalars = {0.25f};
    write(dir / "out.ply", d);
    std::ifstream in(dir / "out.ply");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("0.5 1.25 2 0.25\n"), std::string::npos) << text;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace qm3d::ply
