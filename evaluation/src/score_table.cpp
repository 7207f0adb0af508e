#include "qm3d/evaluation/score_table.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <sstream>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/table_text.h"

namespace qm3d::evaluation {
namespace {

/// The stimulus column of `qm3d batch` results.
constexpr const char* kBatchKeyColumn = "distorted";


std::string trimmed(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t") + 1 - begin);
}

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields = csv_split(line);
  for (std::string& f : fields) f = trimmed(f);
  return fields;
}

std::string where(const CsvTable& t, std::size_t line) {
  return t.path + ":" + std::to_string(line);
}

void set_header(CsvTable& t, const std::string& line, std::size_t line_no) {
  t.header = split_fields(line);
  std::map<std::string, std::size_t> seen;
  for (const std::string& name : t.header) {
    if (!seen.emplace(name, line_no).second) {
      throw FormatError(where(t, line_no) + ": column \"" + name +
                        "\" appears twice in the header");
    }
  }
}

bool is_missing(const std::string& cell) {
  return cell.empty() || cell == "nan" || cell == "NaN" || cell == "NA";
}


std::string joined_names(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// Key -> row, rejecting repeated and empty keys.
std::map<std::string, std::size_t> index_keys(const CsvTable& t, std::size_t column, bool by_stem) {
  std::map<std::string, std::size_t> index;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const std::string& raw = t.rows[r][column];
    if (raw.empty()) {
      throw FormatError(where(t, t.line_numbers[r]) + ": empty key in column \"" +
                        t.header[column] + "\"");
    }
    const auto [it, fresh] = index.emplace(by_stem ? stem_of(raw) : raw, r);
    if (!fresh) {
      throw FormatError(where(t, t.line_numbers[r]) + ": key \"" + it->first +
                        "\" already on line " + std::to_string(t.line_numbers[it->second]));
    }
  }
  return index;
}

}  // namespace

std::string stem_of(const std::string& key) { return std::filesystem::path(key).stem().string(); }

CsvTable read_csv_table(const std::filesystem::path& path) {
  CsvTable t;
  t.path = path.string();
  const std::string bytes = read_file_bytes(path, kMaxTableBytes);
  std::istringstream in(std::string(without_utf8_bom(bytes)));
  std::string line;
  for (std::size_t line_no = 1; std::getline(in, line); ++line_no) {
    if (trimmed(line).empty() || line == "\r") continue;
    if (t.header.empty()) {
      set_header(t, line, line_no);
      continue;
    }
    std::vector<std::string> fields = split_fields(line);
    if (fields.size() != t.header.size()) {
      throw FormatError(where(t, line_no) + ": " + std::to_string(fields.size()) +
                        " fields, the header has " + std::to_string(t.header.size()));
    }
    t.rows.push_back(std::move(fields));
    t.line_numbers.push_back(line_no);
  }
  if (t.header.empty()) throw FormatError(t.path + ": empty file (no header row)");
  return t;
}

std::optional<std::size_t> find_column(const CsvTable& table, const std::string& name) {
  for (std::size_t c = 0; c < table.header.size(); ++c) {
    if (table.header[c] == name) return c;
  }
  return std::nullopt;
}

std::size_t require_column(const CsvTable& table, const std::string& name,
                           const std::string& option) {
  if (const auto c = find_column(table, name)) return *c;
  throw FormatError(table.path + ": no column \"" + name +
                    "\" (columns: " + joined_names(table.header) + "); set it with " + option);
}

std::size_t key_column(const CsvTable& table, const std::string& name, const std::string& option) {
  if (!name.empty()) return require_column(table, name, option);
  return find_column(table, kBatchKeyColumn).value_or(0);
}

std::size_t value_column(const CsvTable& table, const std::string& name,
                         const std::vector<std::string>& preferred, std::size_t key,
                         const std::string& option) {
  if (!name.empty()) return require_column(table, name, option);
  for (const std::string& want : preferred) {
    for (std::size_t c = 0; c < table.header.size(); ++c) {
      if (lower_ascii(table.header[c]) == lower_ascii(want)) return c;
    }
  }
  if (table.header.size() == 2) return key == 0 ? 1 : 0;
  throw FormatError(table.path + ": which column holds the values? set it with " + option +
                    " (columns: " + joined_names(table.header) + ")");
}

std::optional<double> cell_number(const CsvTable& table, std::size_t row, std::size_t column,
                                  bool allow_infinite) {
  const std::string& cell = table.rows[row][column];
  if (is_missing(cell)) return std::nullopt;
  const char* begin = cell.data() + (cell[0] == '+' ? 1 : 0);
  const char* end = cell.data() + cell.size();
  double value = 0;
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr != end || std::isnan(value) ||
      (std::isinf(value) && !allow_infinite)) {
    throw FormatError(where(table, table.line_numbers[row]) + ": column \"" + table.header[column] +
                      "\": \"" + cell + "\" is not a number");
  }
  return value;
}

void KeyList::add(const std::string& key) {
  ++count;
  if (first.size() < kKeysShown) first.push_back(key);
}

std::string KeyList::examples() const {
  return joined_names(first) + (count > first.size() ? ", ..." : "");
}

JoinedRows join_on_key(const CsvTable& left, std::size_t left_key, const CsvTable& right,
                       std::size_t right_key, bool by_stem) {
  const auto left_index = index_keys(left, left_key, by_stem);
  const auto right_index = index_keys(right, right_key, by_stem);
  JoinedRows j;
  for (std::size_t r = 0; r < left.rows.size(); ++r) {
    const std::string key = by_stem ? stem_of(left.rows[r][left_key]) : left.rows[r][left_key];
    const auto partner = right_index.find(key);
    if (partner == right_index.end()) {
      j.left_only.add(key);
      continue;
    }
    j.keys.push_back(key);
    j.left.push_back(r);
    j.right.push_back(partner->second);
  }
  for (std::size_t r = 0; r < right.rows.size(); ++r) {
    const std::string key = by_stem ? stem_of(right.rows[r][right_key]) : right.rows[r][right_key];
    if (left_index.count(key) == 0) j.right_only.add(key);
  }
  return j;
}

}  // namespace qm3d::evaluation
