#include "qm3d/common/color.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <system_error>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"

#ifndef QM3D_DEFAULT_DATA_DIR
#define QM3D_DEFAULT_DATA_DIR ""
#endif

namespace qm3d {
namespace {

// Inverse sRGB companding threshold used by both references (rgb_to_lab.h, PCQM main.cpp).
constexpr double kSrgbLinearThreshold = 0.0404482362771076;

// MATLAB's linear sRGB -> XYZ matrix, as in both references.
constexpr double kSrgbToXyz[3][3] = {{0.412396, 0.357583, 0.180493},
                                     {0.212586, 0.71517, 0.0722005},
                                     {0.0192972, 0.119184, 0.950497}};

// MATLAB's D65 white point, as in both references.
constexpr double kWhiteX = 0.950456;
constexpr double kWhiteY = 1.0;
constexpr double kWhiteZ = 1.088754;

// CIE f(t): cube root above (6/29)^3 ~ 0.008856, linear below.
double lab_f(double t) {
  if (t > 0.008856) return std::cbrt(t);
  return (841.0 / 108.0) * t + 4.0 / 29.0;
}

// Reads exactly `expected` numbers, one per line, from `path`.
std::vector<double> read_table_file(const std::filesystem::path& path, std::size_t expected) {
  std::string text;
  try {
    text = read_file_bytes(path, std::uintmax_t(64) << 20);
  } catch (const InputError& e) {
    throw InputError("LAB2000HL table " + path.string() +
                     ": cannot open (set --data-dir or QM3D_DATA_DIR to the directory holding "
                     "L_data.txt and RegularGrid*.txt)");
  }
  std::vector<double> values;
  values.reserve(expected);
  std::size_t line_no = 0;
  for (std::size_t pos = 0; pos < text.size();) {
    const std::size_t eol = std::min(text.find('\n', pos), text.size());
    ++line_no;
    std::size_t begin = pos, end = eol;
    pos = eol + 1;
    while (begin < end && std::isspace(static_cast<unsigned char>(text[begin]))) ++begin;
    while (end > begin && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
    if (begin == end) continue;  // blank lines (e.g. a trailing one) are fine
    if (values.size() == expected) {
      throw FormatError("LAB2000HL table " + path.string() + ": more than " +
                        std::to_string(expected) + " values (line " + std::to_string(line_no) +
                        ")");
    }
    double v = 0;
    if (text[begin] == '+') ++begin;
    const auto res = std::from_chars(text.data() + begin, text.data() + end, v);
    if (res.ec != std::errc() || res.ptr != text.data() + end || !std::isfinite(v)) {
      throw FormatError("LAB2000HL table " + path.string() + ": line " + std::to_string(line_no) +
                        " is not a number: '" + text.substr(begin, end - begin) + "'");
    }
    values.push_back(v);
  }
  if (values.size() != expected) {
    throw FormatError("LAB2000HL table " + path.string() + ": expected " +
                      std::to_string(expected) + " values, found " + std::to_string(values.size()));
  }
  return values;
}

int grid_coordinate(double v, const std::filesystem::path& path, std::size_t row) {
  const double lo = Lab2000hlTable::kAbMin;
  const double hi = Lab2000hlTable::kAbMin + static_cast<double>(Lab2000hlTable::kAbSide) - 1;
  if (v != std::floor(v) || v < lo || v > hi) {
    throw FormatError("LAB2000HL table " + path.string() + ": row " + std::to_string(row + 1) +
                      " holds " + std::to_string(v) + ", not an integer in [-128, 128]");
  }
  return static_cast<int>(v) - Lab2000hlTable::kAbMin;
}

}  // namespace

namespace {

double srgb_to_linear_formula(double c) {
  return c > kSrgbLinearThreshold ? std::pow((c + 0.055) / 1.055, 2.4) : c / 12.92;
}

// The formula's value at each 8-bit channel k / 255.0 (how the readers convert 8-bit colours),
// computed once: a channel equal, bit for bit, to one of these inputs gets the very value the
// formula gives; any other channel goes through the formula.
struct LinearChannelTable {
  double in[256];
  double out[256];
  LinearChannelTable() {
    for (int k = 0; k < 256; ++k) {
      in[k] = k / 255.0;
      out[k] = srgb_to_linear_formula(in[k]);
    }
  }
};

const LinearChannelTable& linear_channel_table() {
  static const LinearChannelTable table;
  return table;
}

}  // namespace

double srgb_to_linear(double c) {
  if (c >= 0.0 && c <= 1.0) {
    const LinearChannelTable& t = linear_channel_table();
    const int k = static_cast<int>(c * 255.0 + 0.5);
    if (t.in[k] == c) return t.out[k];
  }
  return srgb_to_linear_formula(c);
}

Lab srgb_to_cielab(const Rgb& rgb) {
  const double r = srgb_to_linear(rgb.r);
  const double g = srgb_to_linear(rgb.g);
  const double b = srgb_to_linear(rgb.b);
  const double x = kSrgbToXyz[0][0] * r + kSrgbToXyz[0][1] * g + kSrgbToXyz[0][2] * b;
  const double y = kSrgbToXyz[1][0] * r + kSrgbToXyz[1][1] * g + kSrgbToXyz[1][2] * b;
  const double z = kSrgbToXyz[2][0] * r + kSrgbToXyz[2][1] * g + kSrgbToXyz[2][2] * b;
  const double fy = lab_f(y / kWhiteY);
  return Lab{116.0 * fy - 16.0, 500.0 * (lab_f(x / kWhiteX) - fy),
             200.0 * (fy - lab_f(z / kWhiteZ))};
}

double chroma(const Lab& c) { return std::sqrt(c.a * c.a + c.b * c.b); }

double hue_difference(const Lab& c1, const Lab& c2) {
  return hue_difference(c1, c2, chroma(c1), chroma(c2));
}

double hue_difference(const Lab& c1, const Lab& c2, double chroma1, double chroma2) {
  const double dc = chroma1 - chroma2;
  const double dh2 = std::pow(c1.a - c2.a, 2) + std::pow(c1.b - c2.b, 2) - std::pow(dc, 2);
  return dh2 < 0 ? 0.0 : std::sqrt(dh2);
}

Lab2000hlTable Lab2000hlTable::load(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    throw InputError("LAB2000HL table directory " + dir.string() +
                     ": not found (set --data-dir or QM3D_DATA_DIR)");
  }
  Lab2000hlTable t;
  t.directory_ = dir;
  t.lightness_ = read_table_file(dir / "L_data.txt", kLightnessSize);
  const std::size_t cells = kAbSide * kAbSide;
  const auto a_coord = read_table_file(dir / "RegularGridInit_0_0_1.txt", cells);
  const auto b_coord = read_table_file(dir / "RegularGridInit_0_0_2.txt", cells);
  const auto a_val = read_table_file(dir / "RegularGrid_0_0_1.txt", cells);
  const auto b_val = read_table_file(dir / "RegularGrid_0_0_2.txt", cells);
  t.a_hl_.assign(cells, 0.0);
  t.b_hl_.assign(cells, 0.0);
  std::vector<char> seen(cells, 0);
  const std::filesystem::path a_path = dir / "RegularGridInit_0_0_1.txt";
  const std::filesystem::path b_path = dir / "RegularGridInit_0_0_2.txt";
  for (std::size_t row = 0; row < cells; ++row) {
    const int ai = grid_coordinate(a_coord[row], a_path, row);
    const int bi = grid_coordinate(b_coord[row], b_path, row);
    const std::size_t cell = static_cast<std::size_t>(ai) * kAbSide + static_cast<std::size_t>(bi);
    if (seen[cell]) {
      throw FormatError("LAB2000HL table " + a_path.string() + ": grid point (" +
                        std::to_string(ai + kAbMin) + ", " + std::to_string(bi + kAbMin) +
                        ") appears twice");
    }
    seen[cell] = 1;
    t.a_hl_[cell] = a_val[row];
    t.b_hl_[cell] = b_val[row];
  }
  return t;
}

std::shared_ptr<const Lab2000hlTable> Lab2000hlTable::shared(const std::filesystem::path& dir) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const Lab2000hlTable>> cache;
  std::error_code ec;
  auto key_path = std::filesystem::weakly_canonical(dir, ec);
  const std::string key = ec ? dir.string() : key_path.string();
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  auto table = std::make_shared<const Lab2000hlTable>(load(dir));
  cache.emplace(key, table);
  return table;
}

