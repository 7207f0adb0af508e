// What every reader (PLY, OBJ, OFF, PCD) shares: how colours stored as numbers are scaled, the
// warning that float32 coordinates lost detail, and number parsing that does not depend on the
// C locale (after setlocale(LC_ALL, "de_DE.UTF-8") strtod stops at the '.').
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d {

/// The range of colours stored as numbers with no range of their own (OBJ, OFF, PLY float or
/// double). Integer-typed colours (PLY uchar / ushort, PCD packed rgb) always use their type's.
enum class ColourScale {
  /// The reference's rule (MEPP2, SPEC-CMDM §1.2): 0..255 when any value of the file is above 1,
  /// else 0..1. A decision resting on few values is reported (colour_conversion).
  kAuto,
  kUnit,  ///< 0..1; values above 1 are clamped to 1 (and counted in a warning)
  kByte,  ///< 0..255 (c -> floor(c + 0.5) / 255, as MEPP2 converts)
};

/// "auto", "unit" or "byte" (what --colour-scale and colour_scale= take); std::invalid_argument
/// naming the value otherwise.
ColourScale parse_colour_scale(const std::string& name);
const char* colour_scale_name(ColourScale scale);

/// How a file is read, beyond its content.
struct ReadOptions {
  ColourScale colour_scale = ColourScale::kAuto;
  /// A texture map that replaces the map of every material of a textured mesh (mmetric's
  /// --inputMapA / --inputMapB; qm3d's --ref-texture / --dist-texture): every face with texture
  /// coordinates takes its colour from it. Empty: the file's own materials.
  std::filesystem::path texture;
  /// How the user gives `texture` (named in the warning about a mesh with texture coordinates
  /// but no usable texture).
  std::string texture_option = "--ref-texture / --dist-texture";
};

/// A cloud as read from a file with its reader's warnings (what Input keeps).
struct CloudData {
  ColoredCloud cloud;
  std::vector<std::string> warnings;
  /// The file's normals (PLY nx, ny, nz), one per point as stored; empty when it has none.
  std::vector<Vec3> normals;
};

/// What a reader saw of a file's float colour values, to choose their scale.
struct ColourValues {
  std::size_t count = 0;      ///< values seen (3 per colour)
  std::size_t above_one = 0;  ///< values > 1
  double max = 0;

  void add(double v) {
    ++count;
    if (v > 1.0) ++above_one;
    if (v > max) max = v;
  }
};

/// The conversion of one file's float colour values to [0, 1].
struct ColourConversion {
  bool from_255 = false;
  /// Set when the decision deserves a line (see colour_conversion).
  std::optional<std::string> warning;

  /// c in the file's scale -> [0, 1].
  double operator()(double c) const;
};

/// The scale of a file's float colours under `scale`. A warning naming `file` is given when
/// kAuto reads the file as 0..255 on thin evidence: fewer than 1 % of its values (kFewAboveOne)
/// are above 1, or none is above 2 (kClearlyByte); and when kUnit clamps values above 1.
ColourConversion colour_conversion(const ColourValues& values, ColourScale scale,
                                   const std::string& file);

/// The float32 step at |coordinate| `largest` when it is more than 1/8 of `spacing` (the content
/// has lost detail in float32: float32_rounding_warning's rule), else nullopt.
std::optional<double> large_float32_step(double largest, double spacing);

/// The warning for coordinates stored as float32 whose rounding is large against the points'
/// spacing, or nothing. "Large": the float32 step (ulp) at the largest |coordinate| exceeds 1/8
/// of the typical spacing, estimated as bounding-box diagonal / sqrt(N) (N points on a
/// surface). Cheap (one pass), deterministic, and silent for N < 2 or a zero-size box.
std::optional<std::string> float32_rounding_warning(const std::vector<Vec3>& positions,
                                                    const std::string& file);
/// The same for positions held as float32 (the same warning as for them widened to double).
std::optional<std::string> float32_rounding_warning(
    const std::vector<std::array<float, 3>>& positions, const std::string& file);

/// Parses a whole token as a number (a leading '+' allowed) whatever the C locale; false when
/// the token is not a number or is out of the type's range. "nan" and "inf" are numbers.
bool parse_number(std::string_view token, double& value);
bool parse_number(std::string_view token, float& value);

/// The number as C++ writes it in the "C" locale (%.17g-like shortest round trip), for messages.
std::string number_text(double v);

}  // namespace qm3d
