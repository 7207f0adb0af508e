#include "eval_protocol.h"
#include "emit_text.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <deque>
#include <set>
#include <sstream>

#include "qm3d/scoring/score.h"
#include "qm3d/report/eval_plot.h"
#include "qm3d/common/error.h"
#include "qm3d/common/table_text.h"
#include "qm3d/evaluation/evaluation_protocol.h"
#include "qm3d/evaluation/orientation.h"
#include "qm3d/evaluation/pair_labels.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/version.h"
#include "qm3d/evaluation/score_table.h"

namespace qm3d::app {
using namespace qm3d::scoring;  // NOLINT: the scoring this command drives
using namespace qm3d::report;  // NOLINT: the library this command drives
using namespace qm3d::evaluation;  // NOLINT: the library this command prints
namespace {

using ordered_json = nlohmann::ordered_json;
namespace fs = std::filesystem;

constexpr double kConfidence = 0.95;

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

// ---- the score series ----------------------------------------------------------------------

/// One metric's column: its table (the SCORES file, or its rows of one metric), the column, the
/// join with MOS.
struct Series {
  std::string name;
  const CsvTable* table = nullptr;
  std::size_t column = 0;
  std::string metric;  ///< the registered metric the rows name, or empty
  const JoinedRows* join = nullptr;
};

/// The rows of each metric of a SCORES table's `metric` column, in the order they first appear
/// (batch results: one row per pair and metric; one part when every row names the same metric);
/// the whole table under an empty name when it has no metric column.
std::vector<std::pair<std::string, CsvTable>> split_by_metric(const CsvTable& t) {
  const auto column = find_column(t, "metric");
  if (!column) return {{"", t}};
  std::vector<std::pair<std::string, CsvTable>> parts;
  std::map<std::string, std::size_t> at;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const std::string& m = t.rows[r][*column];
    auto [it, added] = at.emplace(m, parts.size());
    if (added) parts.push_back({m, CsvTable{t.path, t.header, {}, {}}});
    parts[it->second].second.rows.push_back(t.rows[r]);
    parts[it->second].second.line_numbers.push_back(t.line_numbers[r]);
  }
  if (parts.empty()) parts.push_back({"", t});  // a header without rows
  return parts;
}

// Every column whose joined cells are all numbers (or empty), but the key, the metric name and
// what batch results hold besides scores.
std::vector<std::size_t> numeric_columns(const CsvTable& t, std::size_t key) {
  std::vector<std::size_t> out;
  for (std::size_t c = 0; c < t.header.size(); ++c) {
    const std::string& h = t.header[c];
    if (c == key || h == "reference" || h == "distorted" || h == "metric" || h == "status" ||
        h == "error" || h == "seconds" || h == "settings" || h == "warnings" ||
        h.find("bbox_max_side") != std::string::npos) {
      continue;
    }
    bool numeric = true, any = false;
    for (std::size_t r = 0; r < t.rows.size() && numeric; ++r) {
      try {
        any = cell_number(t, r, c, true).has_value() || any;
      } catch (const FormatError&) {
        numeric = false;
      }
    }
    if (numeric && any) out.push_back(c);
  }
  return out;
}

// The orientation of a series (qm3d::evaluation::orient): --lower-is-better, --orientation, the
// registered metric its rows name (asked about the column), a column named after a registered
// metric or one of its named values; else assumed higher = better (Krasula's convention).
void orient_series(const Series& s, const EvalCommandOptions& o, MetricScores& m) {
  const Orientation r =
      orient(default_registry(), {o.lower_is_better, o.orientation},
             {s.name, s.metric, s.table->header[s.column]}, Fallback::column_name_then_quality);
  m.higher_is_better = *r.higher_is_better;
  m.orientation_source = r.source;
}

// Every --lower-is-better name must be one of the series (a typo is refused, never ignored).
void check_lower_is_better(const std::vector<Series>& series, const EvalCommandOptions& o) {
  for (const std::string& name : o.lower_is_better) {
    const auto same = [&](const Series& s) { return s.name == name; };
    if (std::any_of(series.begin(), series.end(), same)) continue;
    std::string names;
    for (const Series& s : series) names += (names.empty() ? "" : ", ") + s.name;
    throw InputError("--lower-is-better " + name + ": no such metric (the metrics: " + names + ")");
  }
}

// ---- the subjective data -------------------------------------------------------------------

/// What the MOS file and the extra files say of the kept stimuli.
struct Stimuli {
  std::vector<std::string> keys;
  std::vector<std::size_t> mos_rows;  ///< row of each in the MOS table
  std::map<std::string, std::size_t> index;  ///< key -> its place in `keys`
  void add(const std::string& key, std::size_t mos_row) {
    index.emplace(key, keys.size());
    keys.push_back(key);
    mos_rows.push_back(mos_row);
  }
};

double required_number(const CsvTable& t, std::size_t row, std::size_t column,
                       const std::string& what) {
  const auto v = cell_number(t, row, column);
  if (!v) {
    throw FormatError(t.path + ":" + std::to_string(t.line_numbers[row]) + ": column \"" +
                      t.header[column] + "\": no " + what + " (every stimulus needs one for the "
                      "pair labels)");
  }
  return *v;
}

// Krasula's labels from SD and n (or n from the CI half-widths: n = (1.96 SD / CI)^2).
PairLabels pairs_from_sd(const CsvTable& mos, std::size_t mos_column, const Stimuli& st,
                         const EvalCommandOptions& o, const std::vector<std::string>& groups) {
  const std::size_t sd_c = require_column(mos, o.sd_column, "--sd-column");
  const auto n_c = o.n_column.empty() ? std::nullopt
                                      : std::optional(require_column(mos, o.n_column, "--n-column"));
  const auto ci_c = o.ci_column.empty() ? std::nullopt
                                        : std::optional(require_column(mos, o.ci_column, "--ci-column"));
  if (!n_c && !ci_c) {
    throw InputError("--sd-column needs the observer counts: --n-column, or --ci-column (n = "
                     "(1.96 SD / CI)^2)");
  }
  std::vector<double> m, sd, n;
  for (std::size_t row : st.mos_rows) {
    m.push_back(required_number(mos, row, mos_column, "MOS"));
    sd.push_back(required_number(mos, row, sd_c, "standard deviation"));
    if (n_c) {
      n.push_back(required_number(mos, row, *n_c, "observer count"));
    } else {
      const double ci = required_number(mos, row, *ci_c, "confidence interval");
      n.push_back(observers_from_ci(sd.back(), ci));
    }
    const std::string where = mos.path + ":" + std::to_string(mos.line_numbers[row]);
    if (sd.back() < 0) throw FormatError(where + ": a negative standard deviation");
    if (!(n.back() >= 2)) {
      throw FormatError(where + ": " + std::to_string(n.back()) +
                        " observers; Krasula's labels need n >= 2");
    }
  }
  PairLabelSource source;
  source.kind = PairLabelSource::Kind::sd;
  source.sd = std::move(sd);
  source.n = std::move(n);
  return *label_pairs(m, source, groups);
}

// Labels from a long-format file of individual scores: stimulus, observer, score (by name or
// the first and last columns).
PairLabels pairs_from_raw(const EvalCommandOptions& o, const Stimuli& st,
                          const std::vector<std::string>& groups) {
  const CsvTable raw = read_csv_table(o.raw);
  const std::size_t key = find_column(raw, "stimulus").value_or(0);
  const std::size_t score = find_column(raw, "score").value_or(raw.header.size() - 1);
  std::vector<std::vector<double>> scores(st.keys.size());
  for (std::size_t r = 0; r < raw.rows.size(); ++r) {
    const std::string k = o.stem ? stem_of(raw.rows[r][key]) : raw.rows[r][key];
    const auto it = st.index.find(k);
    if (it == st.index.end()) {
      throw FormatError(raw.path + ":" + std::to_string(raw.line_numbers[r]) + ": stimulus \"" +
                        raw.rows[r][key] + "\" is not among the evaluated stimuli");
    }
    const auto v = cell_number(raw, r, score);
    if (!v) {
      const std::string& cell = raw.rows[r][score];
      throw FormatError(
          raw.path + ":" + std::to_string(raw.line_numbers[r]) + ": " +
          (cell.empty() ? "an empty score" : "the score \"" + cell + "\" is not a number") +
          " (every individual score must be a number)");
    }
    scores[it->second].push_back(*v);
  }
  for (std::size_t i = 0; i < scores.size(); ++i) {
    if (scores[i].size() < 2) {
      throw FormatError(raw.path + ": stimulus \"" + st.keys[i] + "\" has " +
                        std::to_string(scores[i].size()) + " individual scores; at least 2 needed");
    }
  }
  PairLabelSource source;
  source.kind = PairLabelSource::Kind::raw;
  source.raw = std::move(scores);
  return *label_pairs({}, source, groups);
}

// Given labels: first, second, label (+1 first better, -1 worse, 0 similar).
PairLabels pairs_from_file(const EvalCommandOptions& o, const Stimuli& st) {
  const CsvTable t = read_csv_table(o.pairs);
  if (t.header.size() < 3) {
    throw FormatError(t.path + ": expected the columns first, second, label");
  }
  const std::size_t a = find_column(t, "first").value_or(0);
  const std::size_t b = find_column(t, "second").value_or(1);
  const std::size_t l = find_column(t, "label").value_or(2);
  PairLabels pairs;
  pairs.rule = "given (" + t.path + ")";
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const std::string where = t.path + ":" + std::to_string(t.line_numbers[r]);
    std::size_t ij[2];
    for (int k = 0; k < 2; ++k) {
      const std::string& cell = t.rows[r][k == 0 ? a : b];
      const auto it = st.index.find(o.stem ? stem_of(cell) : cell);
      if (it == st.index.end()) {
        throw FormatError(where + ": stimulus \"" + cell + "\" is not among the evaluated stimuli");
      }
      ij[k] = it->second;
    }
    if (ij[0] == ij[1]) {
      throw FormatError(where + ": stimulus \"" + st.keys[ij[0]] +
                        "\" is paired with itself (a pair is two different stimuli)");
    }
    const auto label = cell_number(t, r, l);
    if (!label || (*label != -1 && *label != 0 && *label != 1)) {
      throw FormatError(where + ": the label must be 1 (first better), -1 or 0");
    }
    pairs.add(ij[0], ij[1], static_cast<int>(*label));
  }
  return pairs;
}