double Lab2000hlTable::lightness(double l_star) const {
  // Same result as the references' std::upper_bound over the grid i * 0.001, found in O(1).
  const std::size_t n = lightness_.size();
  auto grid = [](std::size_t i) { return static_cast<double>(i) * kLightnessStep; };
  if (!(l_star >= 0.0)) return lightness_.front();  // below the table (and NaN): first value
  // a first guess (a product, not a division: the loops below settle the position)
  std::size_t pos = static_cast<std::size_t>(std::min(l_star * (1.0 / kLightnessStep), double(n)));
  while (pos < n && grid(pos) <= l_star) ++pos;
  while (pos > 0 && grid(pos - 1) > l_star) --pos;
  if (pos >= n) return lightness_.back();  // above 100: the last value, as the references do
  const double x0 = grid(pos - 1);
  const double x1 = grid(pos);
  return lightness_[pos - 1] +
         ((l_star - x0) / (x1 - x0)) * (lightness_[pos] - lightness_[pos - 1]);
}

namespace {

/// A point's bilinear cell in the (a, b) tables and its weights, shared by the a_HL and b_HL
/// look-ups: floor(x) and floor(x) + 1, written as in both references. Coordinates outside the
/// table (impossible for sRGB input) are clamped to its last cell.
struct AbCell {
  std::size_t i00, i10, i01, i11;  // (x0, y0), (x1, y0), (x0, y1), (x1, y1)
  double x1x, y1y, xx0, yy0, norm;
};

AbCell ab_cell(double a, double b) {
  constexpr int kMin = Lab2000hlTable::kAbMin;
  constexpr std::size_t kSide = Lab2000hlTable::kAbSide;
  const double max_lo = kMin + static_cast<double>(kSide) - 2;
  const int x0 = static_cast<int>(std::clamp(std::floor(a), double(kMin), max_lo));
  const int y0 = static_cast<int>(std::clamp(std::floor(b), double(kMin), max_lo));
  const int x1 = x0 + 1;
  const int y1 = y0 + 1;
  auto at = [](int x, int y) {
    return static_cast<std::size_t>(x - kMin) * kSide + static_cast<std::size_t>(y - kMin);
  };
  const double x1x0 = x1 - x0, y1y0 = y1 - y0;
  return {at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1),         x1 - a,
          y1 - b,     a - x0,     b - y0,     1.0 / (x1x0 * y1y0)};
}

