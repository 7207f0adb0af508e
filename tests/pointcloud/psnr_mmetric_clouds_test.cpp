// psnr on two clouds with mmetric's conventions (issue 39: --conventions mmetric, mm compare
// --mode pcc run directly on clouds): every value of every row of
// shared/data/reference/mpeg/clouds_pcc/mm_pcc_clouds_reference.csv within 1e-8 relative (the
// rules of mpeg_reference.h: inf for a zero MSE, a zero Hausdorff as 0 with an infinite PSNR),
// through the registry as the tool runs it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "mpeg_reference.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/result_io.h"
#include "qm3d/pointcloud/metrics.h"
#include "test_paths.h"

namespace qm3d {
namespace {

const Registry& registry() {
  static const Registry r = [] {
    Registry out;
    pointcloud::register_metrics(out);
    return out;
  }();
  return r;
}

bool has_flag(const test::PcErrorCase& c, const std::string& flag) {
  return std::find(c.args.begin(), c.args.end(), flag) != c.args.end();
}

// The case's mm compare options as psnr option values (--hausdorff only prints; bAverageNormals
// is not wired in mm).
OptionValues options_of(const test::PcErrorCase& c) {
  OptionValues o = OptionValues::object();
  o["conventions"] = "mmetric";
  if (const auto r = test::pc_error_option(c, "--resolution"); r && *r != "0") {
    o["peak"] = std::stod(*r);
  }
  if (has_flag(c, "--normalCalcModificationEnable=false")) o["d2_normals"] = "transferred";
  if (has_flag(c, "--color=false")) o["no_color"] = true;
  if (const auto d = test::pc_error_option(c, "--dropDuplicates"))
    o["drop_duplicates"] = std::stoi(*d);
  if (const auto p = test::pc_error_option(c, "--neighborsProc")) o["neighbours"] = std::stoi(*p);
  return o;
}

nlohmann::json run_case(const test::PcErrorCase& c, int threads) {
  RunOptions run;
  run.threads = threads;
  if (has_flag(c, "--singlePass")) run.direction = Direction::kRefToDist;
  const Input a = registry().read(test::shared_data() / c.column.at("a"));
  const Input b = registry().read(test::shared_data() / c.column.at("b"));
  return to_json(run_metric(registry().get("psnr"), a, b, run, options_of(c)));
}

TEST(PsnrMmetricClouds, EveryReferenceCaseWithin1e8) {
  const auto cases = test::mpeg_cases("clouds_pcc/mm_pcc_clouds_reference.csv");
  ASSERT_EQ(cases.size(), 30u);
  for (const test::PcErrorCase& c : cases) {
    SCOPED_TRACE(c.name);
    const nlohmann::json j = run_case(c, 2);
    const bool single = has_flag(c, "--singlePass");
    for (const auto& [column, name] : test::pc_error_value_columns()) {
      test::expect_pc_error_value(
          c, "AB_" + column, test::json_feature(j["directions"]["ref_to_dist"]["features"], name));
      if (single) continue;  // mm prints no B -> A and no final block
      test::expect_pc_error_value(
          c, "BA_" + column, test::json_feature(j["directions"]["dist_to_ref"]["features"], name));
      test::expect_pc_error_value(c, "sym_" + column, test::json_feature(j["features"], name));
    }
    const double peak = std::stod(c.column.at("peak"));
    EXPECT_NEAR(j["peak"].get<double>(), peak, 1e-8 * peak);
    EXPECT_EQ(j["points_reference"].get<std::size_t>(), std::stoul(c.column.at("nA")));
    EXPECT_EQ(j["points_distorted"].get<std::size_t>(), std::stoul(c.column.at("nB")));
    const std::string normals = c.column.at("d2_normals");
    if (normals == "none") {
      EXPECT_FALSE(j.contains("d2_normals"));
    } else {
      EXPECT_EQ(j["d2_normals"],
                normals == "cloudB" ? "distorted's own" : "transferred from the reference");
    }
  }
}

TEST(PsnrMmetricClouds, SameBitsOnOneAndTwoThreads) {
  const auto cases = test::mpeg_cases("clouds_pcc/mm_pcc_clouds_reference.csv");
  for (const test::PcErrorCase& c : cases) {
    if (c.name != "mm_cpcc_sph_dupnormals_res") continue;
    EXPECT_EQ(run_case(c, 1)["features"], run_case(c, 2)["features"]);
    return;
  }
  FAIL() << "case mm_cpcc_sph_dupnormals_res not found";
}

TEST(PsnrMmetricClouds, PcErrorStaysTheDefaultAndOwnNormalsNeedMmetric) {
  const Input a = registry().read(test::reference_dir() / "mpeg" / "sphere_50k_ref_n.ply");
  const Input b = registry().read(test::reference_dir() / "mpeg" / "clouds_pcc" / "inputs" /
                                  "sphere_50k_gnoise0.001_n.ply");
  RunOptions run;
  const nlohmann::json j = to_json(run_metric(registry().get("psnr"), a, b, run, {}));
  EXPECT_EQ(j["d2_normals"], "transferred from the reference");
  EXPECT_EQ(j["peak_source"], "largest nearest-neighbour distance in the reference");
  OptionValues own = {{"d2_normals", "own"}};
  EXPECT_THROW(run_metric(registry().get("psnr"), a, b, run, own), std::invalid_argument);
}

}  // namespace
}  // namespace qm3d
