// psnr on two meshes (issue 28): both sampled on one grid as mmetric does, then compared with
// mmetric's compare --mode pcc conventions, through the registry as the tool runs it. Every value
// of every row of shared/data/reference/mpeg/mm_pcc_reference.csv within 1e-8 relative (the
// rules of mpeg_reference.h), except mm_pcc_monkey_g1024 (1.9M samples per mesh: a few seconds
// in Release, minutes under the sanitizers), which bench/run_benchmarks.sh psnr_mesh checks.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "mpeg_reference.h"
#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/result_io.h"
#include "qm3d/mesh/metrics.h"
#include "qm3d/pointcloud/metrics.h"
#include "test_paths.h"

namespace qm3d {
namespace {

const Registry& registry() {
  static const Registry r = [] {
    Registry out;
    mesh::register_metrics(out);
    pointcloud::register_metrics(out);
    return out;
  }();
  return r;
}

Input shared(const std::string& relative) {
  return registry().read(test::shared_data() / relative);
}

// The case's mmetric options as psnr option values.
OptionValues options_of(const test::PcErrorCase& c) {
  OptionValues o = OptionValues::object();
  o["grid_size"] = std::stoi(c.column.at("gridSize"));
  if (const auto r = test::pc_error_option(c, "--resolution"); r && *r != "0") {
    o["peak"] = std::stod(*r);
  }
  if (const auto n = test::pc_error_option(c, "--normalCalcModificationEnable"); n && *n == "false") {
    o["d2_normals"] = "transferred";
  }
  if (const auto d = test::pc_error_option(c, "--dropDuplicates")) o["drop_duplicates"] = std::stoi(*d);
  if (const auto p = test::pc_error_option(c, "--neighborsProc")) o["neighbours"] = std::stoi(*p);
  return o;
}

MetricResult mesh_psnr(const Input& a, const Input& b, const OptionValues& o, int threads = 0) {
  RunOptions run;
  run.threads = threads;
  return run_metric(registry().get("psnr"), a, b, run, o);
}

TEST(MeshPsnr, EveryMmetricReferenceCaseWithin1e8) {
  const auto cases = test::mmetric_mesh_cases();
  ASSERT_EQ(cases.size(), 16u);
  int checked = 0;
  for (const test::PcErrorCase& c : cases) {
    if (c.name == "mm_pcc_monkey_g1024") continue;  // the benchmark checks it (see above)
    SCOPED_TRACE(c.name);
    const MetricResult r =
        mesh_psnr(shared(c.column.at("mesh_a")), shared(c.column.at("mesh_b")), options_of(c));
    const nlohmann::json j = to_json(r);
    test::expect_pc_error_json(c, j);
    test::expect_mmetric_statistics(c, j["features"]);
    const double peak = std::stod(c.column.at("peak"));
    EXPECT_NEAR(j["peak"].get<double>(), peak, 1e-8 * peak);
    EXPECT_EQ(j["sampling"]["reference"]["samples"].get<std::size_t>(),
              std::stoul(c.column.at("nA_sampled")));
    EXPECT_EQ(j["sampling"]["distorted"]["samples"].get<std::size_t>(),
              std::stoul(c.column.at("nB_sampled")));
    EXPECT_EQ(j["points_reference"].get<std::size_t>(), std::stoul(c.column.at("nA")));
    EXPECT_EQ(j["points_distorted"].get<std::size_t>(), std::stoul(c.column.at("nB")));
    EXPECT_EQ(j["d2_normals"], c.column.at("d2_normals") == "cloudB"
                                   ? "distorted's own"
                                   : "transferred from the reference");
    ++checked;
  }
  EXPECT_EQ(checked, 15);
}

TEST(MeshPsnr, SameBitsOnAnyThreadCount) {
  const Input a = shared("reference/cmdm/blob4_ref.ply");
  const Input b = shared("reference/cmdm/blob4_bothnoise.ply");
  OptionValues o = OptionValues::object();
  o["grid_size"] = 128;
  const nlohmann::json one = to_json(mesh_psnr(a, b, o, 1))["features"];
  for (int threads : {2, 3}) EXPECT_EQ(to_json(mesh_psnr(a, b, o, threads))["features"], one);
}

TEST(MeshPsnr, AMeshAgainstACloudIsNotScored) {
  const Input mesh = shared("reference/cmdm/blob4_ref.ply");
  const Input cloud = shared("reference/mpeg/sampled/blob4_ref_g100.ply");
  const MetricSpec& psnr = registry().get("psnr");
  EXPECT_FALSE(psnr.applies(mesh, cloud));
  EXPECT_FALSE(psnr.applies(cloud, mesh));
  EXPECT_FALSE(psnr.applies(mesh, mesh));  // not run by compare (G 1024 is seconds); psnr takes it
  EXPECT_TRUE(psnr.applies(cloud, cloud));
  EXPECT_EQ(psnr.reads_for(mesh, mesh), Input::Kind::kMesh);
  // Run explicitly, a mesh with a cloud is refused (not scored as the mesh's vertices).
  EXPECT_THROW(mesh_psnr(mesh, cloud, OptionValues::object()), FormatError);
  EXPECT_THROW(mesh_psnr(cloud, mesh, OptionValues::object()), FormatError);
}

TEST(MeshPsnr, MeshOptionsAreCheckedWhereTheyDoNotApply) {
  const Input mesh = shared("reference/cmdm/blob4_ref.ply");
  const Input cloud = shared("reference/mpeg/sampled/blob4_ref_g100.ply");
  OptionValues own = OptionValues::object();
  own["d2_normals"] = "own";
  EXPECT_THROW(mesh_psnr(cloud, cloud, own), std::invalid_argument);
  OptionValues normals = OptionValues::object();
  normals["normals"] = "estimate";
  EXPECT_THROW(mesh_psnr(mesh, mesh, normals), std::invalid_argument);
  OptionValues coarse = OptionValues::object();
  coarse["grid_size"] = 1;
  EXPECT_THROW(mesh_psnr(mesh, mesh, coarse), std::invalid_argument);
}

}  // namespace
}  // namespace qm3d
