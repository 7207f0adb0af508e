#include "train_command.h"

#include <bitset>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "qm3d/common/error.h"
#include "qm3d/common/table_text.h"
#include "qm3d/common/file_io.h"
#include "qm3d/evaluation/model_io.h"
#include "qm3d/evaluation/training.h"
#include "qm3d/common/version.h"
#include "qm3d/common/result_io.h"
#include "qm3d/evaluation/score_table.h"

namespace qm3d::app {
using namespace qm3d::evaluation;  // NOLINT: the library this command prints
namespace {

using ordered_json = nlohmann::ordered_json;

/// Subsets listed by the human summary (all of them go to --report and --json).
constexpr std::size_t kSubsetsShown = 10;
/// Feature prefixes of `qm3d batch` results, one per direction.
constexpr const char* kDistToRefPrefix = "dist_to_ref_f";
constexpr const char* kRefToDistPrefix = "ref_to_dist_f";
/// The column of `qm3d batch` results naming the metric.
constexpr const char* kMetricColumn = "metric";

struct TrainData {
  CsvTable features_table, mos_table;
  std::size_t features_key = 0, mos_key = 0, mos_value = 0;
  std::vector<std::string> prefixes;
  JoinedRows join;
  KeyList missing;
  std::vector<std::size_t> rows;  ///< joined row index (into join) of each stimulus kept
  TrainingSet set;
  std::string metric;
};

// ---- feature columns -----------------------------------------------------------------------

std::vector<std::size_t> prefix_columns(const CsvTable& t, const std::string& prefix) {
  std::vector<std::size_t> cols;
  for (std::size_t k = 1; k <= kNumFeatures; ++k) {
    cols.push_back(require_column(t, prefix + std::to_string(k), "--features"));
  }
  return cols;
}

bool has_prefix(const CsvTable& t, const std::string& prefix) {
  return find_column(t, prefix + "1").has_value();
}

// True when every feature cell of `prefix` in row r is a number.
bool complete(const CsvTable& t, std::size_t r, const std::string& prefix) {
  for (std::size_t c : prefix_columns(t, prefix)) {
    if (!cell_number(t, r, c)) return false;
  }
  return true;
}

// The batch directions present in every joined row that has any (see --features auto).
std::vector<std::string> batch_prefixes(const TrainData& d) {
  std::size_t any = 0, both = 0, d2r = 0, r2d = 0;
  for (std::size_t r : d.join.left) {
    const bool a = complete(d.features_table, r, kDistToRefPrefix);
    const bool b = complete(d.features_table, r, kRefToDistPrefix);
    any += a || b;
    both += a && b;
    d2r += a;
    r2d += b;
  }
  if (any > 0 && both == any) return {kDistToRefPrefix, kRefToDistPrefix};
  if (any > 0 && r2d == any) return {kRefToDistPrefix};
  if (any > 0 && d2r == any) return {kDistToRefPrefix};
  throw FormatError(d.features_table.path +
                    ": the rows do not share a direction with complete features; choose one "
                    "with --features " +
                    kDistToRefPrefix + " or " + kRefToDistPrefix);
}

std::vector<std::string> resolve_prefixes(const TrainData& d, const std::string& spec) {
  const CsvTable& t = d.features_table;
  if (spec != "auto") {
    std::vector<std::string> prefixes;
    std::istringstream in(spec);
    for (std::string p; std::getline(in, p, ',');) prefixes.push_back(p);
    for (const std::string& p : prefixes) prefix_columns(t, p);  // each must exist
    return prefixes;
  }
  if (has_prefix(t, "f")) return {"f"};
  if (has_prefix(t, "F")) return {"F"};
  if (has_prefix(t, kDistToRefPrefix) && has_prefix(t, kRefToDistPrefix)) return batch_prefixes(d);
  throw FormatError(t.path + ": no feature columns f1..f8 (nor the batch columns " +
                    kDistToRefPrefix + "1.., " + kRefToDistPrefix +
                    "1..); set them with --features");
}

// The mean over the prefixes of the features of row r; nullopt when a cell is empty.
std::optional<FeatureVector> row_features(const TrainData& d, std::size_t r) {
  FeatureVector sum{};
  for (const std::string& prefix : d.prefixes) {
    const std::vector<std::size_t> cols = prefix_columns(d.features_table, prefix);
    for (std::size_t k = 0; k < kNumFeatures; ++k) {
      const auto v = cell_number(d.features_table, r, cols[k]);
      if (!v) return std::nullopt;
      sum[k] += *v;
    }
  }
  for (double& v : sum) v /= static_cast<double>(d.prefixes.size());
  return sum;
}

// ---- groups, metric, rows ------------------------------------------------------------------

// The label of each kept stimulus in column `name` (FEATURES first, then MOS).
Grouping grouping_of(const TrainData& d, const std::string& name) {
  const auto in_features = find_column(d.features_table, name);
  const auto in_mos = find_column(d.mos_table, name);
  if (!in_features && !in_mos) {
    throw FormatError("--group-by: no column \"" + name + "\" in " + d.features_table.path +
                      " or " + d.mos_table.path);
  }
  Grouping g{name, {}};
  for (std::size_t i : d.rows) {
    g.labels.push_back(in_features ? d.features_table.rows[d.join.left[i]][*in_features]
                                   : d.mos_table.rows[d.join.right[i]][*in_mos]);
  }
  return g;
}

std::string metric_of(const TrainData& d, const std::string& given) {
  if (!given.empty()) return given;
  const auto c = find_column(d.features_table, kMetricColumn);
  std::set<std::string> names;
  for (std::size_t i : d.rows) {
    if (c) names.insert(d.features_table.rows[d.join.left[i]][*c]);
  }
  if (names.size() == 1 && !names.begin()->empty()) return *names.begin();
  throw FormatError(d.features_table.path +
                    (c ? ": the rows are of several metrics" : ": no \"metric\" column") +
                    "; say which metric the model is for with --metric cmdm|pcqm");
}

void collect_rows(TrainData& d) {
  for (std::size_t i = 0; i < d.join.keys.size(); ++i) {
    const auto f = row_features(d, d.join.left[i]);
    const auto mos = cell_number(d.mos_table, d.join.right[i], d.mos_value);
    if (!f || !mos) {
      d.missing.add(d.join.keys[i]);
      continue;
    }
    d.rows.push_back(i);
    d.set.features.push_back(*f);
    d.set.mos.push_back(*mos);
  }
  if (d.rows.empty()) {
    throw FormatError("no stimulus of " + d.features_table.path +
                      " has all its features and a MOS");
  }
}

TrainData load_train_data(const TrainCommandOptions& o) {
  TrainData d;
  d.features_table = read_csv_table(o.features);
  d.mos_table = read_csv_table(o.mos);
  d.features_key = key_column(d.features_table, o.features_key, "--features-key");
  d.mos_key = o.mos_key.empty() ? 0 : require_column(d.mos_table, o.mos_key, "--mos-key");
  d.mos_value = value_column(d.mos_table, o.mos_column, {"mos"}, d.mos_key, "--mos-column");
  d.join = join_on_key(d.features_table, d.features_key, d.mos_table, d.mos_key, o.stem);
  if (d.join.keys.empty()) {
    throw FormatError("no stimulus in common between " + d.features_table.path + " (key \"" +
                      d.features_table.header[d.features_key] + "\") and " + d.mos_table.path +
                      " (key \"" + d.mos_table.header[d.mos_key] + "\"); try --stem for paths");
  }
  d.prefixes = resolve_prefixes(d, o.feature_columns);
  collect_rows(d);
  for (const std::string& g : o.group_by) d.set.groupings.push_back(grouping_of(d, g));
  d.metric = metric_of(d, o.metric);
  return d;
}

TrainingOptions training_options(const TrainCommandOptions& o) {
  TrainingOptions t;
  for (const std::string& s : o.subsets) t.subsets.push_back(parse_subset(s));
  t.criterion = o.criterion == "srocc"  ? SubsetCriterion::kSrocc
                : o.criterion == "both" ? SubsetCriterion::kPlccAndSrocc
                                        : SubsetCriterion::kPlcc;
  t.selection = o.select == "best" ? SubsetSelection::kBest : SubsetSelection::kOneStandardError;
  t.final_weights = o.final_weights == "refit" ? FinalWeights::kRefit : FinalWeights::kMeanOfFolds;
  return t;
}

// ---- writing -------------------------------------------------------------------------------

const SubsetScore& chosen_score(const TrainingResult& r) {
  for (const SubsetScore& s : r.subsets) {
    if (s.subset == r.best) return s;
  }
  return r.subsets.front();
}

std::string joined(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : ",") + s;
  return out;
}

ModelFile model_file(const TrainData& d, const TrainingResult& r, const TrainCommandOptions& o) {
  const SubsetScore& s = chosen_score(r);
  const std::string provenance =
      "qm3d " + std::string(kVersion) + " train " + o.features + " " + o.mos + " --group-by " +
      joined(o.group_by) + ": " + std::to_string(d.set.mos.size()) + " stimuli, subset " +
      subset_name(r.best) + " chosen (" + o.select + ", " + o.criterion + ") among " +
      std::to_string(r.subsets.size()) + " by leave-one-group-out cross-validation over " +
      std::to_string(r.folds.size()) + " folds (mean held-out PLCC " + fixed(s.plcc_mean) +
      ", SROCC " + fixed(s.srocc_mean) + "); weights: " + o.final_weights;
  return {LinearModel{d.metric, r.model.weights, provenance}, r.model.mos_mapping};
}

ordered_json number(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(); }

ordered_json subset_json(const SubsetScore& s, std::size_t rank, FeatureMask chosen) {
  return {{"rank", rank},
          {"subset", subset_name(s.subset)},
          {"features", std::bitset<kNumFeatures>(s.subset).count()},
          {"plcc_mean", number(s.plcc_mean)},
          {"plcc_sd", number(s.plcc_sd)},
          {"srocc_mean", number(s.srocc_mean)},
          {"srocc_sd", number(s.srocc_sd)},
          {"chosen", s.subset == chosen},
          {"error", s.error.empty() ? ordered_json() : ordered_json(s.error)}};
}

ordered_json subsets_json(const TrainingResult& r) {
  ordered_json list = ordered_json::array();
  for (std::size_t i = 0; i < r.subsets.size(); ++i)
    list.push_back(subset_json(r.subsets[i], i + 1, r.best));
  return list;
}

ordered_json train_json(const TrainData& d, const TrainingResult& r, const ModelFile& model,
                        const TrainCommandOptions& o) {
  ordered_json j = {{"command", "train"}, {"version", kVersion}};
  j["features"] = {{"file", d.features_table.path},
                   {"key", d.features_table.header[d.features_key]},
                   {"prefixes", d.prefixes},
                   {"rows", d.features_table.rows.size()}};
  j["mos"] = {{"file", d.mos_table.path},
              {"key", d.mos_table.header[d.mos_key]},
              {"column", d.mos_table.header[d.mos_value]},
              {"rows", d.mos_table.rows.size()}};
  j["stimuli"] = d.set.mos.size();
  j["unmatched"] = {
      {"features", {{"count", d.join.left_only.count}, {"first", d.join.left_only.first}}},
      {"mos", {{"count", d.join.right_only.count}, {"first", d.join.right_only.first}}}};
  j["missing_values"] = {{"count", d.missing.count}, {"first", d.missing.first}};
  j["group_by"] = o.group_by;
  j["folds"] = r.folds;
  j["criterion"] = o.criterion;
  j["selection"] = o.select;
  j["final_weights"] = o.final_weights;
  j["chosen"] = subset_json(chosen_score(r), 0, r.best);
  j["chosen"].erase("rank");
  j["model"] = ordered_json::parse(model_to_json(model));
  j["subsets"] = subsets_json(r);
  return j;
}

std::string report_csv(const TrainingResult& r) {
  std::ostringstream out;
  out << "rank,subset,features,plcc_mean,plcc_sd,srocc_mean,srocc_sd,chosen,error\n";
  for (std::size_t i = 0; i < r.subsets.size(); ++i) {
    const SubsetScore& s = r.subsets[i];
    out << i + 1 << ',' << csv_field(subset_name(s.subset)) << ','
        << std::bitset<kNumFeatures>(s.subset).count() << ',' << format_double(s.plcc_mean) << ','
        << format_double(s.plcc_sd) << ',' << format_double(s.srocc_mean) << ','
        << format_double(s.srocc_sd) << ',' << (s.subset == r.best ? "yes" : "no") << ','
        << csv_field(s.error) << "\n";
  }
  return out.str();
}

std::string subset_line(const SubsetScore& s, std::size_t rank, FeatureMask chosen) {
  const std::string note = s.subset == chosen ? "   <- chosen"
                           : s.error.empty()  ? ""
                                              : "   " + s.error;
  char line[160];
  std::snprintf(line, sizeof line, "%4zu  %-24s %s ± %s   %s ± %s", rank,
                subset_name(s.subset).c_str(), fixed(s.plcc_mean).c_str(), fixed(s.plcc_sd).c_str(),
                fixed(s.srocc_mean).c_str(), fixed(s.srocc_sd).c_str());
  return line + note + "\n";
}

std::string train_text(const TrainData& d, const TrainingResult& r, const TrainCommandOptions& o) {
  std::ostringstream out;
  out << d.set.mos.size() << " stimuli, features " << joined(d.prefixes) << " of " << d.metric
      << ", " << r.folds.size() << " folds (" << joined(o.group_by) << "), " << r.subsets.size()
      << " subsets\nrank  subset                   PLCC (mean ± sd)   SROCC (mean ± sd)\n";
  for (std::size_t i = 0; i < r.subsets.size(); ++i) {
    if (i < kSubsetsShown || r.subsets[i].subset == r.best)
      out << subset_line(r.subsets[i], i + 1, r.best);
  }
  out << "weights:";
  for (std::size_t k = 0; k < kNumFeatures; ++k) {
    if (r.model.weights[k] != 0)
      out << " " << feature_name(k) << " " << fixed(r.model.weights[k], "%.6g");
  }
  const LogisticFunction& f = r.model.mos_mapping;
  out << "\nmapping: MOS = " << fixed(f.beta2, "%.6g") << " + (" << fixed(f.beta1, "%.6g") << " - "
      << fixed(f.beta2, "%.6g") << ") / (1 + exp(-(score - " << fixed(f.beta3, "%.6g") << ") / "
      << fixed(std::fabs(f.beta4), "%.6g") << "))\n";
  if (!o.output.empty()) out << "model written to " << o.output << "\n";
  return out.str();
}

void write_report(const std::string& path, const TrainData& d, const TrainingResult& r,
                  const ModelFile& model, const TrainCommandOptions& o) {
  const std::string ext = lower_extension(path);
  if (ext != "csv" && ext != "json") {
    throw InputError(path + ": unknown report format \"" + ext + "\" (use .csv or .json)");
  }
  const std::string text = ext == "csv" ? report_csv(r) : train_json(d, r, model, o).dump(2) + "\n";
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

void warn_partial_join(const TrainData& d, bool quiet) {
  if (quiet) return;
  if (d.join.left_only.count) {
    std::cerr << "qm3d: warning: " << d.features_table.path << ": " << d.join.left_only.count
              << " rows have no partner in " << d.mos_table.path << ": "
              << d.join.left_only.examples() << "\n";
  }
  if (d.join.right_only.count) {
    std::cerr << "qm3d: warning: " << d.mos_table.path << ": " << d.join.right_only.count
              << " rows have no partner in " << d.features_table.path << ": "
              << d.join.right_only.examples() << "\n";
  }
  if (d.missing.count) {
    std::cerr << "qm3d: warning: " << d.missing.count
              << " stimuli left out (empty features or MOS): " << d.missing.examples() << "\n";
  }
}

}  // namespace

int run_train(const TrainCommandOptions& o, bool quiet) {
  check_outputs({{"FEATURES", o.features}, {"MOS", o.mos}},
                {{"-o", o.output}, {"--report", o.report}});
  const TrainData d = load_train_data(o);
  warn_partial_join(d, quiet);
  const TrainingResult r = train_linear_model(d.set, training_options(o));
  const ModelFile model = model_file(d, r, o);
  if (!o.output.empty()) write_model(o.output, model);
  if (!o.report.empty()) write_report(o.report, d, r, model, o);
  const std::string text = o.json ? train_json(d, r, model, o).dump(2) + "\n" : train_text(d, r, o);
  std::cout << text << std::flush;
  if (!std::cout) throw InputError("stdout: write failed");
  return 0;
}

}  // namespace qm3d::app
