#include "qm3d/study/shard.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "qm3d/common/error.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/table_text.h"

namespace qm3d::study {
namespace {

// A decimal number (digits only: no sign, spaces or exponent); false when `s` is not one.
bool parse_count(const std::string& s, std::size_t& value) {
  if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos) {
    return false;
  }
  value = std::stoul(s);
  return true;
}

std::size_t column_of(const std::vector<std::string>& header, const std::string& name,
                      const std::string& file) {
  const auto it = std::find(header.begin(), header.end(), name);
  if (it == header.end()) {
    throw FormatError(file + ": no \"" + name + "\" column (not a qm3d batch results file?)");
  }
  return static_cast<std::size_t>(it - header.begin());
}

struct Row {
  std::string line;
  std::vector<std::string> fields;
  std::string file;
  std::size_t line_no = 0;
};

std::string where(const Row& r) { return r.file + ":" + std::to_string(r.line_no); }


// Where a list's columns are: by position (reference,distorted[,metric]) unless a header names
// them in another order.
struct ListColumns {
  std::size_t reference = 0, distorted = 1;
  std::size_t metric = 2;  ///< kNoColumn when the header has none
  std::size_t count = 3;   ///< most fields a row may have
  std::size_t ref_texture = std::numeric_limits<std::size_t>::max();  ///< header only
  std::size_t dist_texture = std::numeric_limits<std::size_t>::max();
};
constexpr std::size_t kNoColumn = std::numeric_limits<std::size_t>::max();


// A first line naming any of the list's columns is a header (a path is never just "metric").
bool is_list_header(const std::vector<std::string>& fields) {
  for (const std::string& f : fields) {
    const std::string l = lower_ascii(f);
    if (l == "reference" || l == "distorted" || l == "metric" || l == "ref_texture" ||
        l == "dist_texture") {
      return true;
    }
  }
  return false;
}

ListColumns list_columns(const std::vector<std::string>& fields, const std::string& name,
                         std::size_t line_no) {
  const std::string at = name + ": line " + std::to_string(line_no) + ": ";
  ListColumns c{kNoColumn, kNoColumn, kNoColumn, fields.size()};
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const std::string l = lower_ascii(fields[i]);
    std::size_t* slot = l == "reference"      ? &c.reference
                        : l == "distorted"    ? &c.distorted
                        : l == "metric"       ? &c.metric
                        : l == "ref_texture"  ? &c.ref_texture
                        : l == "dist_texture" ? &c.dist_texture
                                              : nullptr;
    if (slot == nullptr) {
      throw FormatError(at + "unknown column \"" + fields[i] +
                        "\" in the header (a list's columns are reference, distorted and "
                        "optionally metric, ref_texture, dist_texture, in any order)");
    }
    if (*slot != kNoColumn) throw FormatError(at + "column \"" + fields[i] + "\" appears twice");
    *slot = i;
  }
  if (c.reference == kNoColumn || c.distorted == kNoColumn) {
    throw FormatError(at + "the header names no " +
                      std::string(c.reference == kNoColumn ? "reference" : "distorted") +
                      " column");
  }
  return c;
}

ListPair list_pair(const std::vector<std::string>& f, const ListColumns& c, const std::string& name,
                   std::size_t line_no) {
  const auto field = [&](std::size_t i) { return i < f.size() ? f[i] : std::string(); };
  ListPair p{field(c.reference), field(c.distorted), field(c.metric), field(c.ref_texture),
             field(c.dist_texture)};
  if (f.size() > c.count || p.reference.empty() || p.distorted.empty()) {
    throw FormatError(name + ": line " + std::to_string(line_no) + ": expected " +
                      (c.count == 3 && c.reference == 0 && c.distorted == 1
                           ? std::string("reference,distorted[,metric]")
                           : std::to_string(c.count) + " fields as in the header"));
  }
  if (p.metric.empty()) p.metric = "auto";
  return p;
}

// The rows of a merge come from one configuration: a row scored with other settings (shards
// run with different options) would mix scores that cannot be compared.
void check_same_settings(const Row& row, std::optional<Row>& first, std::size_t column) {
  if (!first) {
    first = row;
    return;
  }
  if (row.fields[column] != first->fields[column]) {
    throw FormatError(where(row) + ": scored with settings \"" + row.fields[column] + "\", " +
                      where(*first) + " with \"" + first->fields[column] +
                      "\" (shards run with different options?); nothing merged");
  }
}

// A score batch writes on an ok row: a finite number, or "inf" (the PSNR of identical inputs:
// a quality may be +inf, acceptable_score in common/src/metric.cpp). NaN and -inf never are.
bool is_batch_score(const std::string& s) {
  double value = 0;
  const char* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data(), end, value);
  return !s.empty() && ec == std::errc() && ptr == end &&
         (std::isfinite(value) || value == HUGE_VAL);
}

