// qm3d: visual quality metrics for coloured meshes (CMDM) and point clouds (PCQM).
// Thin command-line front end: parse, call the libraries, write.
#include <omp.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <memory>
#include <sstream>

#include "qm3d/study/batch.h"
#include "qm3d/study/batch_row.h"
#include "qm3d/scoring/score.h"
#include "demo.h"
#include "emit_text.h"
#include "eval_commands.h"
#include "help_format.h"
#include "qm3d/report/html_report.h"
#include "image_command.h"
#include "batch_options.h"
#include "merge_command.h"
#include "metric_cli.h"
#include "progress_display.h"
#include "qm3d/common/color.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/version.h"
#include "sample_commands.h"

namespace qm3d::app {
using namespace qm3d::scoring;  // NOLINT: the scoring this command drives
using namespace qm3d::study;  // NOLINT: the study batch runs
using namespace qm3d::report;  // NOLINT: the library this command drives
namespace {

// Exit codes (README "Exit codes").
constexpr int kExitOk = 0;
constexpr int kExitUsage = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInternal = 3;


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
  // Found once: every command's --help names it, and finding it stats the installation.
  static const std::string default_data_dir = resolve_data_dir("").string();
  cmd->add_option("--threads", g.threads, "Threads to use (0 = all cores)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", g.quiet, "No warnings or progress on stderr");
  cmd->add_option("--data-dir", g.data_dir,
                  "Directory of the LAB2000HL tables (default: $QM3D_DATA_DIR, else " +
                      default_data_dir + ")")
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
    std::vector<const MetricSpec*> specs;
    for (const auto& r : results) {
      if (const MetricSpec* s = default_registry().find(r.metric)) specs.push_back(s);
    }
    const std::vector<std::string> values = csv_value_names(specs);
    out << csv_header(values) << "\n";
    for (const auto& r : results) out << csv_row(r, {}, values) << "\n";
  } else {
    for (const auto& r : results) out << text_line(r) << "\n";
  }
  return out.str();
}

// What one scoring command parses into (each command has its own: CLI11 options are bound to
// their variables, and a value given to one command must not be read through another's option).
struct ScoreCli {
  std::string ref, dist;
  std::string colour_scale = "auto";
  std::string ref_texture, dist_texture;
  bool progress = false;
  RunCli run;
  MetricOptionsCli options;
  OutputOptions out;
  ReportCli report;
};

// One command per registered metric, plus compare and report: REF DIST, the metric's options,
// output.
struct ScoreCommand {
  const MetricSpec* spec = nullptr;  // nullptr: compare (or report)
  CLI::App* cmd = nullptr;
  bool report = false;  // `qm3d report`: compare's metrics, the output is the HTML report
  std::unique_ptr<ScoreCli> cli = std::make_unique<ScoreCli>();
};

// Before anything is scored: no output may replace an input or another output, and each must be
// writable (scoring may take minutes).
void check_score_outputs(const ScoreCli& cli, bool report_command) {
  const std::vector<NamedPath> inputs = {{"REF", cli.ref},
                                         {"DIST", cli.dist},
                                         {"--ref-texture", cli.ref_texture},
                                         {"--dist-texture", cli.dist_texture},
                                         {"--model", cli.run.model_file},
                                         {"--three-js", cli.report.three_js}};
  if (report_command) {
    check_outputs(inputs, {{"-o", cli.report.file}});
  } else {
    check_outputs(inputs,
                  {{"-o", cli.out.output}, {"--map", cli.out.map}, {"--report", cli.report.file}});
  }
}

