// Text helpers of the tool's CSV readers (score tables and pair lists).
#pragma once

#include <cctype>
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

}  // namespace qm3d