std::string csv_line(const std::vector<std::string>& fields) {
  std::string line;
  for (std::size_t i = 0; i < fields.size(); ++i) line += (i ? "," : "") + csv_field(fields[i]);
  return line;
}

}  // namespace

Shard parse_shard(const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return std::invalid_argument("\"" + text + "\": " + why);
  };
  const auto slash = text.find('/');
  if (slash == std::string::npos) throw bad("expected K/N, e.g. 0/4 for the first of 4 shards");
  Shard s;
  if (!parse_count(text.substr(0, slash), s.index)) {
    throw bad("K must be a whole number from 0 to N-1");
  }
  if (!parse_count(text.substr(slash + 1), s.count)) {
    throw bad("N must be a whole number, at least 1");
  }
  if (s.count == 0) throw bad("N must be at least 1");
  if (s.index >= s.count) {
    throw bad("K must be below N (shards are numbered 0.." + std::to_string(s.count - 1) +
              ", as SLURM_ARRAY_TASK_ID with --array=0-" + std::to_string(s.count - 1) + ")");
  }
  return s;
}

std::vector<std::vector<std::size_t>> partition_by_size(const std::vector<std::uintmax_t>& sizes,
                                                        std::size_t count) {
  if (count == 0) throw std::invalid_argument("partition_by_size: no parts");
  std::vector<std::size_t> order(sizes.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return sizes[a] > sizes[b]; });
  // (load, part) ordered: the lightest part first, ties to the lowest index.
  std::set<std::pair<std::uintmax_t, std::size_t>> loads;
  for (std::size_t k = 0; k < count; ++k) loads.emplace(0, k);
  std::vector<std::vector<std::size_t>> parts(count);
  for (const std::size_t row : order) {
    auto [load, part] = *loads.begin();
    loads.erase(loads.begin());
    parts[part].push_back(row);
    const std::uintmax_t max = std::numeric_limits<std::uintmax_t>::max();
    loads.emplace(sizes[row] > max - load ? max : load + sizes[row], part);
  }
  for (auto& p : parts) std::sort(p.begin(), p.end());
  return parts;
}

std::vector<std::size_t> shard_rows(const std::vector<std::uintmax_t>& sizes, Shard shard) {
  if (shard.count == 0 || shard.index >= shard.count) {
    throw std::invalid_argument("shard " + std::to_string(shard.index) + "/" +
                                std::to_string(shard.count) + " does not exist");
  }
  return partition_by_size(sizes, shard.count)[shard.index];
}

std::uintmax_t input_bytes(const std::filesystem::path& path) noexcept {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec) || ec) return 0;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  return ec ? 0 : size;
}

std::vector<ListPair> parse_pair_list(const std::string& text, const std::string& name) {
  std::istringstream in(std::string(without_utf8_bom(text)));
  std::vector<ListPair> pairs;
  std::optional<ListColumns> header;
  std::string line;
  for (std::size_t line_no = 1; std::getline(in, line); ++line_no) {
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    auto f = csv_split(line);
    for (auto& s : f) {
      s.erase(0, s.find_first_not_of(" \t\r"));
      s.erase(s.find_last_not_of(" \t\r") + 1);
    }
    if (pairs.empty() && !header && is_list_header(f)) {
      header = list_columns(f, name, line_no);
      continue;
    }
    pairs.push_back(list_pair(f, header.value_or(ListColumns{}), name, line_no));
  }
  if (pairs.empty()) throw FormatError(name + ": no pairs");
  return pairs;
}

bool ResultKey::operator<(const ResultKey& o) const {
  return std::tie(reference, distorted, metric) < std::tie(o.reference, o.distorted, o.metric);
}
bool ResultKey::operator==(const ResultKey& o) const {
  return std::tie(reference, distorted, metric) == std::tie(o.reference, o.distorted, o.metric);
}

std::string describe(const ResultKey& key) {
  return key.reference + ", " + key.distorted + ", " + key.metric;
}

