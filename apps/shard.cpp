#include "shard.h"

#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "qm3d/common/error.h"
#include "qm3d/common/result_io.h"

namespace qm3d::app {
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
  std::istringstream in(text);
  std::vector<ListPair> pairs;
  std::string line;
  for (std::size_t line_no = 1; std::getline(in, line); ++line_no) {
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    auto f = csv_split(line);
    for (auto& s : f) {
      s.erase(0, s.find_first_not_of(" \t"));
      s.erase(s.find_last_not_of(" \t") + 1);
    }
    if (pairs.empty() && f[0] == "reference") continue;  // header
    if (f.size() < 2 || f.size() > 3 || f[0].empty() || f[1].empty()) {
      throw FormatError(name + ": line " + std::to_string(line_no) +
                        ": expected reference,distorted[,metric]");
    }
    pairs.push_back({f[0], f[1], f.size() == 3 && !f[2].empty() ? f[2] : "auto"});
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

MergeResult merge_results(const std::vector<ResultKey>& expected,
                          const std::vector<ResultFile>& files) {
  MergeResult result;
  result.files = files.size();
  std::map<ResultKey, std::size_t> times_expected;
  for (const ResultKey& k : expected) ++times_expected[k];

  std::map<ResultKey, std::vector<Row>> rows;
  std::vector<std::string> header_fields;
  std::string header_file;
  std::size_t seconds_column = 0, status_column = 0, error_column = 0;
  for (const ResultFile& file : files) {
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
        if (header_fields.empty()) {
          if (fields.size() < 3 || fields[0] != "reference" || fields[1] != "distorted" ||
              fields[2] != "metric") {
            throw FormatError(file.name +
                              ": no reference,distorted,metric header (not a qm3d batch results "
                              "file?)");
          }
          seconds_column = column_of(fields, "seconds", file.name);
          status_column = column_of(fields, "status", file.name);
          error_column = column_of(fields, "error", file.name);
          header_fields = fields;
          header_file = file.name;
          result.header = line;
        } else if (fields != header_fields) {
          throw FormatError(file.name + ": header differs from " + header_file +
                            "'s (results of another qm3d version?)");
        }
        continue;
      }
      if (fields.size() != header_fields.size()) {
        throw FormatError(file.name + ": line " + std::to_string(line_no) + ": " +
                          std::to_string(fields.size()) + " columns, the header has " +
                          std::to_string(header_fields.size()));
      }
      ++result.rows_read;
      ResultKey key{fields[0], fields[1], fields[2]};
      rows[key].push_back(Row{line, std::move(fields), file.name, line_no});
    }
    if (!have_header) throw FormatError(file.name + ": empty (no header line)");
  }

  const auto same_result = [&](const Row& a, const Row& b) {
    for (std::size_t c = 0; c < a.fields.size(); ++c) {
      if (c != seconds_column && a.fields[c] != b.fields[c]) return false;
    }
    return true;
  };
  std::set<ResultKey> emitted;
  for (const ResultKey& key : expected) {
    if (!emitted.insert(key).second) continue;  // listed again: batch writes it once
    const auto it = rows.find(key);
    if (it == rows.end()) {
      result.missing.push_back(describe(key));
      continue;
    }
    const std::vector<Row>& found = it->second;
    bool conflict = false;
    for (std::size_t i = 1; i < found.size(); ++i) {
      if (!same_result(found[0], found[i])) {
        result.conflicts.push_back(describe(key) + ": " + where(found[0]) + " and " +
                                   where(found[i]) + " differ");
        conflict = true;
        break;
      }
    }
    if (conflict) continue;
    if (found.size() > times_expected[key]) {
      std::string places;
      for (const Row& r : found) places += (places.empty() ? "" : ", ") + where(r);
      result.duplicates.push_back(describe(key) + ": " + std::to_string(found.size()) +
                                  " identical rows (" + places + "), one kept");
    }
    result.rows.push_back(found[0].line);
    if (found[0].fields[status_column] != "ok") {
      result.failed.push_back(describe(key) + ": " + found[0].fields[error_column]);
    }
  }
  for (const auto& [key, found] : rows) {
    if (times_expected.count(key) == 0) {
      result.unexpected.push_back(describe(key) + " (" + where(found[0]) + ")");
    }
  }
  return result;
}

}  // namespace qm3d::app
