// qm3d: visual quality metrics for coloured meshes (CMDM) and point clouds (PCQM).
// Thin command-line front end: parse, call the libraries, write.
#include <CLI/CLI.hpp>
#include <omp.h>

#include <fstream>
#include <iostream>
#include <sstream>

#include "batch.h"
#include "commands.h"
#include "demo.h"
#include "eval_commands.h"
#include "merge_command.h"
#include "progress_display.h"
#include "qm3d/common/color.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/model_io.h"
#include "qm3d/common/version.h"
#include "report.h"
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
                    "(positions, float 'distortion', heat-map colour; faces kept for meshes)")
        ->type_name("FILE.ply");
  }
}

void add_cmdm_options(CLI::App* cmd, mesh::CmdmOptions& o, std::string& direction,
                      std::vector<double>& weights) {
  cmd->add_option("--direction", direction,
                  "symmetric: mean of both directions; dist-to-ref: distorted vertices matched on "
                  "the reference (MEPP2's test_cmdm); ref-to-dist: the reverse")
      ->check(CLI::IsMember({"symmetric", "dist-to-ref", "ref-to-dist"}))
      ->capture_default_str();
  cmd->add_option("--scales", o.scales, "Number of scales (curvature radius 0.001 + 0.0005 l of BB)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--weights", weights,
                  "Weights of f1..f8 (8 numbers); default 0,0.091,0,0,0.22,0.032,0.656,0")
      ->expected(8)
      ->delimiter(',');
}

void add_pcqm_options(CLI::App* cmd, pointcloud::PcqmOptions& o, std::string& bbox) {
  cmd->add_option("--radius", o.radius_rel, "Curvature radius as a fraction of the bounding box")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--knn", o.knn, "Neighbours of the quadric fit used for the correspondence")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  cmd->add_option("--rx", o.radius_factor, "Statistics radius = rx * curvature radius")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--bbox", bbox,
                  "reference: the reference tool's |min|+|max| box size (matches published PCQM "
                  "values; warns when it is >1% off the true size); extent: the true longest side")
      ->check(CLI::IsMember({"reference", "extent"}))
      ->capture_default_str();
  cmd->add_flag("--symmetric", o.symmetric,
                "Average both directions (default: reference -> distorted, as PCQM defines it)");
}

