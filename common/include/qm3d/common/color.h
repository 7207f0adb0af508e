// sRGB -> CIELab -> LAB2000HL, the colour pipeline shared by CMDM and PCQM.
//
// Both reference implementations (MEPP2's CMDM, MEPP-team/PCQM) use exactly this pipeline:
// SPEC-CMDM 1.3 and SPEC-PCQM 1.4 step 5. LAB2000HL (Lissner & Urban, "Toward a unified color
// space for perception-based image processing", IEEE TIP 2012) is defined by lookup tables that
// are read at run time from a data directory; see Lab2000hlTable.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d {

/// A colour in CIELab or in LAB2000HL coordinates (same layout, L first).
struct Lab {
  double L = 0;
  double a = 0;
  double b = 0;
};

/// Inverse sRGB gamma on a channel in [0, 1] (threshold as in both references).
double srgb_to_linear(double c);

/// sRGB in [0, 1] -> CIELab with MATLAB's sRGB matrix and D65 white (0.950456, 1, 1.088754).
Lab srgb_to_cielab(const Rgb& rgb);

/// Chroma sqrt(a^2 + b^2).
double chroma(const Lab& c);

/// Hue difference sqrt(max(0, da^2 + db^2 - dC^2)) between two colours (CMDM paper eq. 1.8,
/// MEPP2 `compute_color_statistics`, PCQM `delta_HUE`).
double hue_difference(const Lab& c1, const Lab& c2);
/// The same with the two colours' chroma(c1), chroma(c2) already computed.
double hue_difference(const Lab& c1, const Lab& c2, double chroma1, double chroma2);

/// The LAB2000HL lookup tables: a 1-D table for lightness and two 257x257 tables for (a, b).
///
/// Files (from MEPP-team/PCQM `resources/`, MPL-2.0): `L_data.txt` (100001 values for
/// L* = 0, 0.001, ..., 100), `RegularGridInit_0_0_1.txt` / `_0_0_2.txt` (the a* and b* integer
/// coordinates of each grid row), `RegularGrid_0_0_1.txt` / `_0_0_2.txt` (a_HL and b_HL).
/// A missing, short or malformed file is a qm3d::InputError / qm3d::FormatError naming the file;
/// there is never a silent all-zero table.
class Lab2000hlTable {
 public:
  static constexpr std::size_t kLightnessSize = 100001;  ///< L* grid 0, 0.001, ..., 100
  static constexpr double kLightnessStep = 0.001;
  static constexpr int kAbMin = -128;  ///< a*, b* grid -128 ... 128
  static constexpr std::size_t kAbSide = 257;

  /// Reads the five table files from `dir`.
  static Lab2000hlTable load(const std::filesystem::path& dir);

  /// The table for `dir`, loaded on first use and shared read-only afterwards (thread-safe).
  static std::shared_ptr<const Lab2000hlTable> shared(const std::filesystem::path& dir);

  /// CIELab -> LAB2000HL: linear interpolation of L (clamped to the last value above 100 and to
  /// the first below 0), bilinear interpolation of (a, b) between floor(x) and floor(x) + 1.
  Lab from_cielab(const Lab& lab) const;

  /// sRGB in [0, 1] -> LAB2000HL.
  Lab from_srgb(const Rgb& rgb) const { return from_cielab(srgb_to_cielab(rgb)); }

  double lightness(double l_star) const;

  const std::filesystem::path& directory() const { return directory_; }

 private:
  Lab2000hlTable() = default;
  double ab_value(const std::vector<double>& grid, double a, double b) const;

  std::filesystem::path directory_;
  std::vector<double> lightness_;  // kLightnessSize values
  std::vector<double> a_hl_;       // [(a + 128) * 257 + (b + 128)]
  std::vector<double> b_hl_;
};

/// The table directory to use: `explicit_dir` if not empty, else $QM3D_DATA_DIR if set, else
/// PREFIX/share/qm3d/lab2000hl when the running program is an installed PREFIX/bin/<program>
/// and the tables are there, else the directory fixed at configure time (QM3D_DEFAULT_DATA_DIR).
std::filesystem::path resolve_data_dir(const std::filesystem::path& explicit_dir = {});

/// Converts every colour of a set to LAB2000HL.
std::vector<Lab> to_lab2000hl(const std::vector<Rgb>& colors, const Lab2000hlTable& table);

}  // namespace qm3d