int run_score_command(const ScoreCommand& c, const GlobalOptions& g) {
  const ScoreCli& cli = *c.cli;
  const std::vector<const MetricSpec*> specs =
      c.spec ? std::vector<const MetricSpec*>{c.spec} : compare_metrics();
  ScoreRequest request = score_request(cli.run, c.spec, g.threads, g.data_dir);
  request.options = metric_option_values(specs, cli.options);
  std::optional<ReportSettings> report;  // resolved first: a missing three.js fails fast
  if (!cli.report.file.empty()) report = report_settings(cli.report);
  check_score_outputs(cli, c.report);
  request.keep_per_element = report.has_value();
  const Input ref =
      default_registry().read(cli.ref, read_options(cli.colour_scale, cli.ref_texture, "--ref-texture"));
  const Input dist =
      default_registry().read(cli.dist, read_options(cli.colour_scale, cli.dist_texture, "--dist-texture"));
  const auto chosen = metrics_for(c.spec ? c.spec->name : "compare", ref, dist);
  std::vector<MetricResult> results;
  const bool show = !g.quiet && (cli.progress || stderr_is_terminal());
  for (const MetricSpec* spec : chosen) {
    ScoreRequest r = request;
    if (show) r.run.progress = stderr_progress(spec->title, stderr_is_terminal());
    r.release_inputs = !report && spec == chosen.back();  // a report reads both inputs
    results.push_back(score(*spec, ref, dist, r, c.spec ? cli.out.map : std::string()));
  }
  print_warnings(results, g.quiet);
  if (report) {
    std::vector<ReportEntry> entries;
    for (std::size_t i = 0; i < results.size(); ++i) entries.push_back({chosen[i], &results[i]});
    write_html_report(cli.report.file, entries, ref, dist, *report);
  }
  emit_text(render(results, cli.out, c.spec == nullptr), c.report ? std::string() : cli.out.output);
  return kExitOk;
}

// "qm3d 0.1.0 (commit ...)" and the reference tool each metric reproduces.
std::string version_text() {
  std::string text = std::string("qm3d ") + kVersion + " (commit " + git_commit() + ")";
  for (const MetricSpec& spec : default_registry().metrics()) {
    text += "\n  " + spec.name + ": " +
            (spec.reproduces.empty() ? "qm3d's own definition (no reference implementation)"
                                     : "reproduces " + spec.reproduces);
  }
  return text;
}

// "Distortions (0 = identical, larger is worse): CMDM, ...; qualities (...): PSNR.", from the
// registry's orientation of each metric.
std::string orientation_line() {
  std::string distortions, qualities;
  for (const MetricSpec& spec : default_registry().metrics()) {
    std::string& list = spec.higher_is_better ? qualities : distortions;
    list += (list.empty() ? "" : ", ") + spec.title;
  }
  std::string line;
  if (!distortions.empty()) line += "Distortions (0 = identical, larger is worse): " + distortions;
  if (!qualities.empty()) {
    line += std::string(line.empty() ? "Q" : "; q") +
            "ualities (higher is better; in dB inf = identical, similarities 1 = identical): " +
            qualities;
  }
  return line + ".";
}

CLI::App* add_score_command(CLI::App& app, std::vector<ScoreCommand>& commands,
                            const MetricSpec* spec, const std::string& name,
                            const std::string& help, bool report = false) {
  commands.push_back({spec, app.add_subcommand(name, help), report});
  return commands.back().cmd;
}

// cmdm, msdm2, pcqm, ... (one per registered metric), compare and report.
std::vector<ScoreCommand> add_score_commands(CLI::App& app, GlobalOptions& global) {
  std::vector<ScoreCommand> commands;
  for (const MetricSpec& spec : default_registry().metrics()) {
    add_score_command(app, commands, &spec, spec.name, spec.summary);
  }
  add_score_command(app, commands, nullptr, "compare",
                    "Every metric that applies: CMDM, MSDM2, PCQM on the vertices "
                    "and PCQM on surface samples (pcqm_sampled; both meshes "
                    "sampled alike), D_LAB for two meshes, PCQM, PSNR and D_LAB for "
                    "two clouds (ibsm, seconds of rendering per pair, only by name)");
  add_score_command(app, commands, nullptr, "report",
                    "Run every metric that applies (as compare) and write one "
                    "self-contained HTML report: scores, features, options, warnings, "
                    "linked 3-D views of both objects and the local-distortion heat map, "
                    "its histogram and hottest regions. Prints the scores as compare does",
                    true);
  for (const ScoreCommand& c : commands) {
    ScoreCli& cli = *c.cli;
    add_global_options(c.cmd, global);
    add_progress_flag(c.cmd, cli.progress);
    c.cmd->add_option("REF", cli.ref, "Reference")->required();
    c.cmd->add_option("DIST", cli.dist, "Distorted")->required();
    add_run_options(c.cmd, cli.run, c.spec);
    add_read_options(c.cmd, cli.colour_scale);
    add_texture_options(c.cmd, cli.ref_texture, cli.dist_texture);
    add_metric_options(c.cmd, c.spec ? std::vector<const MetricSpec*>{c.spec} : compare_metrics(),
                       cli.options);
    if (!c.report) add_output_options(c.cmd, cli.out, c.spec && (c.spec->per_element_on_input ||
                                                                   c.spec->per_element_positions));
    add_report_options(c.cmd, cli.report, c.report);
  }
  return commands;
}

