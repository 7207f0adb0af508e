#include "demo.h"

#include <stdlib.h>

#include <iomanip>
#include <iostream>
#include <optional>

#include "qm3d/scoring/score.h"
#include "qm3d/common/error.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/file_io.h"

#ifndef QM3D_DEMO_DIR
#define QM3D_DEMO_DIR "data"
#endif

namespace qm3d::app {
using namespace qm3d::scoring;  // NOLINT: the scoring this command drives
using namespace qm3d::report;  // NOLINT: the library this command drives
namespace {

struct DemoPair {
  const char* reference;
  const char* distorted;
  const char* what;
};

constexpr DemoPair kPairs[] = {
    {"meshes/blob3_ref.off", "meshes/blob3_ref.off", "blob3 mesh: identical mesh"},
    {"meshes/blob3_ref.off", "meshes/blob3_geonoise.off", "blob3 mesh: geometric noise"},
    {"meshes/blob3_ref.off", "meshes/blob3_colnoise.off", "blob3 mesh: colour noise"},
    {"meshes/blob3_ref.off", "meshes/blob3_bothnoise.off", "blob3 mesh: geometric + colour noise"},
    {"clouds/sphere_2k_ref.ply", "clouds/sphere_2k_cnoise10.ply", "sphere 2k cloud: colour noise"},
    {"clouds/sphere_2k_ref.ply", "clouds/sphere_2k_gnoise0.005.ply",
     "sphere 2k cloud: geometric noise"},
    {"clouds/sphere_2k_ref.ply", "clouds/sphere_2k_down0.5.ply",
     "sphere 2k cloud: 50% downsampling"},
};

// The pair whose report the demo writes (an index of kPairs): both kinds of noise, every mesh
// metric.
constexpr std::size_t kReportPair = 3;

constexpr int kPairWidth = 42;
constexpr int kScoreWidth = 14;

void row(std::ostream& out, const std::string& pair, const std::vector<std::string>& cells) {
  out << std::left << std::setw(kPairWidth) << pair << std::right;
  for (const auto& c : cells) out << std::setw(kScoreWidth) << c;
  out << "\n";
}

// The report's settings; unset (with a warning) when three.js is missing and no folder was asked
// for, so that the demo still shows its table.
std::optional<ReportSettings> demo_report_settings(const ReportCli& report, bool quiet) {
  try {
    return report_settings(report);
  } catch (const InputError& e) {
    if (!report.file.empty()) throw;
    if (!quiet) std::cerr << "qm3d: warning: no demo report: " << e.what() << "\n";
    return std::nullopt;
  }
}

// The given folder (created), or a new one in the temporary directory.
std::filesystem::path demo_report_dir(const std::string& given) {
  if (!given.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(given, ec);
    if (ec || !std::filesystem::is_directory(given)) {
      throw InputError(given + ": cannot create the report folder (--report-dir)");
    }
    return given;
  }
  std::string pattern = (std::filesystem::temp_directory_path() / "qm3d-demo-XXXXXX").string();
  if (!::mkdtemp(pattern.data())) {
    throw InputError(pattern + ": cannot create a temporary folder for the demo report");
  }
  return pattern;
}

}  // namespace

std::filesystem::path default_demo_dir() {
  // An installed tool has its stimuli in PREFIX/share/qm3d/data; a build tree uses the sources'.
  const std::filesystem::path share = installed_share_dir();
  if (!share.empty() && std::filesystem::is_directory(share / "data" / "meshes")) {
    return share / "data";
  }
  return QM3D_DEMO_DIR;
}

namespace {

using DemoInputs = std::vector<std::pair<Input, Input>>;

// One column per registered metric that applies to a bundled pair. Metrics asked for by name
// only (MetricSpec::in_compare false, e.g. ibsm's rendering) are left out, as in `compare`.
std::vector<const MetricSpec*> demo_columns(const DemoInputs& inputs) {
  std::vector<const MetricSpec*> columns;
  for (const auto& m : default_registry().metrics()) {
    if (!m.in_compare) continue;
    for (const auto& [ref, dist] : inputs) {
      if (m.applies(ref, dist)) {
        columns.push_back(&m);
        break;
      }
    }
  }
  return columns;
}

void print_table_head(std::ostream& out, const std::filesystem::path& dir,
                      const std::vector<const MetricSpec*>& columns) {
  out << "qm3d demo: bundled stimuli in " << dir.string() << "\n\n";
  std::vector<std::string> titles, rules;
  for (const MetricSpec* m : columns) {
    titles.push_back(m->title);
    rules.push_back(std::string(kScoreWidth - 2, '-'));
  }
  row(out, "pair (reference vs distorted)", titles);
  row(out, std::string(kPairWidth - 2, '-'), rules);
}

// The results of the pair the report shows, with their metrics.
struct ReportedResults {
  std::vector<MetricResult> results;
  std::vector<const MetricSpec*> specs;
};

// Scores every pair with every column's metric, a table row each; keeps the report pair's
// results (per-element values included) when a report is written.
ReportedResults score_table_rows(std::ostream& out, const DemoInputs& inputs,
                                 const std::vector<const MetricSpec*>& columns,
                                 const ScoreRequest& request, bool report) {
  ReportedResults reported;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const auto& [ref, dist] = inputs[i];
    ScoreRequest r = request;
    r.keep_per_element = report && i == kReportPair;
    std::vector<std::string> cells;
    for (const MetricSpec* m : columns) {
      if (!m->applies(ref, dist)) {
        cells.push_back("-");
        continue;
      }
      MetricResult result = score(*m, ref, dist, r);
      cells.push_back(short_number(result.score));
      if (r.keep_per_element) {
        reported.results.push_back(std::move(result));
        reported.specs.push_back(m);
      }
    }
    row(out, kPairs[i].what, cells);
  }
  return reported;
}

void print_table_notes(std::ostream& out, const std::vector<const MetricSpec*>& columns) {
  std::string qualities;
  for (const MetricSpec* m : columns) {
    if (m->higher_is_better) qualities += (qualities.empty() ? "" : ", ") + m->title;
  }
  out << "\nScores are distortions (0 = identical)";
  if (!qualities.empty()) out << ", except " << qualities << " (a quality in dB: higher is better, inf = identical)";
  out << ". PCQM on meshes uses their vertices; PCQM_SAMPLED samples both surfaces alike.\n";
}

void write_demo_report(std::ostream& out, const ReportedResults& reported,
                       const DemoInputs& inputs, const ReportCli& report,
                       const ReportSettings& settings) {
  std::vector<ReportEntry> entries;
  for (std::size_t i = 0; i < reported.results.size(); ++i) {
    entries.push_back({reported.specs[i], &reported.results[i]});
  }
  const std::filesystem::path file = demo_report_dir(report.file) / "blob3_bothnoise_report.html";
  write_html_report(file, entries, inputs[kReportPair].first, inputs[kReportPair].second,
                    settings);
  out << "\nReport of '" << kPairs[kReportPair].what << "' (open it in a browser): "
      << file.string() << "\n";
}

}  // namespace

int run_demo(const std::filesystem::path& dir, const ScoreRequest& request,
             const ReportCli& report, bool quiet, std::ostream& out) {
  if (!std::filesystem::is_directory(dir / "meshes")) {
    throw InputError(dir.string() + ": bundled demo data not found (use --dir)");
  }
  const std::optional<ReportSettings> settings = demo_report_settings(report, quiet);
  DemoInputs inputs;
  for (const auto& p : kPairs) {
    inputs.emplace_back(default_registry().read(dir / p.reference), default_registry().read(dir / p.distorted));
  }
  const std::vector<const MetricSpec*> columns = demo_columns(inputs);
  print_table_head(out, dir, columns);
  const ReportedResults reported =
      score_table_rows(out, inputs, columns, request, settings.has_value());
  print_table_notes(out, columns);
  if (settings) write_demo_report(out, reported, inputs, report, *settings);
  return 0;
}

}  // namespace qm3d::app