// Krasula's analysis needs 2 significantly different pairs: fewer is a property of the data
// (constant individual scores, SDs too large for any difference to be significant), refused as
// the other data errors are (exit code 2), naming the file the labels come from.
void check_pair_labels(const PairLabels& pairs, const EvalCommandOptions& o) {
  std::size_t different = 0;
  for (const auto l : pairs.label) different += l != 0;
  if (different >= 2) return;
  const std::string source = !o.raw.empty()     ? o.raw + " (--raw)"
                             : !o.pairs.empty() ? o.pairs + " (--pairs)"
                                                : o.mos + " (--sd-column " + o.sd_column + ")";
  throw FormatError(source + ": " + std::to_string(different) + " of " +
                    std::to_string(pairs.size()) + " pairs are significantly different; " +
                    "Krasula's analysis needs at least 2 (constant or too uncertain subjective "
                    "scores?)");
}

// ---- output --------------------------------------------------------------------------------

// A statistic of the protocol's JSON as fixed() writes it; "-" when it has none.
std::string json_fixed(const ordered_json& v, const char* spec = "%.4f") {
  return v.is_number() ? fixed(v.get<double>(), spec) : "-";
}

std::string cell(const ordered_json& statistic) {
  std::string s = json_fixed(statistic["value"]);
  if (statistic["ci95"].is_array()) {
    s += " [" + json_fixed(statistic["ci95"][0]) + ", " + json_fixed(statistic["ci95"][1]) + "]";
  }
  return s;
}

