// qm3d: visual quality metrics for coloured meshes (CMDM) and point clouds (PCQM).
// Thin command-line front end: parse, call the libraries, write.
#include <CLI/CLI.hpp>
#include <omp.h>

#include <fstream>
#include <map>
#include <set>
#include <iostream>
#include <sstream>

#include "batch.h"
#include "commands.h"
#include "demo.h"
#include "eval_commands.h"
#include "html_report.h"
#include "merge_command.h"
#include "progress_display.h"
#include "qm3d/common/color.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/model_io.h"
#include "qm3d/common/version.h"
#include "qm3d/common/result_io.h"
#include "sample_commands.h"

namespace qm3d::app {
namespace {

// Exit codes (README "Exit codes").
constexpr int kExitOk = 0;
constexpr int kExitUsage = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInternal = 3;

constexpr const char* kModelHelp =
    "Model file (JSON: metric, features, weights; e.g. written by qm3d train) used instead of the "
    "built-in weights";

struct OutputOptions {
  bool json = false;
  bool csv = false;
  std::string output;  // empty = stdout
  std::string map;
};

struct GlobalOptions {
  int threads = 0;
  bool quiet = false;
  std::string data_dir;
};

// Accepted before the command and by every command (so each --help lists them).
void add_global_options(CLI::App* cmd, GlobalOptions& g) {
  cmd->add_option("--threads", g.threads, "Threads to use (0 = all cores)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", g.quiet, "No warnings or progress on stderr");
  cmd->add_option("--data-dir", g.data_dir,
                  "Directory of the LAB2000HL tables (default: $QM3D_DATA_DIR, else " +
                      resolve_data_dir("").string() + ")")
      ->type_name("DIR");
}

void add_progress_flag(CLI::App* cmd, bool& progress) {
  cmd->add_flag("--progress", progress,
                "Report each stage on stderr even when it is not a terminal (on a terminal the "
                "progress line is shown anyway, unless --quiet)");
}

void add_output_options(CLI::App* cmd, OutputOptions& o, bool with_map) {
  auto* json = cmd->add_flag("--json", o.json, "Write one JSON object instead of the human line");
  cmd->add_flag("--csv", o.csv, "Write a CSV header and one row instead of the human line")
      ->excludes(json);
  cmd->add_option("-o,--output", o.output, "Write the result to FILE instead of stdout")
      ->type_name("FILE");
  if (with_map) {
    cmd->add_option("--map", o.map,
                    "Also write the per-vertex / per-point distortion as a binary PLY "
                    "(positions, the value as float 'distortion', 'quality' (MeshLab) and "
                    "'scalar_distortion' (CloudCompare), heat-map colour; faces kept for meshes)")
        ->type_name("FILE.ply");
  }
}

// The values of the metrics' own options as given on the command line (before conversion).
struct MetricOptionsCli {
  std::map<std::string, std::string> text;  // name -> value as typed
  std::map<std::string, bool> flags;        // boolean options
  std::map<std::string, CLI::Option*> given;
};

// Adds --NAME for each option of `specs`, once per name (compare/batch take the options of every
// metric; a value given applies to each metric that has an option of that name).
// CLI11's check of a number option: its range, or its sign when the range is open-ended.
CLI::Validator range_check(const OptionSpec& o) {
  constexpr double kOpenEnded = 1e12;
  if (o.max >= kOpenEnded && o.min == 0) {
    return o.min_exclusive ? CLI::Validator(CLI::PositiveNumber)
                           : CLI::Validator(CLI::NonNegativeNumber);
  }
  if (o.max >= kOpenEnded && o.min == 1 && o.default_value.is_number_integer()) {
    return CLI::PositiveNumber;
  }
  if (o.default_value.is_number_integer()) {
    return CLI::Range(static_cast<long long>(o.min), static_cast<long long>(o.max));
  }
  return CLI::Range(o.min, o.max);
}

// The help of an option: its metric's, or each metric's when several have an option of that
// name with different help ("cmdm: ...; msdm2: ...").
std::string option_help(const std::vector<const MetricSpec*>& specs, const std::string& name) {
  std::vector<std::pair<std::string, std::string>> helps;
  for (const MetricSpec* spec : specs) {
    for (const OptionSpec& o : spec->options) {
      if (o.name != name) continue;
      const bool seen = std::any_of(helps.begin(), helps.end(),
                                    [&](const auto& h) { return h.second == o.help; });
      if (!seen) helps.emplace_back(spec->name, o.help);
    }
  }
  if (helps.size() == 1) return helps.front().second;
  std::string text;
  for (const auto& [metric, help] : helps) text += (text.empty() ? "" : "; ") + metric + ": " + help;
  return text;
}

void add_metric_options(CLI::App* cmd, const std::vector<const MetricSpec*>& specs,
                        MetricOptionsCli& cli) {
  std::set<std::string> added;
  for (const MetricSpec* spec : specs) {
    for (const OptionSpec& o : spec->options) {
      if (!added.insert(o.name).second) continue;
      const std::string flag = "--" + o.name;
      const std::string help = option_help(specs, o.name);
      const nlohmann::json& d = o.default_value;
      if (d.is_boolean()) {
        cli.given[o.name] = cmd->add_flag(flag, cli.flags[o.name], help);
        continue;
      }
      CLI::Option* opt = cmd->add_option(flag, cli.text[o.name], help);
      if (d.is_array()) {
        opt->type_name("LIST")->default_str(d.dump());
      } else {
        opt->default_str(d.is_string() ? d.get<std::string>() : d.dump());
      }
      if (!o.choices.empty()) opt->check(CLI::IsMember(o.choices));
      if (d.is_number()) {
        opt->type_name(d.is_number_integer() ? "INT" : "FLOAT");
        opt->check(range_check(o));
      }
      cli.given[o.name] = opt;
    }
  }
}

// The options given, converted to their types (checked later against each metric's spec).
OptionValues metric_option_values(const std::vector<const MetricSpec*>& specs,
                                  const MetricOptionsCli& cli) {
  OptionValues values = OptionValues::object();
  for (const MetricSpec* spec : specs) {
    for (const OptionSpec& o : spec->options) {
      const auto it = cli.given.find(o.name);
      if (it == cli.given.end() || it->second->count() == 0 || values.contains(o.name)) continue;
      const nlohmann::json& d = o.default_value;
      if (d.is_boolean()) {
        values[o.name] = cli.flags.at(o.name);
        continue;
      }
      const std::string& text = cli.text.at(o.name);
      const auto bad = [&] {
        return std::invalid_argument("--" + o.name + ": '" + text + "' is not " +
                                     (d.is_number_integer() ? "an integer"
                                      : d.is_number()       ? "a number"
                                                            : "a list of numbers"));
      };
      try {
        std::size_t used = 0;
        if (d.is_number_integer()) {
          const long long v = std::stoll(text, &used);
          if (used != text.size()) throw bad();
          values[o.name] = v;
        } else if (d.is_number()) {
          const double v = std::stod(text, &used);
          if (used != text.size()) throw bad();
          values[o.name] = v;
        } else if (d.is_array()) {
          nlohmann::json list = nlohmann::json::array();
          std::stringstream in(text);
          std::string item;
          while (std::getline(in, item, ',')) {
            list.push_back(std::stod(item, &used));
            if (used != item.size()) throw bad();
          }
          values[o.name] = list;
        } else {
          values[o.name] = text;
        }
      } catch (const std::logic_error&) {  // std::stod's invalid_argument / out_of_range
        throw bad();
      }
    }
  }
  return values;
}

// --direction / --symmetric, --weights / --model: the run options every metric command has.
struct RunCli {
  std::string direction;
  bool symmetric = false;
  std::vector<double> weights;
  std::string model_file;
};

void add_run_options(CLI::App* cmd, RunCli& r, const MetricSpec* spec) {
  const std::string help =
      spec ? spec->direction_help + " (default " + direction_name(spec->default_direction) + ")"
           : "symmetric, dist-to-ref or ref-to-dist, for every metric (default: each metric's "
             "own: CMDM symmetric, MSDM2 dist-to-ref, PCQM ref-to-dist)";
  auto* direction = cmd->add_option("--direction", r.direction, help)
                        ->check(CLI::IsMember({"symmetric", "dist-to-ref", "ref-to-dist"}));
  cmd->add_flag("--symmetric", r.symmetric, "Same as --direction symmetric")->excludes(direction);
  if (spec && !spec->takes_model) return;
  CLI::Option* weights = nullptr;
  if (spec) {
    weights = cmd->add_option("--weights", r.weights,
                                       "Weights of the 8 features replacing the published model")
                           ->expected(8)
                           ->delimiter(',');
  }
  auto* model = cmd->add_option("--model", r.model_file,
                                spec ? std::string(kModelHelp)
                                     : std::string(kModelHelp) +
                                           "; applies to the metric the file names")
                    ->type_name("MODEL.json");
  if (weights) model->excludes(weights);
}

// The request of a metric command (`spec` set) or of compare / batch.
ScoreRequest score_request(const GlobalOptions& g, const RunCli& r, const MetricSpec* spec) {
  ScoreRequest req;
  req.run.threads = g.threads;
  req.run.data_dir = g.data_dir;
  if (r.symmetric) req.run.direction = Direction::kSymmetric;
  if (!r.direction.empty()) req.run.direction = parse_direction(r.direction);
  if (!r.weights.empty()) {
    LinearModel m;
    m.metric = spec->model_name();
    std::copy(r.weights.begin(), r.weights.end(), m.weights.begin());
    m.provenance = "--weights";
    req.model = m;
    req.model_any_metric = true;
  } else if (!r.model_file.empty()) {
    const std::string metric = spec ? spec->model_name() : read_model(r.model_file).model.metric;
    req.model = read_model_for(r.model_file, metric);
    req.model_any_metric = spec != nullptr;
  }
  return req;
}

// Writes text to stdout or, atomically, to the requested file.
void emit(const std::string& text, const std::string& output) {
  if (output.empty()) {
    std::cout << text << std::flush;
    if (!std::cout) throw InputError("stdout: write failed");
    return;
  }
  write_file_atomically(output, [&](std::ostream& out) { out << text; });
}

void print_warnings(const std::vector<MetricResult>& results, bool quiet) {
  if (quiet) return;
  for (const auto& r : results) {
    for (const auto& w : r.warnings) std::cerr << "qm3d: warning: " << w << "\n";
  }
}

std::string render(const std::vector<MetricResult>& results, const OutputOptions& o,
                   bool as_compare) {
  std::ostringstream out;
  if (o.json) {
    out << (as_compare ? compare_json(results) : to_json(results.front())).dump(2) << "\n";
  } else if (o.csv) {
    out << csv_header() << "\n";
    for (const auto& r : results) out << csv_row(r) << "\n";
  } else {
    for (const auto& r : results) out << text_line(r) << "\n";
  }
  return out.str();
}

// One command per registered metric, plus compare: REF DIST, the metric's options, output.
struct ScoreCommand {
  const MetricSpec* spec = nullptr;  // nullptr: compare (or report)
  CLI::App* cmd = nullptr;
  bool report = false;  // `qm3d report`: compare's metrics, the output is the HTML report
};

struct ScoreCli {
  std::string ref, dist;
  bool progress = false;
  RunCli run;
  MetricOptionsCli options;
  OutputOptions out;
  ReportCli report;
};

std::vector<const MetricSpec*> all_metrics() {
  std::vector<const MetricSpec*> all;
  for (const auto& m : registry().metrics()) all.push_back(&m);
  return all;
}

int run_score_command(const ScoreCommand& c, ScoreCli& cli, const GlobalOptions& g) {
  const std::vector<const MetricSpec*> specs = c.spec ? std::vector<const MetricSpec*>{c.spec}
                                                      : all_metrics();
  ScoreRequest request = score_request(g, cli.run, c.spec);
  request.options = metric_option_values(specs, cli.options);
  std::optional<ReportSettings> report;  // resolved first: a missing three.js fails fast
  if (!cli.report.file.empty()) report = report_settings(cli.report);
  request.keep_per_element = report.has_value();
  const Input ref = registry().read(cli.ref), dist = registry().read(cli.dist);
  const auto chosen = metrics_for(c.spec ? c.spec->name : "compare", ref, dist);
  std::vector<MetricResult> results;
  const bool show = !g.quiet && (cli.progress || stderr_is_terminal());
  for (const MetricSpec* spec : chosen) {
    ScoreRequest r = request;
    if (show) r.run.progress = stderr_progress(spec->title, stderr_is_terminal());
    results.push_back(score(*spec, ref, dist, r, c.spec ? cli.out.map : std::string()));
  }
  print_warnings(results, g.quiet);
  if (report) {
    std::vector<ReportEntry> entries;
    for (std::size_t i = 0; i < results.size(); ++i) entries.push_back({chosen[i], &results[i]});
    write_html_report(cli.report.file, entries, ref, dist, *report);
  }
  emit(render(results, cli.out, c.spec == nullptr), c.report ? std::string() : cli.out.output);
  return kExitOk;
}

int run(int argc, char** argv) {
  CLI::App app{"qm3d " + std::string(kVersion) +
               " - visual quality metrics for coloured 3D content: CMDM for meshes with vertex "
               "colours, PCQM for coloured point clouds.\nScores are distortions: 0 means "
               "identical, larger is worse. Inputs are recognised by content (PLY, OBJ, OFF, "
               "PCD); a PLY with faces is a mesh."};
  app.set_version_flag("--version", std::string("qm3d ") + kVersion);
  app.require_subcommand(1);
  GlobalOptions global;
  add_global_options(&app, global);

  // cmdm, msdm2, pcqm, ... (one per registered metric) and compare.
  ScoreCli score_cli;
  std::vector<ScoreCommand> score_commands;
  for (const MetricSpec& spec : registry().metrics()) {
    score_commands.push_back({&spec, app.add_subcommand(spec.name, spec.summary)});
  }
  score_commands.push_back(
      {nullptr, app.add_subcommand("compare",
                                   "Every metric that applies: CMDM, MSDM2, PCQM on the vertices "
                                   "and PCQM on surface samples (pcqm_sampled; both meshes "
                                   "sampled alike) for two meshes, PCQM for two clouds")});
  score_commands.push_back(
      {nullptr,
       app.add_subcommand("report",
                          "Run every metric that applies (as compare) and write one "
                          "self-contained HTML report: scores, features, options, warnings, "
                          "linked 3-D views of both objects and the local-distortion heat map, "
                          "its histogram and hottest regions. Prints the scores as compare does"),
       true});
  for (const ScoreCommand& c : score_commands) {
    add_global_options(c.cmd, global);
    add_progress_flag(c.cmd, score_cli.progress);
    c.cmd->add_option("REF", score_cli.ref, "Reference")->required();
    c.cmd->add_option("DIST", score_cli.dist, "Distorted")->required();
    add_run_options(c.cmd, score_cli.run, c.spec);
    add_metric_options(c.cmd, c.spec ? std::vector<const MetricSpec*>{c.spec} : all_metrics(),
                       score_cli.options);
    if (!c.report) add_output_options(c.cmd, score_cli.out, c.spec && c.spec->per_element_on_input);
    add_report_options(c.cmd, score_cli.report, c.report);
  }

  BatchOptions batch;
  RunCli batch_run;
  MetricOptionsCli batch_options;
  std::string list, results;
  std::string metric_names;
  for (const auto& m : registry().metrics()) metric_names += m.name + ", ";
  auto* batch_cmd = app.add_subcommand(
      "batch", "Score every pair of LIST.csv (columns reference,distorted[,metric]; metric = " +
                   metric_names +
                   "compare (one row per metric that applies) or auto (the first that applies: "
                   "CMDM for two meshes, PCQM otherwise); relative paths are relative to LIST's "
                   "folder). Each row is appended to RESULTS as soon as it is done; a failing "
                   "pair records its error in its row");
  add_global_options(batch_cmd, global);
  batch_cmd->add_option("LIST", list, "CSV list of pairs")->required()->check(CLI::ExistingFile);
  batch_cmd->add_option("-o,--output", results, "Results CSV")->required()->type_name("RESULTS.csv");
  batch_cmd->add_option("-j,--jobs", batch.jobs, "Pairs scored at the same time")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  batch_cmd->add_flag("--resume", batch.resume, "Skip the pairs already in RESULTS");
  batch_cmd->add_flag("--overwrite", batch.overwrite, "Replace an existing RESULTS");
  add_run_options(batch_cmd, batch_run, nullptr);
  add_metric_options(batch_cmd, all_metrics(), batch_options);
  add_shard_option(batch_cmd, batch.shard);
  ReportCli batch_report;
  add_report_dir_options(batch_cmd, batch_report,
                         "Also write one HTML report per pair into DIR (created if needed) and "
                         "DIR/index.html listing every pair by score, linking to its report");

  auto* demo_cmd = app.add_subcommand("demo", "Score the small stimuli bundled with qm3d with "
                                              "every metric that applies and print the table");
  add_global_options(demo_cmd, global);
  std::string demo_dir = default_demo_dir().string();
  demo_cmd->add_option("--dir", demo_dir, "Folder of the bundled stimuli")->capture_default_str();
  ReportCli demo_report;
  add_report_dir_options(demo_cmd, demo_report,
                         "Folder for the HTML report of one bundled pair (default: a new folder "
                         "in the system's temporary directory)");

  const auto eval_commands =
      add_eval_commands(app, [&](CLI::App* cmd) { add_global_options(cmd, global); });
  const auto sample_commands =
      add_sample_commands(app, [&](CLI::App* cmd) { add_global_options(cmd, global); });
  const auto merge_command =
      add_merge_command(app, [&](CLI::App* cmd) { add_global_options(cmd, global); });

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }

