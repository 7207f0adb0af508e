// Line, statement and number scanning for the text mesh formats (OBJ, MTL, OFF). Internal.
#pragma once

#include <charconv>
#include <cstddef>
#include <string>
#include <string_view>

#include "qm3d/common/reading.h"

namespace qm3d::mesh::detail {

/// The whitespace of the text formats: blank, tab, carriage return, form feed, vertical tab
/// (tested inline: string_view's find_first_of calls memchr on the set for every character).
inline bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

/// Iterates over the lines of a buffer, stripping '#' comments and trailing '\r'.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}

  /// Next line that is not blank after comment removal; false at the end.
  bool next(std::string_view& line) {
    while (pos_ < text_.size()) {
      const std::size_t end = std::min(text_.find('\n', pos_), text_.size());
      std::string_view l = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
      ++line_no_;
      if (const auto hash = l.find('#'); hash != std::string_view::npos) l = l.substr(0, hash);
      if (blank(l)) continue;
      line = l;
      return true;
    }
    return false;
  }

  std::size_t line_number() const { return line_no_; }
  std::size_t remaining_bytes() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }

 private:
  static bool blank(std::string_view l) {
    for (const char c : l) {
      if (!is_blank(c)) return false;
    }
    return true;
  }

  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_no_ = 0;
};

/// Splits a line into whitespace-separated tokens, one at a time.
class Tokens {
 public:
  Tokens() = default;
  explicit Tokens(std::string_view line) : line_(line) {}

  bool next(std::string_view& token) {
    std::size_t begin = pos_;
    while (begin < line_.size() && is_blank(line_[begin])) ++begin;
    if (begin == line_.size()) return false;
    std::size_t end = begin + 1;
    while (end < line_.size() && !is_blank(line_[end])) ++end;
    token = line_.substr(begin, end - begin);
    pos_ = end;
    return true;
  }

 private:
  std::string_view line_;
  std::size_t pos_ = 0;
};

/// The statements of a keyword-led format (OBJ, MTL): for each line that is not blank, its first
/// token and the tokens after it.
class Statements {
 public:
  explicit Statements(std::string_view text) : lines_(text) {}

  /// Next statement; false at the end.
  bool next(std::string_view& keyword, Tokens& arguments) {
    std::string_view line;
    if (!lines_.next(line)) return false;
    arguments = Tokens(line);
    arguments.next(keyword);  // the line is not blank: there is a first token
    return true;
  }

  std::size_t line_number() const { return lines_.line_number(); }

 private:
  LineReader lines_;
};

/// Parses a whole token as a double whatever the C locale; false when it is not a number (a
/// value beyond double's range is +-inf or 0, as strtod gives it, for the callers' checks).
inline bool parse_double(std::string_view token, double& value) {
  return parse_number(token, value);
}

/// Parses a whole token as a (possibly negative) integer.
inline bool parse_long(std::string_view token, long long& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, value);
  return result.ec == std::errc() && result.ptr == end;
}

}  // namespace qm3d::mesh::detail