// A table printed with each column as wide as its widest cell.
class TextTable {
 public:
  void row(std::vector<std::string> cells) { rows_.push_back(std::move(cells)); }
  void print(std::ostream& out) const {
    std::vector<std::size_t> width;
    for (const auto& r : rows_) {
      width.resize(std::max(width.size(), r.size()));
      for (std::size_t c = 0; c < r.size(); ++c) width[c] = std::max(width[c], r[c].size());
    }
    for (const auto& r : rows_) {
      std::string line;
      for (std::size_t c = 0; c < r.size(); ++c) {
        const std::string pad(width[c] - r[c].size(), ' ');
        line += c == 0 ? r[c] + pad : "  " + pad + r[c];
      }
      out << line << "\n";
    }
  }

 private:
  std::vector<std::vector<std::string>> rows_;
};

std::string protocol_text(const ordered_json& j, const std::vector<std::string>& names) {
  std::ostringstream out;
  out << j["stimuli"].get<std::size_t>() << " stimuli; metrics: ";
  for (std::size_t i = 0; i < names.size(); ++i) out << (i ? ", " : "") << names[i];
  out << "\n";
  TextTable t;
  std::vector<std::string> cells = {""};
  cells.insert(cells.end(), names.begin(), names.end());
  t.row(cells);
  cells = {"orientation"};
  for (const auto& n : names) {
    cells.push_back(j["metrics"][n]["orientation"]["higher_is_better"].get<bool>() ? "quality"
                                                                                    : "distortion");
  }
  t.row(cells);
  const std::pair<const char*, const char*> stats[] = {
      {"plcc", "PLCC"},
      {"srocc", "SROCC"},
      {"krocc", "KROCC"},
      {"plcc_mapped", "PLCC (mapped)"},
      {"rmse_mapped", "RMSE (mapped)"},
      {"rmse_star", "RMSE*"},
      {"outlier_ratio", "outlier ratio"}};
  for (const auto& [key, label] : stats) {
    if (!j["metrics"][names[0]]["statistics"].contains(key)) continue;
    cells = {label};
    for (const auto& n : names) cells.push_back(cell(j["metrics"][n]["statistics"][key]));
    t.row(cells);
  }
  if (!j["krasula"].is_null()) {
    const std::pair<const char*, const char*> ks[] = {
        {"auc_ds", "AUC_DS"}, {"auc_bw", "AUC_BW"}, {"c0", "C0"}, {"thr", "THR"}};
    for (const auto& [key, label] : ks) {
      cells = {label};
      for (const auto& n : names) cells.push_back(json_fixed(j["metrics"][n]["krasula"][key], "%.6g"));
      t.row(cells);
    }
  }
  t.print(out);
  if (!j["krasula"].is_null()) {
    const auto& k = j["krasula"];
    out << "Krasula: " << k["different"].get<std::size_t>() << " different ("
        << k["better"].get<std::size_t>() << " first better), " << k["similar"].get<std::size_t>()
        << " similar of " << k["pairs"].get<std::size_t>() << " pairs; labels: "
        << k["rule"].get<std::string>() << "\n";
  }
  if (!j["comparisons"].empty()) {
    out << "comparisons (p: two-sided, one-sided for the F tests):\n";
    TextTable c;
    c.row({"  a", "b", "test", "statistic", "p"});
    for (const auto& x : j["comparisons"]) {
      c.row({"  " + x["a"].get<std::string>(), x["b"].get<std::string>(),
             x["test"].get<std::string>(), json_fixed(x["statistic"], "%.4f"), json_fixed(x["p"], "%.3g")});
    }
    c.print(out);
  }
  return out.str();
}

