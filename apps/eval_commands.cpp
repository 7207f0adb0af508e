#include "eval_commands.h"
#include "emit_text.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "qm3d/report/eval_plot.h"
#include "eval_protocol.h"
#include "qm3d/common/error.h"
#include "qm3d/common/table_text.h"
#include "qm3d/evaluation/evaluation.h"
#include "qm3d/evaluation/evaluation_io.h"
#include "qm3d/evaluation/orientation.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/version.h"
#include "qm3d/scoring/score.h"
#include "qm3d/evaluation/score_table.h"
#include "train_command.h"

namespace qm3d::app {
using namespace qm3d::scoring;  // NOLINT: the scoring this command drives
using namespace qm3d::report;  // NOLINT: the library this command drives
using namespace qm3d::evaluation;  // NOLINT: the library this command prints
namespace {

using ordered_json = nlohmann::ordered_json;

/// Coverage of the bootstrap intervals (the "95%" of the issue and of P.1401).
constexpr double kConfidence = 0.95;

// ---- reading and joining -------------------------------------------------------------------

struct EvalData {
  CsvTable scores_table, mos_table;
  std::size_t scores_key = 0, scores_value = 0, mos_key = 0, mos_value = 0;
  std::optional<std::size_t> ci;
  JoinedRows join;
  KeyList missing;  ///< joined rows with an empty score, MOS or CI (e.g. failed batch pairs)
  KeyList infinite;  ///< joined rows whose score is infinite (PSNR of identical geometry)
  std::vector<std::string> keys;
  std::vector<double> scores, mos, ci95;
  /// Whether a higher score is better (a quality): from --orientation, else from the metric the
  /// SCORES rows name; nullopt when neither says.
  std::optional<bool> higher_is_better;
  std::string orientation_source;  ///< "--orientation", "metric column: psnr", or empty
};

// The distinct non-empty keys of a column, whole or by file stem (a batch file names a stimulus
// once per metric: a set, not join_on_key, which refuses repeated keys).
std::set<std::string> key_set(const CsvTable& t, std::size_t column, bool by_stem) {
  std::set<std::string> keys;
  for (const auto& row : t.rows) {
    if (column < row.size() && !row[column].empty()) {
      keys.insert(by_stem ? stem_of(row[column]) : row[column]);
    }
  }
  return keys;
}

bool any_common(const std::set<std::string>& a, const std::set<std::string>& b) {
  for (const std::string& k : a) {
    if (b.count(k)) return true;
  }
  return false;
}

// Whether the keys of SCORES and MOS must be compared by file stem: --stem, or automatically
// when no key matches whole but some match by stem (batch paths against stimulus names; said in
// a note).
bool match_by_stem(const CsvTable& scores, const EvalCommandOptions& o, bool quiet) {
  const CsvTable mos = read_csv_table(o.mos);
  const std::size_t sk = key_column(scores, o.scores_key, "--scores-key");
  const std::size_t mk = o.mos_key.empty() ? 0 : require_column(mos, o.mos_key, "--mos-key");
  if (!o.stem && any_common(key_set(scores, sk, false), key_set(mos, mk, false))) return false;
  const bool by_stem = any_common(key_set(scores, sk, true), key_set(mos, mk, true));
  if (by_stem && !o.stem && !quiet) {
    std::cerr << "qm3d: note: no key of " << scores.path << " equals one of " << mos.path
              << "; matching them by file stem (as --stem)\n";
  }
  return by_stem || o.stem;  // none matching either way: said where the rows are joined
}

void check_something_joined(const EvalData& d) {
  if (!d.join.keys.empty()) return;
  throw FormatError(no_common_key(d.scores_table, d.scores_key, d.mos_table, d.mos_key));
}

void collect_values(EvalData& d) {
  for (std::size_t i = 0; i < d.join.keys.size(); ++i) {
    const auto score = cell_number(d.scores_table, d.join.left[i], d.scores_value, true);
    const auto mos = cell_number(d.mos_table, d.join.right[i], d.mos_value);
    const auto ci =
        d.ci ? cell_number(d.mos_table, d.join.right[i], *d.ci) : std::optional<double>(0);
    if (!score || !mos || !ci) {
      d.missing.add(d.join.keys[i]);
      continue;
    }
    if (std::isinf(*score)) {
      d.infinite.add(d.join.keys[i]);
      continue;
    }
    if (*ci < 0) {
      throw FormatError(d.mos_table.path + ":" +
                        std::to_string(d.mos_table.line_numbers[d.join.right[i]]) + ": column \"" +
                        d.mos_table.header[*d.ci] + "\": a confidence interval cannot be negative");
    }
    d.keys.push_back(d.join.keys[i]);
    d.scores.push_back(*score);
    d.mos.push_back(*mos);
    if (d.ci) d.ci95.push_back(*ci);
  }
}

// The metric every used row of SCORES names in its "metric" column (batch results); empty when
// the file has no metric column, or a row names none or another metric.
std::string the_metric(const EvalData& d) {
  const auto c = find_column(d.scores_table, "metric");
  if (!c) return "";
  std::string metric;
  for (std::size_t row : d.join.left) {
    const auto& cells = d.scores_table.rows[row];
    const std::string name = *c < cells.size() ? cells[*c] : std::string();
    if (name.empty() || (!metric.empty() && name != metric)) return "";
    metric = name;
  }
  return metric;
}

// The orientation of the score column (qm3d::evaluation::orient, Fallback::none):
// --lower-is-better, --orientation, else the registered metric every used row of SCORES names in
// its "metric" column (batch results), asked about that column ("score", "d1_mse",
// "dist_to_ref_d1_psnr"...); unknown for columns the metric does not describe (f1..f8) and for
// files without a metric column or with several metrics.
void find_orientation(EvalData& d, const EvalCommandOptions& o) {
  // A name that is not the evaluated column (a typo) is refused, never silently ignored.
  const std::string& evaluated = d.scores_table.header[d.scores_value];
  for (const std::string& name : o.lower_is_better) {
    if (name != evaluated) {
      throw InputError("--lower-is-better " + name +
                       ": no such score column (evaluated: " + evaluated + ")");
    }
  }
  const Orientation orientation =
      orient(default_registry(), {o.lower_is_better, o.orientation},
             {evaluated, the_metric(d), evaluated}, Fallback::none);
  d.higher_is_better = orientation.higher_is_better;
  d.orientation_source = orientation.source;
}

EvalData load_eval_data(const EvalCommandOptions& o, CsvTable scores) {
  EvalData d;
  d.scores_table = std::move(scores);
  d.mos_table = read_csv_table(o.mos);
  d.scores_key = key_column(d.scores_table, o.scores_key, "--scores-key");
  d.scores_value =
      value_column(d.scores_table, o.scores_column, {"score"}, d.scores_key, "--scores-column");
  d.mos_key = o.mos_key.empty() ? 0 : require_column(d.mos_table, o.mos_key, "--mos-key");
  d.mos_value = value_column(d.mos_table, o.mos_column, {"mos"}, d.mos_key, "--mos-column");
  if (!o.ci_column.empty()) d.ci = require_column(d.mos_table, o.ci_column, "--ci-column");
  d.join = join_on_key(d.scores_table, d.scores_key, d.mos_table, d.mos_key, o.stem);
  check_something_joined(d);
  collect_values(d);
  find_orientation(d, o);
  return d;
}

void warn_partial_join(const EvalData& d, bool quiet) {
  if (quiet) return;
  if (d.join.left_only.count) {
    std::cerr << "qm3d: warning: " << d.scores_table.path << ": " << d.join.left_only.count
              << " rows have no partner in " << d.mos_table.path << ": "
              << d.join.left_only.examples() << "\n";
  }
  if (d.join.right_only.count) {
    std::cerr << "qm3d: warning: " << d.mos_table.path << ": " << d.join.right_only.count
              << " rows have no partner in " << d.scores_table.path << ": "
              << d.join.right_only.examples() << "\n";
  }
  if (d.missing.count) {
    std::cerr << "qm3d: warning: " << d.missing.count
              << " stimuli left out (empty or NaN score, MOS or CI): " << d.missing.examples()
              << "\n";
  }
  if (d.infinite.count) {
    std::cerr << "qm3d: warning: " << d.infinite.count
              << " stimuli left out (infinite score, e.g. the PSNR of an unchanged geometry): "
              << d.infinite.examples() << "\n";
  }
}

// ---- writing -------------------------------------------------------------------------------

ordered_json keys_json(const KeyList& k) { return {{"count", k.count}, {"first", k.first}}; }

ordered_json table_json(const CsvTable& t, std::size_t key, std::size_t value, std::size_t rows) {
  return {{"file", t.path}, {"key", t.header[key]}, {"column", t.header[value]}, {"rows", rows}};
}

// Whether the scores rank the stimuli the way their orientation says (a quality rising with the
// MOS: SROCC > 0; a distortion falling: SROCC < 0); nullopt when the orientation is unknown or
// SROCC is 0 or NaN.
std::optional<bool> agrees(const EvalData& d, const EvaluationResult& r) {
  const double rho = r.srocc.value;
  if (!d.higher_is_better || !(rho != 0) || std::isnan(rho)) return std::nullopt;
  return (rho > 0) == *d.higher_is_better;
}

std::string orientation_text(const EvalData& d) {
  if (!d.higher_is_better) return "unknown (set it with --orientation quality|distortion)";
  return std::string(*d.higher_is_better ? "quality (higher is better)"
                                         : "distortion (lower is better)") +
         ", from " + d.orientation_source;
}

ordered_json eval_json(const EvalData& d, const EvaluationResult& r, const EvalCommandOptions& o) {
  ordered_json j = {{"command", "eval"}, {"version", kVersion}};
  j["scores"] =
      table_json(d.scores_table, d.scores_key, d.scores_value, d.scores_table.rows.size());
  j["mos"] = table_json(d.mos_table, d.mos_key, d.mos_value, d.mos_table.rows.size());
  j["mos"]["ci_column"] = d.ci ? ordered_json(d.mos_table.header[*d.ci]) : ordered_json();
  j["key_match"] = o.stem ? "file stem" : "exact";
  j["stimuli"] = r.count;
  j["unmatched"] = {{"scores", keys_json(d.join.left_only)}, {"mos", keys_json(d.join.right_only)}};
  j["missing_values"] = keys_json(d.missing);
  j["infinite_scores"] = keys_json(d.infinite);
  j["orientation"] = {
      {"higher_is_better", d.higher_is_better ? ordered_json(*d.higher_is_better) : ordered_json()},
      {"from", d.orientation_source.empty() ? ordered_json() : ordered_json(d.orientation_source)},
      {"agrees", d.higher_is_better && agrees(d, r) ? ordered_json(*agrees(d, r)) : ordered_json()}};
  for (const auto& [name, s] : named_statistics(r)) j["statistics"][name] = statistic_json(s);
  j["logistic"] = logistic_json(r.fit);
  j["bootstrap"] = {
      {"replicates", r.bootstrap_replicates},
      {"used", r.bootstrap_used},
      {"seed", o.seed},
      {"confidence", kConfidence},
      {"method", "percentile; stimuli resampled with replacement; logistic refitted"}};
  return j;
}

std::string eval_csv(const EvaluationResult& r) {
  std::ostringstream out;
  out << "statistic,value,ci95_low,ci95_high\nstimuli," << r.count << ",,\n";
  for (const auto& [name, s] : named_statistics(r)) {
    out << name << ',' << format_double(s.value) << ','
        << (s.ci ? format_double(s.ci->low) + ',' + format_double(s.ci->high) : std::string(","))
        << "\n";
  }
  return out.str();
}

const char* display_name(const std::string& name) {
  if (name == "plcc") return "PLCC";
  if (name == "srocc") return "SROCC";
  if (name == "krocc") return "KROCC";
  if (name == "plcc_logistic") return "PLCC (logistic)";
  if (name == "rmse_logistic") return "RMSE (logistic)";
  return "outlier ratio";
}

// The column header of the text table, saying where the intervals come from.
std::string interval_header(const EvaluationResult& r, const EvalCommandOptions& o) {
  char line[160];
  if (r.bootstrap_replicates == 0) {
    std::snprintf(line, sizeof line, "%-17s %9s   95%% CI: none (--bootstrap 0)\n", "", "value");
  } else {
    std::snprintf(line, sizeof line,
                  "%-17s %9s   95%% CI (bootstrap: %zu of %zu replicates, seed %llu)\n", "",
                  "value", r.bootstrap_used, r.bootstrap_replicates,
                  static_cast<unsigned long long>(o.seed));
  }
  return line;
}

std::string eval_text(const EvalData& d, const EvaluationResult& r, const EvalCommandOptions& o) {
  std::ostringstream out;
  out << r.count << " stimuli: " << d.scores_table.path << " (key "
      << d.scores_table.header[d.scores_key] << ", score " << d.scores_table.header[d.scores_value]
      << ") vs " << d.mos_table.path << " (key " << d.mos_table.header[d.mos_key] << ", MOS "
      << d.mos_table.header[d.mos_value] << ")\n";
  out << "orientation: " << orientation_text(d)
      << "; the signs of PLCC, SROCC and KROCC are those of the scores\n";
  out << interval_header(r, o);
  char line[160];
  for (const auto& [name, s] : named_statistics(r)) {
    const std::string ci = s.ci ? "[" + fixed(s.ci->low) + ", " + fixed(s.ci->high) + "]" : "-";
    std::snprintf(line, sizeof line, "%-17s %9s   %s\n", display_name(name), fixed(s.value).c_str(),
                  ci.c_str());
    out << line;
  }
  const LogisticFunction& f = r.fit.function;
  out << "logistic: MOS = " << fixed(f.beta2, "%.6g") << " + (" << fixed(f.beta1, "%.6g") << " - "
      << fixed(f.beta2, "%.6g") << ") / (1 + exp(-(score - " << fixed(f.beta3, "%.6g") << ") / "
      << fixed(std::fabs(f.beta4), "%.6g") << "))"
      << (r.fit.converged ? ""
          : r.fit.bounded ? "  [stopped at the bound: nearly linear or a step]"
                          : "  [not converged]")
      << "\n";
  return out.str();
}


void plot_eval(const EvalData& d, const EvaluationResult& r, const std::string& path) {
  ScatterPlot p{d.scores, d.mos, r.fit.function, "", "", ""};
  p.title = "PLCC " + fixed(r.plcc.value, "%.3f") + ", SROCC " + fixed(r.srocc.value, "%.3f") +
            ", PLCC after logistic " + fixed(r.plcc_logistic.value, "%.3f") + " (" +
            std::to_string(r.count) + " stimuli)";
  p.x_label = d.scores_table.header[d.scores_value] + " (" +
              std::filesystem::path(d.scores_table.path).filename().string() + ")";
  p.y_label = d.mos_table.header[d.mos_value] + " (" +
              std::filesystem::path(d.mos_table.path).filename().string() + ")";
  write_scatter_plot(path, p);
}

int run_eval(const EvalCommandOptions& given, bool quiet) {
  check_outputs({{"SCORES", given.scores}, {"MOS", given.mos}},
                {{"-o", given.output}, {"--plot", given.plot}});
  CsvTable scores = read_csv_table(given.scores);
  EvalCommandOptions o = given;
  o.stem = match_by_stem(scores, given, quiet);
  if (needs_protocol(o, scores)) return run_eval_protocol(o, scores, quiet);
  const EvalData d = load_eval_data(o, std::move(scores));
  warn_partial_join(d, quiet);
  EvaluationOptions options;
  options.bootstrap = o.bootstrap;
  options.seed = o.seed;
  options.confidence = kConfidence;
  const EvaluationResult r = evaluate_scores(d.scores, d.mos, d.ci95, options);
  if (!quiet && !r.fit.converged && !r.fit.bounded) {
    std::cerr << "qm3d: warning: the logistic fit did not converge in its evaluation budget\n";
  }
  // One column: it is every metric of known orientation, so a clear disagreement is evidence.
  if (!quiet && agrees(d, r) == false && clearly_nonzero(r.srocc.value, r.count)) {
    std::cerr << "qm3d: warning: " << d.scores_table.path << ": column \""
              << d.scores_table.header[d.scores_value] << "\" is a "
              << (*d.higher_is_better ? "quality (higher is better)" : "distortion (lower is better)")
              << " but SROCC with " << d.mos_table.header[d.mos_value] << " is "
              << fixed(r.srocc.value) << ": is the MOS column a DMOS, or the orientation wrong?\n";
  }
  const std::string text = o.json  ? eval_json(d, r, o).dump(2) + "\n"
                           : o.csv ? eval_csv(r)
                                   : eval_text(d, r, o);
  if (!o.plot.empty()) plot_eval(d, r, o.plot);
  emit_text(text, o.output);
  return 0;
}

// ---- registration --------------------------------------------------------------------------

// The two tables and their key and score columns.
void add_eval_input_options(CLI::App* cmd, EvalCommandOptions& o) {
  cmd->add_option("SCORES", o.scores, "CSV of objective scores (e.g. the results of qm3d batch)")
      ->required();
  cmd->add_option("MOS", o.mos, "CSV of subjective scores")->required();
  cmd->add_option("--scores-key", o.scores_key,
                  "Stimulus column of SCORES (default: 'distorted' if present, else the first)");
  cmd->add_option("--scores-column", o.scores_column,
                  "Score column(s) of SCORES: NAME, NAME1,NAME2,... (compared side by side) or "
                  "'all' (every numeric column); default: 'score', else the other column of "
                  "two. A batch file of several metrics gives one column per metric");
  cmd->add_option("--mos-key", o.mos_key, "Stimulus column of MOS (default: the first)");
  cmd->add_option("--mos-column", o.mos_column,
                  "MOS column of MOS (default: 'mos' in any case, else the other column of two)");
  cmd->add_option("--ci-column", o.ci_column,
                  "Column of MOS holding the 95% confidence-interval half-widths; adds the outlier "
                  "ratio (ITU-T P.1401)");
  cmd->add_flag("--stem", o.stem,
                "Match keys by file stem (directories and extension removed), e.g. batch paths "
                "against stimulus names");
}

// Which way the scores go, and more score files.
void add_eval_orientation_options(CLI::App* cmd, EvalCommandOptions& o) {
  cmd->add_option("--orientation", o.orientation,
                  "Whether a higher score is better: quality, distortion, or auto (from the "
                  "registered metric SCORES' metric column names: psnr is a quality, cmdm a "
                  "distortion); reported, and a warning when the scores rank the other way")
      ->check(CLI::IsMember({"auto", "distortion", "quality"}))
      ->capture_default_str();
  cmd->add_option("--more-scores", o.more_scores,
                  "More SCORES files (repeatable): their score columns (or batch metrics) are "
                  "compared with SCORES's, joined on the same key; a name already taken gets "
                  "its file's stem in front (run2:psnr)")
      ->type_name("FILE")
      ->allow_extra_args(false);
  cmd->add_option("--lower-is-better", o.lower_is_better,
                  "Score columns that are distortions, for Krasula's analysis (registered "
                  "metrics are oriented by themselves; other columns are taken as qualities)")
      ->delimiter(',')
      ->allow_extra_args(false);
}

// How the pairs of Krasula's analysis are labelled.
void add_krasula_label_options(CLI::App* cmd, EvalCommandOptions& o) {
  cmd->add_option("--sd-column", o.sd_column,
                  "Column of MOS with each stimulus' standard deviation of the opinion scores: "
                  "pairs labelled by Krasula's 95% z test (with --n-column, or n from "
                  "--ci-column) and his AUC analysis run");
  cmd->add_option("--n-column", o.n_column, "Column of MOS with each stimulus' observer count");
  cmd->add_option("--raw", o.raw,
                  "CSV of individual scores (stimulus, observer, score): pairs labelled as VMAF "
                  "does (|z| > 2, every ordered pair) for Krasula's analysis")
      ->type_name("FILE");
  cmd->add_option("--pairs", o.pairs,
                  "CSV of labelled pairs (first, second, label: 1 first better, -1 worse, 0 "
                  "similar) for Krasula's analysis")
      ->type_name("FILE");
}

// The mapping before P.1401's statistics, the grouping of pairs, the bootstrap.
void add_eval_statistics_options(CLI::App* cmd, EvalCommandOptions& o) {
  cmd->add_option("--mapping", o.mapping,
                  "Mapping of the scores to the MOS scale before P.1401's statistics (RMSE with "
                  "N - d degrees of freedom, RMSE*, outlier ratio, analytic intervals, tests "
                  "between metrics): logistic4 (VQEG, the default), logistic5, cubic "
                  "(monotonic), linear or none")
      ->check(CLI::IsMember({"logistic4", "logistic5", "cubic", "linear", "none"}));
  cmd->add_option("--group-column", o.group_column,
                  "Column of MOS (e.g. the source model): only pairs within a group are "
                  "labelled (the BASICS intra-source track)");
  cmd->add_option("--bootstrap", o.bootstrap,
                  "Bootstrap replicates for the 95% intervals (0 = none; at most " +
                      std::to_string(kMaxBootstrapReplicates) + ")")
      ->check(CLI::Range(std::size_t(0), kMaxBootstrapReplicates))
      ->capture_default_str();
  cmd->add_option("--seed", o.seed, "Seed of the bootstrap")->capture_default_str();
}

// What is written, and where.
void add_eval_output_options(CLI::App* cmd, EvalCommandOptions& o) {
  auto* json = cmd->add_flag("--json", o.json, "Write one JSON object");
  cmd->add_flag("--csv", o.csv, "Write CSV: statistic,value,ci95_low,ci95_high")->excludes(json);
  cmd->add_option("-o,--output", o.output, "Write to FILE instead of stdout")->type_name("FILE");
  cmd->add_option("--plot", o.plot,
                  "Also draw score vs MOS with the fitted mapping (and with Krasula's analysis "
                  "FILE-auc: the AUCs); .svg or .png")
      ->type_name("FILE.svg|png");
}

void add_eval_options(CLI::App* cmd, EvalCommandOptions& o) {
  add_eval_input_options(cmd, o);
  add_eval_orientation_options(cmd, o);
  add_krasula_label_options(cmd, o);
  add_eval_statistics_options(cmd, o);
  add_eval_output_options(cmd, o);
}

void add_train_options(CLI::App* cmd, TrainCommandOptions& o) {
  cmd->add_option("FEATURES", o.features, "CSV of pooled features f1..f8 (e.g. qm3d batch results)")
      ->required();
  cmd->add_option("MOS", o.mos, "CSV of subjective scores")->required();
  cmd->add_option("--group-by", o.group_by,
                  "Column(s) whose values are the cross-validation groups (source model, "
                  "distortion type; several columns pool their folds), in FEATURES or MOS")
      ->required()
      ->delimiter(',')
      ->allow_extra_args(false);
  cmd->add_option("--features", o.feature_columns,
                  "Feature column prefixes: columns PREFIX1..PREFIX8, averaged over several "
                  "prefixes; auto: f1..f8, else the batch columns of the directions every row has")
      ->capture_default_str();
  cmd->add_option("--features-key", o.features_key,
                  "Stimulus column of FEATURES (default: 'distorted' if present, else the first)");
  cmd->add_option("--mos-key", o.mos_key, "Stimulus column of MOS (default: the first)");
  cmd->add_option("--mos-column", o.mos_column, "MOS column (default: 'mos' in any case)");
  cmd->add_flag("--stem", o.stem, "Match keys by file stem");
  cmd->add_option("--metric", o.metric,
                  "Metric the model is for, cmdm or pcqm (default: FEATURES' metric column)");
  cmd->add_option("--subset", o.subsets,
                  "Only compare this subset (e.g. f2,f5,f6,f7); repeatable (default: all 255)")
      ->allow_extra_args(false);
  cmd->add_option("--criterion", o.criterion, "Subset ranking: mean held-out plcc, srocc or both")
      ->check(CLI::IsMember({"plcc", "srocc", "both"}))
      ->capture_default_str();
  cmd->add_option("--select", o.select,
                  "one-se: fewest features within one standard error of the best; best: the best")
      ->check(CLI::IsMember({"one-se", "best"}))
      ->capture_default_str();
  cmd->add_option("--final", o.final_weights,
                  "Final weights: mean-of-folds (the CMDM report) or refit on every stimulus")
      ->check(CLI::IsMember({"mean-of-folds", "refit"}))
      ->capture_default_str();
  cmd->add_flag("--json", o.json, "Write the whole result as one JSON object on stdout");
  cmd->add_option("-o,--output", o.output, "Write the model file (JSON) for --model")
      ->type_name("MODEL.json");
  cmd->add_option("--report", o.report, "Write every subset's cross-validation scores")
      ->type_name("FILE.csv|json");
}

}  // namespace

std::unique_ptr<EvalCommands> add_eval_commands(CLI::App& app,
                                                const std::function<void(CLI::App*)>& add_common) {
  auto c = std::make_unique<EvalCommands>();
  c->eval = app.add_subcommand(
      "eval",
      "Agreement of objective scores with subjective scores: PLCC, SROCC, KROCC, PLCC and "
      "RMSE after the VQEG logistic mapping, outlier ratio, with bootstrap 95% intervals");
  add_common(c->eval);
  add_eval_options(c->eval, c->eval_options);
  c->train = app.add_subcommand(
      "train",
      "Fit the weights of f1..f8 to subjective scores through a logistic link, choosing "
      "the feature subset by leave-one-group-out cross-validation; writes a model file");
  add_common(c->train);
  add_train_options(c->train, c->train_options);
  return c;
}

std::optional<int> run_eval_commands(const EvalCommands& commands, bool quiet) {
  if (commands.eval->parsed()) return run_eval(commands.eval_options, quiet);
  if (commands.train->parsed()) return run_train(commands.train_options, quiet);
  return std::nullopt;
}

}  // namespace qm3d::app