mesh::Direction parse_direction(const std::string& s) {
  if (s == "dist-to-ref") return mesh::Direction::kDistToRef;
  if (s == "ref-to-dist") return mesh::Direction::kRefToDist;
  return mesh::Direction::kSymmetric;
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

void print_warnings(const std::vector<MetricReport>& reports, bool quiet) {
  if (quiet) return;
  for (const auto& r : reports) {
    for (const auto& w : r.warnings) std::cerr << "qm3d: warning: " << w << "\n";
  }
}

std::string render(const std::vector<MetricReport>& reports, const OutputOptions& o,
                   bool as_compare) {
  std::ostringstream out;
  if (o.json) {
    if (!as_compare) {
      out << to_json(reports.front()).dump(2) << "\n";
    } else {
      nlohmann::json j = {{"metric", "compare"}, {"version", kVersion},
                          {"reference", reports.front().reference},
                          {"distorted", reports.front().distorted}};
      for (const auto& r : reports) j["metrics"][r.metric] = to_json(r);
      out << j.dump(2) << "\n";
    }
  } else if (o.csv) {
    out << csv_header() << "\n";
    for (const auto& r : reports) out << csv_row(r) << "\n";
  } else {
    for (const auto& r : reports) out << text_line(r) << "\n";
  }
  return out.str();
}

int run(int argc, char** argv) {
  CLI::App app{"qm3d " + std::string(kVersion) +
               " - visual quality metrics for coloured 3D content: CMDM for meshes with vertex "
               "colours, PCQM for coloured point clouds.\nScores are distortions: 0 means "
               "identical, larger is worse."};
  app.set_version_flag("--version", std::string("qm3d ") + kVersion);
  app.require_subcommand(1);
  GlobalOptions global;
  add_global_options(&app, global);
  bool progress = false;
  std::string ref, dist, direction = "symmetric", bbox = "reference";
  std::vector<double> weights;
  mesh::CmdmOptions cmdm;
  pointcloud::PcqmOptions pcqm;
  OutputOptions out;

  auto* cmdm_cmd = app.add_subcommand("cmdm", "CMDM between two coloured meshes (OBJ, OFF, PLY)");
  add_global_options(cmdm_cmd, global);
  add_progress_flag(cmdm_cmd, progress);
  cmdm_cmd->add_option("REF", ref, "Reference mesh")->required();
  cmdm_cmd->add_option("DIST", dist, "Distorted mesh")->required();
  add_cmdm_options(cmdm_cmd, cmdm, direction, weights);
  std::string model_file;
  cmdm_cmd->add_option("--model", model_file, kModelHelp)
      ->type_name("MODEL.json")
      ->excludes("--weights");
  add_output_options(cmdm_cmd, out, true);

  mesh::Msdm2Options msdm2;
  std::string msdm2_direction = "dist-to-ref";
  auto* msdm2_cmd = app.add_subcommand(
      "msdm2", "MSDM2 (geometry only; colours ignored) between two meshes (OBJ, OFF, PLY)");
  add_global_options(msdm2_cmd, global);
  add_progress_flag(msdm2_cmd, progress);
  msdm2_cmd->add_option("REF", ref, "Reference mesh")->required();
  msdm2_cmd->add_option("DIST", dist, "Distorted mesh")->required();
  msdm2_cmd->add_option("--direction", msdm2_direction,
                        "dist-to-ref (MEPP2's example_msdm2), ref-to-dist or symmetric")
      ->check(CLI::IsMember({"symmetric", "dist-to-ref", "ref-to-dist"}))
      ->capture_default_str();
  msdm2_cmd->add_option("--scales", msdm2.scales,
                        "Number of scales (curvature radius (0.002 + 0.001 l) of BB)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  add_output_options(msdm2_cmd, out, true);

  auto* pcqm_cmd = app.add_subcommand("pcqm", "PCQM between two coloured point clouds (PLY, PCD; "
                                              "OBJ/OFF/PLY meshes are read as their vertices)");
  add_global_options(pcqm_cmd, global);
  add_progress_flag(pcqm_cmd, progress);
  pcqm_cmd->add_option("REF", ref, "Reference cloud (PCQM's first argument)")->required();
  pcqm_cmd->add_option("DIST", dist, "Distorted cloud")->required();
  add_pcqm_options(pcqm_cmd, pcqm, bbox);
  pcqm_cmd->add_option("--model", model_file, kModelHelp)->type_name("MODEL.json");
  add_output_options(pcqm_cmd, out, true);

  auto* compare_cmd = app.add_subcommand(
      "compare", "Every metric that applies: CMDM, MSDM2, PCQM on the vertices and PCQM on "
                 "surface samples (pcqm_sampled; both meshes sampled alike) for two meshes, PCQM "
                 "for two clouds");
  add_global_options(compare_cmd, global);
  add_progress_flag(compare_cmd, progress);
  compare_cmd->add_option("REF", ref, "Reference")->required();
  compare_cmd->add_option("DIST", dist, "Distorted")->required();
  add_output_options(compare_cmd, out, false);
  SamplingCli sampling;
  const std::string sampling_note =
      " for pcqm_sampled (default " + std::to_string(kDefaultSampledPoints) + ")";
  add_sampling_options(compare_cmd, sampling, sampling_note);

  BatchOptions batch;
  std::string list, results;
  auto* batch_cmd = app.add_subcommand(
      "batch", "Score every pair of LIST.csv (columns reference,distorted[,metric]; metric = cmdm, "
               "msdm2, pcqm, pcqm_sampled, compare (one row per metric) or auto (CMDM for two meshes, PCQM otherwise); relative paths are relative to LIST's folder). Each row is appended "
               "to RESULTS as soon as it is done; a failing pair records its error in its row");
  add_global_options(batch_cmd, global);
  batch_cmd->add_option("LIST", list, "CSV list of pairs")->required()->check(CLI::ExistingFile);
  batch_cmd->add_option("-o,--output", results, "Results CSV")->required()->type_name("RESULTS.csv");
  batch_cmd->add_option("-j,--jobs", batch.jobs, "Pairs scored at the same time")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  batch_cmd->add_flag("--resume", batch.resume, "Skip the pairs already in RESULTS");
  batch_cmd->add_flag("--overwrite", batch.overwrite, "Replace an existing RESULTS");
  add_shard_option(batch_cmd, batch.shard);
  add_cmdm_options(batch_cmd, cmdm, direction, weights);
  add_pcqm_options(batch_cmd, pcqm, bbox);
  add_sampling_options(batch_cmd, sampling, sampling_note);

  auto* demo_cmd = app.add_subcommand("demo", "Score the small stimuli bundled with qm3d and print "
                                              "the table");
  add_global_options(demo_cmd, global);
  std::string demo_dir = default_demo_dir().string();
  demo_cmd->add_option("--dir", demo_dir, "Folder of the bundled stimuli")->capture_default_str();

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
  cmdm.direction = parse_direction(direction);
  if (!weights.empty()) std::copy(weights.begin(), weights.end(), cmdm.model.weights.begin());
  cmdm.model.provenance = weights.empty() ? cmdm.model.provenance : "--weights";
  if (!model_file.empty() && *cmdm_cmd) cmdm.model = read_model_for(model_file, "cmdm");
  if (!model_file.empty() && *pcqm_cmd) pcqm.model = read_model_for(model_file, "pcqm");
  pcqm.bbox = bbox == "extent" ? pointcloud::BboxMode::kExtent : pointcloud::BboxMode::kReference;
  cmdm.data_dir = pcqm.data_dir = global.data_dir;
  cmdm.threads = pcqm.threads = global.threads;
  msdm2.threads = global.threads;
  msdm2.direction = parse_direction(msdm2_direction);
  // One pair: its stages on stderr (batch shows pairs done instead).
  const bool single_pair = *cmdm_cmd || *msdm2_cmd || *pcqm_cmd || *compare_cmd;
  if (single_pair && !global.quiet && (progress || stderr_is_terminal())) {
    const bool in_place = stderr_is_terminal();
    cmdm.progress = stderr_progress("CMDM", in_place);
    msdm2.progress = stderr_progress("MSDM2", in_place);
    pcqm.progress = stderr_progress("PCQM", in_place);
  }
  const MetricOptions metrics{cmdm, msdm2, pcqm,
                              to_sampling_options(sampling, kDefaultSampledPoints)};

  std::vector<MetricReport> reports;
  if (*cmdm_cmd) reports.push_back(run_cmdm(ref, dist, cmdm, out.map));
  if (*msdm2_cmd) reports.push_back(run_msdm2(ref, dist, msdm2, out.map));
  if (*pcqm_cmd) reports.push_back(run_pcqm(ref, dist, pcqm, out.map));
  if (*compare_cmd) reports = run_compare(ref, dist, metrics);
  if (!reports.empty()) {
    print_warnings(reports, global.quiet);
    emit(render(reports, out, compare_cmd->parsed()), out.output);
    return kExitOk;
  }
  if (*batch_cmd) {
    batch.list = list;
    batch.output = results;
    batch.threads = global.threads;
    batch.quiet = global.quiet;
    batch.metrics = metrics;
    return run_batch(batch);
  }
  return run_demo(demo_dir, cmdm, pcqm, std::cout);
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