namespace {

// The columns merge reads, found in the first file's header; every other file's header must
// be the same.
struct ResultColumns {
  std::vector<std::string> header_fields;
  std::string header_file;
  std::size_t seconds = 0, status = 0, error = 0, score = 0, settings = kNoColumn;
};

using RowsByKey = std::map<ResultKey, std::vector<Row>>;

// The header line of `file`: the first file's sets the columns, another's must equal it.
void read_header(const std::vector<std::string>& fields, const std::string& line,
                 const ResultFile& file, ResultColumns& columns, MergeResult& result) {
  if (!columns.header_fields.empty()) {
    if (fields != columns.header_fields) {
      throw FormatError(file.name + ": header differs from " + columns.header_file +
                        "'s (results of another qm3d version?)");
    }
    return;
  }
  if (fields.size() < 3 || fields[0] != "reference" || fields[1] != "distorted" ||
      fields[2] != "metric") {
    throw FormatError(file.name +
                      ": no reference,distorted,metric header (not a qm3d batch results "
                      "file?)");
  }
  columns.seconds = column_of(fields, "seconds", file.name);
  columns.status = column_of(fields, "status", file.name);
  columns.error = column_of(fields, "error", file.name);
  columns.score = column_of(fields, "score", file.name);
  const auto settings = std::find(fields.begin(), fields.end(), "settings");
  if (settings != fields.end()) columns.settings = settings - fields.begin();
  columns.header_fields = fields;
  columns.header_file = file.name;
  result.header = line;
}

// The rows of `file` by key into `rows`; `first_settings`: the first row read, whose settings
// every row must share.
void read_rows(const ResultFile& file, ResultColumns& columns, RowsByKey& rows,
               std::optional<Row>& first_settings, MergeResult& result) {
  std::istringstream in(file.text);
  std::string line;
  bool have_header = false;
  for (std::size_t line_no = 1; std::getline(in, line); ++line_no) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (in.eof()) {  // no newline after this line: cut short by a kill
      result.warnings.push_back(file.name + ":" + std::to_string(line_no) +
                                ": incomplete last line ignored (a killed batch? --resume "
                                "completes it)");
      break;
    }
    if (line.empty()) continue;
    auto fields = csv_split(line);
    if (!have_header) {
      have_header = true;
      read_header(fields, line, file, columns, result);
      continue;
    }
    if (fields.size() != columns.header_fields.size()) {
      throw FormatError(file.name + ": line " + std::to_string(line_no) + ": " +
                        std::to_string(fields.size()) + " columns, the header has " +
                        std::to_string(columns.header_fields.size()));
    }
    ++result.rows_read;
    ResultKey key{fields[0], fields[1], fields[2]};
    Row row{line, std::move(fields), file.name, line_no};
    if (columns.settings != kNoColumn) check_same_settings(row, first_settings, columns.settings);
    rows[key].push_back(std::move(row));
  }
  if (!have_header) throw FormatError(file.name + ": empty (no header line)");
}

// Rows of one key are the same when every column but `seconds` is equal.
bool same_result(const Row& a, const Row& b, const ResultColumns& columns) {
  for (std::size_t c = 0; c < a.fields.size(); ++c) {
    if (c != columns.seconds && a.fields[c] != b.fields[c]) return false;
  }
  return true;
}

// The row kept of a key's rows: the first, an ok row without a score made the error it is.
Row kept_row(const std::vector<Row>& found, const ResultColumns& columns) {
  Row kept = found[0];
  std::vector<std::string>& f = kept.fields;
  if (f[columns.status] == "ok" && !is_batch_score(f[columns.score])) {
    f[columns.status] = "error";
    f[columns.error] = "merge: status ok but the score \"" + f[columns.score] +
                       "\" is not a score (a finite number or inf) (" + where(kept) + ")";
    f[columns.score].clear();
    kept.line = csv_line(f);
  }
  return kept;
}

// Adds the rows found for `key` (listed `times` times) to `result`: a conflict, or the kept row
// (with a duplicate or failure noted).
void join_key(const ResultKey& key, const std::vector<Row>& found, std::size_t times,
              const ResultColumns& columns, MergeResult& result) {
  for (std::size_t i = 1; i < found.size(); ++i) {
    if (!same_result(found[0], found[i], columns)) {
      result.conflicts.push_back(describe(key) + ": " + where(found[0]) + " and " +
                                 where(found[i]) + " differ");
      return;
    }
  }
  if (found.size() > times) {
    std::string places;
    for (const Row& r : found) places += (places.empty() ? "" : ", ") + where(r);
    result.duplicates.push_back(describe(key) + ": " + std::to_string(found.size()) +
                                " identical rows (" + places + "), one kept");
  }
  const Row kept = kept_row(found, columns);
  result.rows.push_back(kept.line);
  if (kept.fields[columns.status] != "ok") {
    result.failed.push_back(describe(key) + ": " + kept.fields[columns.error]);
  }
}

}  // namespace

MergeResult merge_results(const std::vector<ResultKey>& expected,
                          const std::vector<ResultFile>& files) {
  MergeResult result;
  result.files = files.size();
  std::map<ResultKey, std::size_t> times_expected;
  for (const ResultKey& k : expected) ++times_expected[k];
  RowsByKey rows;
  ResultColumns columns;
  std::optional<Row> first_settings;
  for (const ResultFile& file : files) read_rows(file, columns, rows, first_settings, result);

  std::set<ResultKey> emitted;
  for (const ResultKey& key : expected) {
    if (!emitted.insert(key).second) continue;  // listed again: batch writes it once
    const auto it = rows.find(key);
    if (it == rows.end()) {
      result.missing.push_back(describe(key));
      continue;
    }
    join_key(key, it->second, times_expected[key], columns, result);
  }
  for (const auto& [key, found] : rows) {
    if (times_expected.count(key) == 0) {
      result.unexpected.push_back(describe(key) + " (" + where(found[0]) + ")");
    }
  }
  return result;
}

}  // namespace qm3d::study
