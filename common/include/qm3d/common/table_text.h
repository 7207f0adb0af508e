// Text helpers of the tool's tables: its CSV readers (score tables and pair lists) and the
// numbers of its printed tables.
#pragma once

#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>

namespace qm3d {

/// `text` without a leading UTF-8 byte-order mark (spreadsheets write one before the header).
inline std::string_view without_utf8_bom(std::string_view text) {
  constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";
  return text.substr(0, kUtf8Bom.size()) == kUtf8Bom ? text.substr(kUtf8Bom.size()) : text;
}

/// ASCII lower case, for column names compared without case.
inline std::string lower_ascii(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// `v` written with the printf conversion `spec` (one double: "%.4f", "%.3f", "%.6g"), as the
/// tool's printed tables and messages show statistics; "nan" when `v` is not finite.
inline std::string fixed(double v, const char* spec = "%.4f") {
  if (!std::isfinite(v)) return "nan";
  char buf[64];
  std::snprintf(buf, sizeof buf, spec, v);
  return buf;
}

}  // namespace qm3d
