#include "qm3d/common/reading.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <system_error>

namespace qm3d {
namespace {

/// kAuto's 0..255 decision is reported when fewer than this share of the values is above 1 ...
constexpr double kFewAboveOne = 0.01;
/// ... or when no value reaches this (values barely above 1 are the overshoot of a 0..1 file as
/// often as the darkest values of a 0..255 one).
constexpr double kClearlyByte = 2.0;
/// The float32 step is "large" above this fraction of the point spacing.
constexpr double kLargeStepOfSpacing = 1.0 / 8.0;

std::string count_text(const ColourValues& v) {
  return std::to_string(v.above_one) + " of " + std::to_string(v.count) +
         " colour values above 1 (max " + number_text(v.max) + ")";
}

// from_chars reports values beyond the type's range (1e400, 1e-50 as float) instead of
// returning inf or a rounded subnormal as strtod does; those are parsed at long double range and
// narrowed, so that they reach the readers' own checks (non-finite coordinates) as before.
template <typename T>
bool parse_as(std::string_view token, T& value) {
  if (!token.empty() && token.front() == '+') {
    token.remove_prefix(1);
    if (!token.empty() && (token.front() == '-' || token.front() == '+')) return false;
  }
  const char* end = token.data() + token.size();
  auto r = std::from_chars(token.data(), end, value);
  if (r.ec == std::errc::result_out_of_range && r.ptr == end) {
    long double wide = 0;
    r = std::from_chars(token.data(), end, wide);
    if (r.ec == std::errc() && r.ptr == end) value = static_cast<T>(wide);
  }
  return r.ec == std::errc() && r.ptr == end;
}

}  // namespace

ColourScale parse_colour_scale(const std::string& name) {
  if (name == "auto") return ColourScale::kAuto;
  if (name == "unit") return ColourScale::kUnit;
  if (name == "byte") return ColourScale::kByte;
  throw std::invalid_argument("colour scale: expected auto, unit or byte, got '" + name + "'");
}

const char* colour_scale_name(ColourScale scale) {
  switch (scale) {
    case ColourScale::kAuto:
      return "auto";
    case ColourScale::kUnit:
      return "unit";
    case ColourScale::kByte:
      return "byte";
  }
  return "?";
}

double ColourConversion::operator()(double c) const {
  return from_255 ? std::floor(c + 0.5) / 255.0 : std::min(c, 1.0);
}

ColourConversion colour_conversion(const ColourValues& values, ColourScale scale,
                                   const std::string& file) {
  ColourConversion out;
  switch (scale) {
    case ColourScale::kByte:
      out.from_255 = true;
      return out;
    case ColourScale::kUnit:
      if (values.above_one > 0) {
        out.warning = file + ": " + count_text(values) + ": clamped to 1 (--colour-scale unit)";
      }
      return out;
    case ColourScale::kAuto:
      break;
  }
  out.from_255 = values.above_one > 0;  // MEPP2's rule
  const bool thin =
      static_cast<double>(values.above_one) < kFewAboveOne * static_cast<double>(values.count) ||
      values.max < kClearlyByte;
  if (out.from_255 && thin) {
    out.warning = file + ": " + count_text(values) +
                  ": read as 0..255 like the reference; --colour-scale unit reads them as 0..1";
  }
  return out;
}

std::optional<double> large_float32_step(double largest, double spacing) {
  if (!(spacing > 0) || !std::isfinite(largest)) return std::nullopt;
  const float at = static_cast<float>(largest);
  const double step = static_cast<double>(std::nextafter(at, std::numeric_limits<float>::max())) -
                      static_cast<double>(at);
  if (!(step > kLargeStepOfSpacing * spacing)) return std::nullopt;
  return step;
}

namespace {

template <class Point>
std::optional<std::string> rounding_warning(const std::vector<Point>& positions,
                                            const std::string& file) {
  if (positions.size() < 2) return std::nullopt;
  Vec3 lo{positions.front()[0], positions.front()[1], positions.front()[2]}, hi = lo;
  double largest = 0;
  for (const Point& p : positions) {
    for (int a = 0; a < 3; ++a) {
      const double v = p[a];
      lo[a] = std::min(lo[a], v);
      hi[a] = std::max(hi[a], v);
      largest = std::max(largest, std::abs(v));
    }
  }
  const double diagonal =
      std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
  const double spacing = diagonal / std::sqrt(static_cast<double>(positions.size()));
  if (!(spacing > 0) || !std::isfinite(largest)) return std::nullopt;
  const std::optional<double> large = large_float32_step(largest, spacing);
  if (!large) return std::nullopt;
  const double step = *large;
  return file + ": coordinates stored as float32: at |coordinate| " + number_text(largest) +
         " the float32 step is " + number_text(step) + ", more than 1/8 of the typical point " +
         "spacing " + number_text(spacing) +
         " (bounding-box diagonal / sqrt(points)): the geometry has lost detail (store the " +
         "coordinates as double, or centred)";
}

}  // namespace

std::optional<std::string> float32_rounding_warning(const std::vector<Vec3>& positions,
                                                    const std::string& file) {
  return rounding_warning(positions, file);
}

std::optional<std::string> float32_rounding_warning(
    const std::vector<std::array<float, 3>>& positions, const std::string& file) {
  return rounding_warning(positions, file);
}

bool parse_number(std::string_view token, double& value) { return parse_as(token, value); }
bool parse_number(std::string_view token, float& value) { return parse_as(token, value); }

std::string number_text(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace qm3d