std::string csv_number(const ordered_json& v) {
  return v.is_number() ? format_double(v.get<double>()) : "";
}

std::string protocol_csv(const ordered_json& j, const std::vector<std::string>& names) {
  std::ostringstream out;
  out << "metric,versus,statistic,value,ci95_low,ci95_high\n";
  for (const auto& n : names) {
    const auto& m = j["metrics"][n];
    out << csv_field(n) << ",,stimuli," << j["stimuli"].get<std::size_t>() << ",,\n";
    for (const auto& [key, s] : m["statistics"].items()) {
      out << csv_field(n) << ",," << key << ',' << csv_number(s["value"]) << ','
          << (s["ci95"].is_array() ? csv_number(s["ci95"][0]) + ',' + csv_number(s["ci95"][1])
                                   : std::string(","))
          << "\n";
    }
    if (!m["krasula"].is_null()) {
      for (const auto& [key, v] : m["krasula"].items()) {
        out << csv_field(n) << ",," << key << ',' << csv_number(v) << ",,\n";
      }
    }
  }
  for (const auto& c : j["comparisons"]) {
    const std::string test = c["test"].get<std::string>();
    const std::string ab = csv_field(c["a"].get<std::string>()) + ',' +
                           csv_field(c["b"].get<std::string>()) + ',' + test;
    out << ab << "_statistic," << csv_number(c["statistic"]) << ",,\n";
    out << ab << "_p," << csv_number(c["p"]) << ",,\n";
  }
  return out.str();
}


