// PLY reading and writing (ASCII, binary little and big endian), in the manner of happly: every
// scalar type, every error prefixed with the file name and specific.
//
// Why our own reader: to match the reference scores the positions of an ASCII PLY must be parsed
// at double precision whatever type the header declares for meshes (MEPP2 does so) and at the
// declared precision for clouds (MEPP-team/PCQM does so), colours may be uchar,
// ushort or float and named red/green/blue, r/g/b or diffuse_*, and a header that claims more
// elements than the file can hold must fail before anything is allocated.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/reading.h"
#include "qm3d/common/types.h"

namespace qm3d::ply {

enum class Format { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

enum class ScalarType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

struct Property {
  std::string name;
  ScalarType type = ScalarType::kFloat32;  ///< value type (list items for a list)
  bool is_list = false;
  ScalarType count_type = ScalarType::kUint8;  ///< list length type
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

struct Header {
  Format format = Format::kAscii;
  /// The texture maps of `comment TextureFile NAME` lines (MeshLab's, MEPP2's and mmetric's
  /// convention), in order; NAME is the rest of the line, relative to the PLY's folder.
  std::vector<std::string> texture_files;
  std::vector<Element> elements;
  std::size_t data_offset = 0;  ///< byte offset of the first data byte
};

/// How the colour channels of the vertex element were stored.
enum class ColorEncoding { kNone, kUint8, kUint16, kFloat };

/// What qm3d takes from a PLY file.
struct Content {
  std::vector<Vec3> positions;
  /// Colours in [0, 1] at double precision (uchar / 255, ushort / 65535; float colours as the
  /// ColourScale says: by default kept, or read as 0..255 when any exceeds 1, as MEPP2 does).
  /// Empty when there are none.
  std::vector<Rgb> colors;
  ColorEncoding color_encoding = ColorEncoding::kNone;
  /// Vertex normals (nx, ny, nz of any scalar type, values as stored: not normalised, NaN
  /// kept); empty when the vertex element lacks one of them.
  std::vector<Vec3> normals;
  /// Faces as polygons in compressed form: face f has vertices
  /// face_indices[face_offsets[f] .. face_offsets[f + 1]). face_offsets has #F + 1 entries.
  std::vector<std::uint32_t> face_offsets{0};
  std::vector<std::uint32_t> face_indices;
  /// Texture coordinates (u, v), one per vertex, from the vertex properties texture_u /
  /// texture_v, s / t or u / v (the first pair present); empty when there are none.
  std::vector<std::array<double, 2>> uvs;
  /// Per-corner texture coordinates from the face list property `texcoord` (u0 v0 u1 v1 ... for
  /// the face's corners, in face_indices order): 2 values per corner; empty when there are none.
  std::vector<double> face_texcoords;
  /// Each face's `texnumber` (its index into texture_files); empty when there is none.
  std::vector<std::int64_t> face_texnumbers;
  std::vector<std::string> texture_files;  ///< Header::texture_files
  /// What the reader could not keep silent: a colour scale chosen on thin evidence, coordinates
  /// rounded to float32 against their spacing (reading.h). Each line names the file.
  std::vector<std::string> warnings;
};

/// Parses the header of `bytes` (the file's content); `name` is used in error messages. When
/// `bytes` is only the beginning of the file, `file_size` (the whole file's) is what the declared
/// element counts are checked against.
Header parse_header(const std::string& bytes, const std::string& name,
                    std::optional<std::uint64_t> file_size = std::nullopt);

/// How ASCII values of properties declared `float` are parsed (binary files hold the declared
/// type anyway).
enum class AsciiFloat {
  /// At double precision whatever the declared type: what MEPP2 does for meshes.
  kDouble,
  /// As float32, then widened: what MEPP-team/PCQM's tinyply does for clouds (SPEC-PCQM §9.1);
  /// the value can differ from the double parse by half a float ulp.
  kAsDeclared,
};

/// Reads the vertex positions, colours and faces of a PLY file. Throws InputError / FormatError
/// naming the file on any problem (truncation, bad values, an ASCII integer outside its declared
/// type's range (`uchar 300`, naming element, line and value), face index out of range, ...).
/// Numbers are parsed the same whatever the C locale.
Content read(const std::filesystem::path& path, AsciiFloat ascii_float = AsciiFloat::kDouble,
             ColourScale colour_scale = ColourScale::kAuto);

/// Reads PLY content already in memory.
Content parse(const std::string& bytes, const std::string& name,
              AsciiFloat ascii_float = AsciiFloat::kDouble,
              ColourScale colour_scale = ColourScale::kAuto);

/// What to write: positions, optional 8-bit colours, optional float scalar per vertex, faces.
struct WriteData {
  std::vector<Vec3> positions;
  std::vector<std::array<std::uint8_t, 3>> colors;  ///< empty or one per vertex
  /// Float vertex properties that all hold `scalars` (e.g. "distortion", MeshLab's "quality",
  /// CloudCompare's "scalar_distortion"); empty = none.
  std::vector<std::string> scalar_names;
  std::vector<float> scalars;  ///< one per vertex when scalar_names is not empty
  /// Further float vertex properties, each with its own values (one per vertex), after those.
  std::vector<std::pair<std::string, std::vector<float>>> extra_scalars;
  std::vector<Triangle> triangles;
  Format format = Format::kBinaryLittleEndian;
  bool double_positions = false;  ///< write x, y, z as double instead of float
};

/// Writes a PLY file atomically (never a partial file). Throws InputError on failure.
void write(const std::filesystem::path& path, const WriteData& data);

}  // namespace qm3d::ply
