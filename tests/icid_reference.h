// The iCID reference table (shared/data/reference/icid/icid_reference.csv, README there): its
// rows, their options as qm3d's, and the comparison rule of issue 40: the score and m1..m7 within
// 1e-10 relative. Values the reference itself gets from rounding alone (identical images: m_k
// ~1e-17, IAM=NONE's score -4.4e-14) carry no digits to compare: an absolute floor of
// kIcidAbsoluteFloor, the rounding of a mean of ~50000 window sums of order 1, covers them.
// Header-only, shared by the library and CLI tests (python/tests/test_icid.py applies the same
// rules).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "test_paths.h"

namespace qm3d::test {

constexpr double kIcidRelativeTolerance = 1e-10;
constexpr double kIcidAbsoluteFloor = 1e-13;

struct IcidCase {
  std::string name;     ///< "synth_blur", "blob4_geonoise:view03", "blob4_geonoise:mean18"
  std::string image_a;  ///< relative to icid_dir(); "view_*" for a mean row
  std::string image_b;
  std::string options;             ///< "default", "Intent=chromatic", "IAM=NONE", ...
  std::array<double, 8> values{};  ///< icid, m1 .. m7

  bool is_mean() const { return name.find(":mean") != std::string::npos; }
  /// The set of a view or mean row ("blob4_geonoise"), else empty.
  std::string set() const {
    const auto colon = name.find(':');
    return colon == std::string::npos ? std::string() : name.substr(0, colon);
  }
};

/// How the table's Octave 7.3 run read a PNG, where it differs from MATLAB's (and qm3d's) imread.
/// Octave's __magick_read__ (libinterp/corefcn/__magick_read__.cc, get_depth) takes an 8-bit
/// image whose red channel GraphicsMagick finds 1 bit deep (every red value 0 or 255; its checks
/// of the cyan, gray and opacity channels are the red one again and the alpha, opaque or 0/255
/// here) for a binary image and returns a logical array: each channel value v becomes v > 0.
/// iCID.m divides only uint8 images by 255, so the logical 0/1 reach colorspace.m, which divides
/// every non-double input by 255: the pixels become 0 or 1/255, near black. The one row of the
/// table this decides is synth_colour_bars (7 saturated bars, every channel 0 or 255): with it,
/// its m1 = 3.8150062714178243e-07 comes out to the last bit and every value of its 6 rows within
/// 1e-10 relative but m6 and m7 of IAM=NONE (5e-10 and 1.7e-10 relative, 9e-15 and 2.2e-14
/// absolute: within kIcidAbsoluteFloor; not traced). As MATLAB reads the files, m1 = 0.035. qm3d
/// reads images as MATLAB does (uint8 / 255); the tests apply this rule to the table's images (it
/// changes no other image of the table).
inline bool octave_reads_as_binary(const std::vector<std::uint8_t>& rgb) {
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    if (rgb[i] != 0 && rgb[i] != 255) return false;
  }
  return true;
}

/// The pixels as the table's Octave run used them (octave_reads_as_binary), in place.
inline void read_as_octave(std::vector<std::uint8_t>& rgb) {
  if (!octave_reads_as_binary(rgb)) return;
  for (std::uint8_t& v : rgb) v = v > 0 ? 1 : 0;
}

/// The rows `qm3d image` cannot reproduce from the files (it reads them as MATLAB does; the
/// library's and Python's tests check these rows on the images as Octave read them).
inline bool icid_row_read_differently(const std::string& name) {
  return name == "synth_colour_bars";
}

inline std::filesystem::path icid_dir() { return reference_dir() / "icid"; }

inline std::vector<IcidCase> icid_cases() {
  std::ifstream in(icid_dir() / "icid_reference.csv");
  std::vector<IcidCase> cases;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<std::string> f;
    std::stringstream s(line);
    for (std::string field; std::getline(s, field, ';');) f.push_back(field);
    if (f.size() != 12) continue;
    IcidCase c{f[0], f[1], f[2], f[3], {}};
    for (int k = 0; k < 8; ++k) c.values[k] = std::stod(f[4 + k]);
    cases.push_back(c);
  }
  return cases;
}

/// Whether `got` agrees with the reference's `want` (the rule above).
inline bool icid_close(double got, double want) {
  return std::abs(got - want) <= kIcidRelativeTolerance * std::abs(want) + kIcidAbsoluteFloor;
}

/// The `qm3d image` options of a row's options column.
inline std::vector<std::string> icid_cli_options(const std::string& options) {
  if (options == "Intent=hue-preserving") return {"--intent", "hue-preserving"};
  if (options == "Intent=chromatic") return {"--intent", "chromatic"};
  if (options == "IAM=NONE") return {"--no-iam"};
  if (options == "Omit_Maps67=true") return {"--omit-maps67"};
  if (options == "Downsampling=false") return {"--no-downsampling"};
  return {};
}

}  // namespace qm3d::test
