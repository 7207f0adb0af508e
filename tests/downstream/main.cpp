// score_pair METRIC REF DIST: CMDM (meshes) or PCQM (clouds) of one pair with the default
// options and the package's tables, printed with 17 significant digits, through the installed
// qm3d libraries only. `score_pair spearman` checks the evaluation toolkit through its
// deprecated header path (qm3d/common/evaluation.h, kept one release) and the registry.
#include <cstdio>
#include <exception>
#include <string>
#include <type_traits>

#include "qm3d/common/evaluation.h"  // deprecated path: forwards to qm3d/evaluation/evaluation.h
#include "qm3d/evaluation/orientation.h"
#include "qm3d/mesh/cmdm.h"
#include "qm3d/mesh/mesh_io.h"
#include "qm3d/pointcloud/cloud_io.h"
#include "qm3d/pointcloud/pcqm.h"
#include "qm3d/scoring/registry.h"

// The old names still resolve, to the new ones.
static_assert(std::is_same_v<qm3d::EvaluationResult, qm3d::evaluation::EvaluationResult>);

// Spearman's rho of 1..4 against 4..1 (-1) through the old name, and PSNR's orientation through
// the one rule and the default registry (a quality: 1).
int check_evaluation() {
  const double rho = qm3d::spearman({1, 2, 3, 4}, {4, 3, 2, 1});
  const auto psnr = qm3d::evaluation::orient(qm3d::scoring::default_registry(), {},
                                             {"psnr", "", "psnr"},
                                             qm3d::evaluation::Fallback::column_name_then_quality);
  std::printf("%.17g %d\n", rho, psnr.higher_is_better.value_or(false) ? 1 : 0);
  return 0;
}

int main(int argc, char** argv) {
  if (argc == 2 && std::string(argv[1]) == "spearman") return check_evaluation();
  if (argc != 4) {
    std::fprintf(stderr, "usage: score_pair cmdm|pcqm REF DIST, or score_pair spearman\n");
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