// `qm3d batch LIST -o RESULTS` and what it parses into.
struct BatchCommand {
  CLI::App* cmd = nullptr;
  BatchOptions batch;
  RunCli run;
  MetricOptionsCli options;
  std::string list, results;
  std::string colour_scale = "auto";
  ReportCli report;
};

void add_batch_options(CLI::App* cmd, BatchCommand& c) {
  cmd->add_option("LIST", c.list, "CSV list of pairs")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", c.results, "Results CSV")->required()->type_name("RESULTS.csv");
  cmd->add_option("-j,--jobs", c.batch.jobs, "Pairs scored at the same time")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  cmd->add_flag("--resume", c.batch.resume,
                "Skip the pairs already in RESULTS (scored with the same settings; error rows "
                "too, unless --retry-failed)");
  cmd->add_flag("--overwrite", c.batch.overwrite, "Replace an existing RESULTS");
  add_batch_safety_options(cmd, c.batch);
  add_read_options(cmd, c.colour_scale);
  add_run_options(cmd, c.run, nullptr);
  add_metric_options(cmd, all_metrics(), c.options);
  add_shard_option(cmd, c.batch.shard);
  add_report_dir_options(cmd, c.report,
                         "Also write one HTML report per pair into DIR (created if needed) and "
                         "DIR/index.html listing every pair by score, linking to its report");
}

std::unique_ptr<BatchCommand> add_batch_command(CLI::App& app, GlobalOptions& global) {
  auto c = std::make_unique<BatchCommand>();
  std::string metric_names;
  for (const auto& m : default_registry().metrics()) metric_names += m.name + ", ";
  c->cmd = app.add_subcommand(
      "batch", "Score every pair of LIST.csv (columns reference,distorted[,metric]; metric = " +
                   metric_names +
                   "compare (one row per metric that applies) or auto (the first that applies: "
                   "CMDM for two meshes, PCQM otherwise); relative paths are relative to LIST's "
                   "folder). Each row is appended to RESULTS as soon as it is done; a failing "
                   "pair records its error in its row, also one that crashes (pairs are scored "
                   "in worker processes). Exit code 2 while a row of RESULTS records an error");
  add_global_options(c->cmd, global);
  add_batch_options(c->cmd, *c);
  return c;
}

int run_batch_command(BatchCommand& c, const GlobalOptions& global, bool worker, int argc,
                      char** argv) {
  BatchOptions& batch = c.batch;
  batch.list = c.list;
  batch.output = c.results;
  batch.threads = global.threads;
  batch.quiet = global.quiet;
  batch.progress = stderr_batch_progress();
  batch.request = score_request(c.run, nullptr, global.threads, global.data_dir);
  batch.request.options = metric_option_values(all_metrics(), c.options);
  batch.request.read = read_options(c.colour_scale);
  if (!c.report.file.empty()) {
    batch.report_dir = c.report.file;
    batch.report = report_settings(c.report);
  }
  batch.program = argv[0];
  batch.command_line.assign(argv + 1, argv + argc);
  return worker ? run_batch_worker(batch) : run_batch(batch);
}

// `qm3d demo` and what it parses into.
struct DemoCommand {
  CLI::App* cmd = nullptr;
  std::string dir = default_demo_dir().string();
  ReportCli report;
};