  if (global.threads > 0) omp_set_num_threads(global.threads);
  if (const auto code = run_eval_commands(*eval_commands, global.quiet)) return *code;
  if (const auto code = run_sample_commands(*sample_commands)) return *code;
  if (const auto code = run_merge_command(*merge_command, global.quiet)) return *code;
  for (const ScoreCommand& c : score_commands) {
    if (*c.cmd) return run_score_command(c, score_cli, global);
  }
  if (*batch_cmd) {
    batch.list = list;
    batch.output = results;
    batch.threads = global.threads;
    batch.quiet = global.quiet;
    batch.request = score_request(global, batch_run, nullptr);
    batch.request.options = metric_option_values(all_metrics(), batch_options);
    if (!batch_report.file.empty()) {
      batch.report_dir = batch_report.file;
      batch.report = report_settings(batch_report);
    }
    return run_batch(batch);
  }
  ScoreRequest demo;
  demo.run.threads = global.threads;
  demo.run.data_dir = global.data_dir;
  return run_demo(demo_dir, demo, demo_report, global.quiet, std::cout);
}

}  // namespace
}  // namespace qm3d::app

int main(int argc, char** argv) {
  using namespace qm3d::app;
  // One line on stderr (after erasing a progress line on a terminal), then the exit code. No
  // std::string is built, so this also works when memory ran out.
  const auto fail = [](const char* kind, const char* what, int code) {
    clear_progress_line();
    std::cerr << "qm3d: " << kind << ": " << what << "\n";
    return code;
  };
  try {
    return run(argc, argv);
  } catch (const qm3d::Error& e) {
    return fail("error", e.what(), kExitBadInput);
  } catch (const std::invalid_argument& e) {
    return fail("error", e.what(), kExitUsage);
  } catch (const std::bad_alloc&) {
    return fail("error", "out of memory", kExitInternal);
  } catch (const std::exception& e) {
    return fail("internal error", e.what(), kExitInternal);
  }
}