double ab_interpolate(const std::vector<double>& grid, const AbCell& c) {
  return c.norm * (grid[c.i00] * c.x1x * c.y1y + grid[c.i10] * c.xx0 * c.y1y +
                   grid[c.i01] * c.x1x * c.yy0 + grid[c.i11] * c.xx0 * c.yy0);
}

}  // namespace

double Lab2000hlTable::ab_value(const std::vector<double>& grid, double a, double b) const {
  return ab_interpolate(grid, ab_cell(a, b));
}

Lab Lab2000hlTable::from_cielab(const Lab& lab) const {
  const AbCell cell = ab_cell(lab.a, lab.b);
  return Lab{lightness(lab.L), ab_interpolate(a_hl_, cell), ab_interpolate(b_hl_, cell)};
}

std::filesystem::path resolve_data_dir(const std::filesystem::path& explicit_dir) {
  if (!explicit_dir.empty()) return explicit_dir;
  if (const char* env = std::getenv("QM3D_DATA_DIR"); env != nullptr && *env != '\0') {
    return std::filesystem::path(env);
  }
  if (const auto share = installed_share_dir(); !share.empty()) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(share / "lab2000hl" / "L_data.txt", ec)) {
      return share / "lab2000hl";
    }
  }
  return std::filesystem::path(QM3D_DEFAULT_DATA_DIR);
}

std::vector<Lab> to_lab2000hl(const std::vector<Rgb>& colors, const Lab2000hlTable& table) {
  std::vector<Lab> out(colors.size());
  for (std::size_t i = 0; i < colors.size(); ++i) out[i] = table.from_srgb(colors[i]);
  return out;
}

}  // namespace qm3d
