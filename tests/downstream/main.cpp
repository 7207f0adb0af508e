// score_pair METRIC REF DIST: CMDM (meshes) or PCQM (clouds) of one pair with the default
// options and the package's tables, printed with 17 significant digits, through the installed
// qm3d libraries only.
#include <cstdio>
#include <exception>
#include <string>

#include "qm3d/mesh/cmdm.h"
#include "qm3d/mesh/mesh_io.h"
#include "qm3d/pointcloud/cloud_io.h"
#include "qm3d/pointcloud/pcqm.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: score_pair cmdm|pcqm REF DIST\n");
    return 1;
  }
  const std::string metric = argv[1];
  try {
    double score = 0;
    if (metric == "cmdm") {
      const auto ref = qm3d::mesh::read_mesh(argv[2]).mesh;
      const auto dist = qm3d::mesh::read_mesh(argv[3]).mesh;
      qm3d::mesh::CmdmOptions options;
      options.data_dir = QM3D_TABLES;
      score = qm3d::mesh::compute_cmdm(ref, dist, options).score;
    } else if (metric == "pcqm") {
      const auto ref = qm3d::pointcloud::read_cloud(argv[2]);
      const auto dist = qm3d::pointcloud::read_cloud(argv[3]);
      qm3d::pointcloud::PcqmOptions options;
      options.data_dir = QM3D_TABLES;
      score = qm3d::pointcloud::compute_pcqm(ref, dist, options).score;
    } else {
      std::fprintf(stderr, "score_pair: unknown metric '%s'\n", metric.c_str());
      return 1;
    }
    std::printf("%.17g\n", score);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "score_pair: %s\n", e.what());
    return 2;
  }
  return 0;
}
