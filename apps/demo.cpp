#include "demo.h"

#include <iomanip>

#include "commands.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"

#ifndef QM3D_DEMO_DIR
#define QM3D_DEMO_DIR "data"
#endif

namespace qm3d::app {
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

constexpr int kPairWidth = 42;
constexpr int kScoreWidth = 14;

void row(std::ostream& out, const std::string& pair, const std::vector<std::string>& cells) {
  out << std::left << std::setw(kPairWidth) << pair << std::right;
  for (const auto& c : cells) out << std::setw(kScoreWidth) << c;
  out << "\n";
}

std::string fixed(double v) {
  std::ostringstream o;
  o << std::setprecision(6) << v;
  return o.str();
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

int run_demo(const std::filesystem::path& dir, const ScoreRequest& request, std::ostream& out) {
  if (!std::filesystem::is_directory(dir / "meshes")) {
    throw InputError(dir.string() + ": bundled demo data not found (use --dir)");
  }
  // One column per registered metric that applies to a bundled pair.
  std::vector<std::pair<Input, Input>> inputs;
  std::vector<const MetricSpec*> columns;
  for (const auto& p : kPairs) {
    inputs.emplace_back(registry().read(dir / p.reference), registry().read(dir / p.distorted));
  }
  for (const auto& m : registry().metrics()) {
    for (const auto& [ref, dist] : inputs) {
      if (m.applies(ref, dist)) {
        columns.push_back(&m);
        break;
      }
    }
  }
  out << "qm3d demo: bundled stimuli in " << dir.string() << "\n\n";
  std::vector<std::string> titles, rules;
  for (const MetricSpec* m : columns) {
    titles.push_back(m->title);
    rules.push_back(std::string(kScoreWidth - 2, '-'));
  }
  row(out, "pair (reference vs distorted)", titles);
  row(out, std::string(kPairWidth - 2, '-'), rules);
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const auto& [ref, dist] = inputs[i];
    std::vector<std::string> cells;
    for (const MetricSpec* m : columns) {
      cells.push_back(m->applies(ref, dist) ? fixed(score(*m, ref, dist, request).score) : "-");
    }
    row(out, kPairs[i].what, cells);
  }
  out << "\nScores are distortions (0 = identical). PCQM on meshes uses their vertices; "
         "PCQM_SAMPLED samples both surfaces alike.\n";
  return 0;
}

}  // namespace qm3d::app