// A metric's name as part of a file name.
std::string file_part(const std::string& name) {
  std::string out;
  for (char c : name) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  return out;
}

// --plot FILE.svg|png: FILE-NAME.svg|png, a scatter per metric, and with Krasula's analysis
// FILE-auc.svg|png, the AUC summary.
void plot_protocol(const std::string& path, const std::vector<MetricScores>& metrics,
                   const SubjectiveData& subjective, const ProtocolResult& r,
                   const ordered_json& j, const std::string& mos_label) {
  const fs::path base(path);
  const auto sibling = [&](const std::string& part, const std::string& ext) {
    return base.parent_path() / (base.stem().string() + "-" + file_part(part) + ext);
  };
  AucPlot auc;
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    const MetricScores& m = metrics[i];
    const ordered_json& statistics = j["metrics"][m.name]["statistics"];
    const MappingFunction& map = r.p1401[i].fit.function;
    ScatterPlot p{m.scores, subjective.mos, map,
                  m.name + ": PLCC " + json_fixed(statistics["plcc"]["value"], "%.3f") + ", SROCC " +
                      json_fixed(statistics["srocc"]["value"], "%.3f") + ", " +
                      std::string(mapping_name(map.mapping)) + " mapping",
                  m.name, mos_label.empty() ? "MOS" : mos_label};
    write_scatter_plot(sibling(m.name, base.extension().string()), p);
    if (r.krasula) {
      const KrasulaMetric& k = r.krasula->metrics[i];
      auc.names.push_back(m.name);
      auc.auc_ds.push_back(k.auc_ds);
      auc.se_ds.push_back(k.se_ds);
      auc.auc_bw.push_back(k.auc_bw);
      auc.se_bw.push_back(k.se_bw);
    }
  }
  if (r.krasula) {
    auc.title = "Krasula's AUCs (" + std::to_string(r.krasula->different) + " different, " +
                std::to_string(r.krasula->similar) + " similar pairs)";
    write_auc_plot(sibling("auc", base.extension().string()), auc);
  }
}

// Scores ranking against their orientation. Every metric of known orientation doing so clearly
// is evidence that the MOS runs the other way (a DMOS); one metric among others that agree
// merely correlates poorly: no warning. A column of assumed orientation (not a registered
// metric) clearly ranking the other way is probably a distortion.
void warn_orientation(const std::vector<MetricScores>& metrics, const ordered_json& j,
                      std::size_t n) {
  std::size_t known = 0, against = 0;
  std::string examples;
  for (const MetricScores& m : metrics) {
    const ordered_json& rho = j["metrics"][m.name]["statistics"]["srocc"]["value"];
    const bool opposite = rho.is_number() && clearly_nonzero(rho.get<double>(), n) &&
                          (rho.get<double>() > 0) != m.higher_is_better;
    if (m.orientation_source.rfind("assumed", 0) == 0) {
      if (opposite) {
        std::cerr << "qm3d: warning: " << m.name << " is taken as a quality ("
                  << m.orientation_source << ") but SROCC is " << json_fixed(rho)
                  << ": a distortion (--lower-is-better " << m.name
                  << ")? Krasula's BW analysis and C0 depend on it\n";
      }
      continue;
    }
    ++known;
    if (!opposite) continue;
    ++against;
    if (against <= 3) examples += (against > 1 ? ", " : "") + m.name + " " + json_fixed(rho);
  }
  if (known > 0 && against == known) {
    std::cerr << "qm3d: warning: every metric of known orientation ranks the stimuli the other way "
                 "(SROCC "
              << examples << (against > 3 ? ", ..." : "")
              << "): is the MOS column a DMOS (higher = worse)?\n";
  }
}

}  // namespace