std::unique_ptr<DemoCommand> add_demo_command(CLI::App& app, GlobalOptions& global) {
  auto c = std::make_unique<DemoCommand>();
  c->cmd = app.add_subcommand("demo", "Score the small stimuli bundled with qm3d with "
                                      "every metric that applies and print the table");
  add_global_options(c->cmd, global);
  c->cmd->add_option("--dir", c->dir, "Folder of the bundled stimuli")->capture_default_str();
  add_report_dir_options(c->cmd, c->report,
                         "Folder for the HTML report of one bundled pair (default: a new folder "
                         "in the system's temporary directory)");
  return c;
}

int run_demo_command(const DemoCommand& c, const GlobalOptions& global) {
  ScoreRequest demo;
  demo.run.threads = global.threads;
  demo.run.data_dir = global.data_dir;
  return run_demo(c.dir, demo, c.report, global.quiet, std::cout);
}

std::string app_description() {
  return "qm3d " + std::string(kVersion) +
         " - visual quality metrics for coloured 3D content: CMDM and MSDM2 for meshes, "
         "PCQM for coloured point clouds, MPEG pc_error's PSNR and mmetric's IBSM (image-based, on rendered views).\n" +
         orientation_line() +
         " Inputs are recognised by content (PLY, OBJ, OFF, PCD); a PLY with faces is a "
         "mesh.";
}

int run(int argc, char** argv) {
  CLI::App app{app_description()};
  app.formatter(wrapping_formatter(help_width()));  // before the commands, which inherit it
  app.set_version_flag("--version", version_text());
  app.require_subcommand(1);
  GlobalOptions global;
  add_global_options(&app, global);
  bool batch_worker = false;  // set only in a worker process of `qm3d batch` (batch.h)
  app.add_flag("--batch-worker", batch_worker)->group("");
  const auto add_common = [&](CLI::App* cmd) { add_global_options(cmd, global); };
  // The order of the commands is the order of --help.
  const std::vector<ScoreCommand> score_commands = add_score_commands(app, global);
  const auto batch_command = add_batch_command(app, global);
  const auto demo_command = add_demo_command(app, global);
  const auto eval_commands = add_eval_commands(app, add_common);
  const auto sample_commands = add_sample_commands(app, add_common);
  const auto merge_command = add_merge_command(app, add_common);
  const auto image_command = add_image_command(app, add_common);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }
  check_thread_count(global.threads);  // before libgomp is asked for that many
  if (global.threads > 0) omp_set_num_threads(global.threads);
  if (const auto code = run_eval_commands(*eval_commands, global.quiet)) return *code;
  if (const auto code = run_sample_commands(*sample_commands)) return *code;
  if (const auto code = run_merge_command(*merge_command, global.quiet)) return *code;
  if (const auto code = run_image_command(*image_command, global.threads, global.data_dir)) {
    return *code;
  }
  for (const ScoreCommand& c : score_commands) {
    if (*c.cmd) return run_score_command(c, global);
  }
  if (*batch_command->cmd) {
    return run_batch_command(*batch_command, global, batch_worker, argc, argv);
  }
  return run_demo_command(*demo_command, global);
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
  // A closed pipe on stdout or -o is a write error reported by the writer, not a silent death.
  std::signal(SIGPIPE, SIG_IGN);
  try {
    const int code = run(argc, argv);
    if (!(std::cout << std::flush)) return fail("error", "stdout: write failed", kExitBadInput);
    return code;
  } catch (const qm3d::Error& e) {
    return fail("error", e.what(), kExitBadInput);
  } catch (const std::invalid_argument& e) {
    return fail("error", e.what(), kExitUsage);
  } catch (const qm3d::MemoryLimitError& e) {
    return fail("error", (std::string("out of memory: ") + e.what()).c_str(), kExitInternal);
  } catch (const std::bad_alloc&) {
    return fail("error", "out of memory", kExitInternal);
  } catch (const std::exception& e) {
    return fail("internal error", e.what(), kExitInternal);
  }
}
