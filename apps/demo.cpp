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

constexpr DemoPair kMeshPairs[] = {
    {"meshes/blob3_ref.off", "meshes/blob3_ref.off", "identical mesh"},
    {"meshes/blob3_ref.off", "meshes/blob3_geonoise.off", "geometric noise"},
    {"meshes/blob3_ref.off", "meshes/blob3_colnoise.off", "colour noise"},
    {"meshes/blob3_ref.off", "meshes/blob3_bothnoise.off", "geometric + colour noise"},
};
constexpr DemoPair kCloudPairs[] = {
    {"clouds/sphere_2k_ref.ply", "clouds/sphere_2k_cnoise10.ply", "colour noise"},
    {"clouds/sphere_2k_ref.ply", "clouds/sphere_2k_gnoise0.005.ply", "geometric noise"},
    {"clouds/sphere_2k_ref.ply", "clouds/sphere_2k_down0.5.ply", "50% downsampling"},
};

void row(std::ostream& out, const std::string& pair, const std::string& cmdm, const std::string& pcqm) {
  out << std::left << std::setw(52) << pair << std::right << std::setw(12) << cmdm << std::setw(12)
      << pcqm << "\n";
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

int run_demo(const std::filesystem::path& dir, const mesh::CmdmOptions& cmdm,
             const pointcloud::PcqmOptions& pcqm, std::ostream& out) {
  if (!std::filesystem::is_directory(dir / "meshes")) {
    throw InputError(dir.string() + ": bundled demo data not found (use --dir)");
  }
  out << "qm3d demo: bundled stimuli in " << dir.string() << "\n\n";
  row(out, "pair (reference vs distorted)", "CMDM", "PCQM");
  row(out, std::string(50, '-'), "----------", "----------");
  for (const auto& p : kMeshPairs) {
    const auto c = run_cmdm(dir / p.reference, dir / p.distorted, cmdm);
    const auto q = run_pcqm(dir / p.reference, dir / p.distorted, pcqm);
    row(out, std::string("blob3 mesh: ") + p.what, fixed(c.score), fixed(q.score));
  }
  for (const auto& p : kCloudPairs) {
    const auto q = run_pcqm(dir / p.reference, dir / p.distorted, pcqm);
    row(out, std::string("sphere 2k cloud: ") + p.what, "-", fixed(q.score));
  }
  out << "\nScores are distortions (0 = identical). PCQM on meshes uses their vertices.\n";
  return 0;
}

}  // namespace qm3d::app