std::string no_common_key(const CsvTable& scores, std::size_t scores_key, const CsvTable& mos,
                          std::size_t mos_key) {
  const auto first_key = [](const CsvTable& t, std::size_t column) -> std::string {
    for (const auto& row : t.rows) {
      if (column < row.size() && !row[column].empty()) return "\"" + row[column] + "\"";
    }
    return "none";
  };
  return "no stimulus in common between " + scores.path + " (key \"" + scores.header[scores_key] +
         "\", e.g. " + first_key(scores, scores_key) + ") and " + mos.path + " (key \"" +
         mos.header[mos_key] + "\", e.g. " + first_key(mos, mos_key) +
         "), whole or by file stem (--stem); choose the key columns with --scores-key and "
         "--mos-key";
}

bool clearly_nonzero(double rho, std::size_t n) {
  // 1.96: the two-sided 5% point of the standard normal distribution.
  return n >= 3 && std::isfinite(rho) && std::fabs(rho) * std::sqrt(double(n - 1)) > 1.96;
}

bool needs_protocol(const EvalCommandOptions& o, const CsvTable& scores) {
  return o.scores_column.find(',') != std::string::npos || o.scores_column == "all" ||
         !o.mapping.empty() || !o.more_scores.empty() ||
         !o.sd_column.empty() || !o.raw.empty() || !o.pairs.empty() ||
         split_by_metric(scores).size() > 1;
}

namespace {

// The tables of the series: each SCORES file (SCORES, then --more-scores), or its rows of each
// metric.
struct Part {
  std::string metric;
  CsvTable table;
  std::size_t key = 0;
  bool pivot = false;
};

// What `eval` reads for the protocol, step by step. Deques: the series point into them (and the
// object is never moved).
struct ProtocolData {
  const CsvTable* scores = nullptr;
  CsvTable mos;
  std::size_t key = 0, mos_key = 0, mos_value = 0;
  std::optional<std::size_t> ci;
  std::deque<Part> parts;
  std::deque<JoinedRows> joins;
  std::vector<Series> series;
  std::vector<std::map<std::string, double>> values;  ///< per series: key -> finite score
  KeyList left_out;
  Stimuli st;
  SubjectiveData subjective;
};

void read_tables(ProtocolData& d, const EvalCommandOptions& o, const CsvTable& scores) {
  d.scores = &scores;
  d.mos = read_csv_table(o.mos);
  d.key = key_column(scores, o.scores_key, "--scores-key");
  d.mos_key = o.mos_key.empty() ? 0 : require_column(d.mos, o.mos_key, "--mos-key");
  d.mos_value = value_column(d.mos, o.mos_column, {"mos"}, d.mos_key, "--mos-column");
  d.ci = o.ci_column.empty() ? std::nullopt
                             : std::optional(require_column(d.mos, o.ci_column, "--ci-column"));
  std::vector<CsvTable> files = {scores};
  for (const std::string& f : o.more_scores) files.push_back(read_csv_table(f));
  for (const CsvTable& t : files) {
    const std::size_t k = &t == &files.front() ? d.key : key_column(t, o.scores_key, "--scores-key");
    auto split = split_by_metric(t);
    const bool pivot = split.size() > 1;
    for (auto& [metric, table] : split) d.parts.push_back({metric, std::move(table), k, pivot});
  }
  bool joined = false;
  for (const Part& part : d.parts) {
    d.joins.push_back(join_on_key(part.table, part.key, d.mos, d.mos_key, o.stem));
    joined = joined || !d.joins.back().keys.empty();
  }
  if (!joined) throw FormatError(no_common_key(scores, d.key, d.mos, d.mos_key));
}

// The score columns of a part: "all" numeric ones, the default one, or the named ones.
std::vector<std::size_t> score_columns(const Part& part, const EvalCommandOptions& o) {
  std::vector<std::size_t> columns;
  if (o.scores_column == "all") {
    columns = numeric_columns(part.table, part.key);
  } else if (o.scores_column.empty()) {
    columns.push_back(value_column(part.table, "", {"score"}, part.key, "--scores-column"));
  } else {
    for (const std::string& c : split_list(o.scores_column)) {
      columns.push_back(require_column(part.table, c, "--scores-column"));
    }
  }
  return columns;
}

void make_series(ProtocolData& d, const EvalCommandOptions& o) {
  std::set<std::string> names_taken;
  for (std::size_t p = 0; p < d.parts.size(); ++p) {
    const CsvTable& t = d.parts[p].table;
    for (std::size_t c : score_columns(d.parts[p], o)) {
      const std::string& header = t.header[c];
      std::string name = header;
      if (d.parts[p].pivot) {
        name = header == "score" ? d.parts[p].metric : d.parts[p].metric + ":" + header;
      }
      // The same name from another file: its file stem in front ("run2:psnr").
      if (names_taken.count(name)) name = fs::path(t.path).stem().string() + ":" + name;
      names_taken.insert(name);
      d.series.push_back({name, &t, c, d.parts[p].metric, &d.joins[p]});
    }
  }
  if (d.series.empty()) throw FormatError(o.scores + ": no numeric score column");
  check_lower_is_better(d.series, o);
}

// Each series' finite scores by key. A series without a single finite score (a failed batch
// pair's "compare" row, a column of text) is left out with a warning rather than emptying the
// stimuli every series must share.
void collect_series_values(ProtocolData& d, const EvalCommandOptions& o, bool quiet) {
  d.values.resize(d.series.size());
  for (std::size_t s = 0; s < d.series.size(); ++s) {
    const JoinedRows& j = *d.series[s].join;
    for (std::size_t i = 0; i < j.keys.size(); ++i) {
      const auto v = cell_number(*d.series[s].table, j.left[i], d.series[s].column, true);
      if (v && std::isfinite(*v)) d.values[s][j.keys[i]] = *v;
    }
  }
  for (std::size_t k = d.series.size(); k-- > 0;) {
    if (!d.values[k].empty()) continue;
    if (!quiet) {
      std::cerr << "qm3d: warning: " << o.scores << ": " << d.series[k].name
                << " has no finite score on the stimuli of " << o.mos << "; left out\n";
    }
    d.series.erase(d.series.begin() + static_cast<std::ptrdiff_t>(k));
    d.values.erase(d.values.begin() + static_cast<std::ptrdiff_t>(k));
  }
  if (d.series.empty()) throw FormatError(o.scores + ": no finite score of any metric");
}

// The stimuli every series and the MOS have a finite value for: every joined key once, in the
// order the parts first name it, with its MOS row.
void select_stimuli(ProtocolData& d, const EvalCommandOptions& o) {
  std::map<std::string, std::size_t> mos_row;
  std::vector<std::string> candidates;
  for (const auto& j : d.joins) {
    for (std::size_t i = 0; i < j.keys.size(); ++i) {
      if (mos_row.emplace(j.keys[i], j.right[i]).second) candidates.push_back(j.keys[i]);
    }
  }
  for (const std::string& k : candidates) {
    const std::size_t row = mos_row.at(k);
    const auto m = cell_number(d.mos, row, d.mos_value);
    const auto c = d.ci ? cell_number(d.mos, row, *d.ci) : std::optional<double>(0);
    bool all = m && c;
    for (const auto& v : d.values) all = all && v.count(k);
    if (!all) {
      d.left_out.add(k);
      continue;
    }
    d.st.add(k, row);
    d.subjective.mos.push_back(*m);
    if (d.ci) d.subjective.ci95.push_back(*c);
  }
  if (d.st.keys.empty()) {
    throw FormatError("no stimulus in common between " + o.scores + " and " + o.mos +
                      " with a value of every metric");
  }
}

void warn_unjoined(const ProtocolData& d) {
  for (std::size_t p = 0; p < d.joins.size(); ++p) {
    const std::string what = d.parts[p].pivot ? " (" + d.parts[p].metric + ")" : "";
    if (d.joins[p].left_only.count) {
      std::cerr << "qm3d: warning: " << d.parts[p].table.path << what << ": "
                << d.joins[p].left_only.count << " rows have no partner in " << d.mos.path
                << ": " << d.joins[p].left_only.examples() << "\n";
    }
  }
  if (d.joins[0].right_only.count) {
    std::cerr << "qm3d: warning: " << d.mos.path << ": " << d.joins[0].right_only.count
              << " rows have no partner in " << d.scores->path << ": "
              << d.joins[0].right_only.examples() << "\n";
  }
  if (d.left_out.count) {
    std::cerr << "qm3d: warning: " << d.left_out.count
              << " stimuli left out (a metric's score empty, NaN or infinite, or no MOS): "
              << d.left_out.examples() << "\n";
  }
}

// Krasula's pair labels from --sd-column, --raw or --pairs (within --group-column's groups).
void label_stimuli(ProtocolData& d, const EvalCommandOptions& o) {
  std::vector<std::string> groups;
  if (!o.group_column.empty()) {
    const std::size_t g = require_column(d.mos, o.group_column, "--group-column");
    for (std::size_t row : d.st.mos_rows) groups.push_back(d.mos.rows[row][g]);
  }
  if (!o.sd_column.empty()) d.subjective.pairs = pairs_from_sd(d.mos, d.mos_value, d.st, o, groups);
  if (!o.raw.empty()) d.subjective.pairs = pairs_from_raw(o, d.st, groups);
  if (!o.pairs.empty()) d.subjective.pairs = pairs_from_file(o, d.st);
  if (d.subjective.pairs) check_pair_labels(*d.subjective.pairs, o);
}

std::vector<MetricScores> metric_scores(const ProtocolData& d, const EvalCommandOptions& o) {
  std::vector<MetricScores> metrics;
  for (std::size_t s = 0; s < d.series.size(); ++s) {
    MetricScores m;
    m.name = d.series[s].name;
    for (const std::string& k : d.st.keys) m.scores.push_back(d.values[s].at(k));
    orient_series(d.series[s], o, m);
    metrics.push_back(std::move(m));
  }
  return metrics;
}

// The files read, as the JSON names them (before the protocol's own fields).
ordered_json inputs_json(const ProtocolData& d, const EvalCommandOptions& o) {
  const CsvTable& scores = *d.scores;
  ordered_json j = {{"command", "eval"}, {"version", kVersion}};
  j["scores"] = {{"file", scores.path}, {"key", scores.header[d.key]}, {"rows", scores.rows.size()}};
  j["more_scores"] = o.more_scores;
  j["mos"] = {{"file", d.mos.path},
              {"key", d.mos.header[d.mos_key]},
              {"column", d.mos.header[d.mos_value]},
              {"ci_column", d.ci ? ordered_json(d.mos.header[*d.ci]) : ordered_json()},
              {"rows", d.mos.rows.size()}};
  j["key_match"] = o.stem ? "file stem" : "exact";
  j["left_out"] = {{"count", d.left_out.count}, {"first", d.left_out.first}};
  return j;
}

}  // namespace

int run_eval_protocol(const EvalCommandOptions& o, const CsvTable& scores, bool quiet) {
  const int sources = !o.sd_column.empty() + !o.raw.empty() + !o.pairs.empty();
  if (sources > 1) throw InputError("give one of --sd-column, --raw and --pairs");
  ProtocolData d;
  read_tables(d, o, scores);
  make_series(d, o);
  collect_series_values(d, o, quiet);
  select_stimuli(d, o);
  if (!quiet) warn_unjoined(d);
  label_stimuli(d, o);
  const std::vector<MetricScores> metrics = metric_scores(d, o);
  std::vector<std::string> names;
  for (const MetricScores& m : metrics) names.push_back(m.name);
  ProtocolOptions options;
  options.evaluation.bootstrap = o.bootstrap;
  options.evaluation.seed = o.seed;
  options.evaluation.confidence = kConfidence;
  options.mapping = parse_mapping(o.mapping.empty() ? "logistic4" : o.mapping);
  ordered_json j = inputs_json(d, o);
  const ProtocolResult result = run_protocol(metrics, d.subjective, options);
  j.update(protocol_json(metrics, d.subjective, result));
  j["bootstrap"] = {{"replicates", o.bootstrap},
                    {"seed", o.seed},
                    {"confidence", kConfidence},
                    {"method", "percentile; stimuli resampled with replacement; mapping refitted"}};
  if (!quiet) warn_orientation(metrics, j, d.st.keys.size());
  if (!o.plot.empty()) plot_protocol(o.plot, metrics, d.subjective, result, j, o.mos_column);
  emit_text(o.json ? j.dump(2) + "\n" : o.csv ? protocol_csv(j, names) : protocol_text(j, names),
            o.output);
  return 0;
}

}  // namespace qm3d::app
