// mmetric 1.1.7's IBSM cases (shared/data/reference/mpeg/mm_ibsm_reference.csv, README there:
// `mm compare --mode ibsm` with the software rasteriser): every printed value within 1e-6
// relative, PSNRs clipped at 99.99 as mmetric prints them, the bounding sphere too. SSIM is left
// out (--no-ssim): mmetric has none, and it is the slowest part.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "qm3d/common/metric.h"
#include "qm3d/mesh/metrics.h"
#include "qm3d/render/ibsm.h"
#include "mpeg_reference.h"
#include "test_paths.h"

namespace qm3d::render {
namespace {

/// mmetric's ibsm options as qm3d's.
OptionValues options_of(const std::string& args) {
  OptionValues o = {{"no_ssim", true}};
  std::stringstream s(args);
  std::string word;
  while (s >> word) {
    if (word == "--ibsmResolution") s >> word, o["resolution"] = std::stoi(word);
    if (word == "--ibsmCameraCount") s >> word, o["views"] = std::stoi(word);
    if (word == "--ibsmDisableCulling") o["no_culling"] = true;
    if (word == "--ibsmCameraRotation") {
      std::string a, b, c;
      s >> a >> b >> c;
      auto num = [](std::string t) {
        t.erase(std::remove(t.begin(), t.end(), '"'), t.end());
        return std::stod(t);
      };
      o["rotation"] = {num(a), num(b), num(c)};
    }
  }
  return o;
}

const Registry& registry() {
  static const Registry r = [] {
    Registry reg;
    mesh::register_metrics(reg);
    register_metrics(reg);
    return reg;
  }();
  return r;
}

/// Relative difference (absolute when the expected value is 0).
double deviation(double got, double want) {
  if (want == 0) return std::abs(got);
  return std::abs(got - want) / std::abs(want);
}

constexpr double kTolerance = 1e-6;

const std::map<std::string, std::string> kColumns = {
    {"UnmatchedPixelPercentage", "unmatched_pixel_percentage"},
    {"R_MSE", "r_mse"}, {"G_MSE", "g_mse"}, {"B_MSE", "b_mse"}, {"RGB_MSE", "rgb_mse"},
    {"Y_MSE", "y_mse"}, {"U_MSE", "u_mse"}, {"V_MSE", "v_mse"}, {"YUV_MSE", "yuv_mse"},
    {"GEO_MSE", "geo_mse"}, {"R_PSNR", "r_psnr"}, {"G_PSNR", "g_psnr"}, {"B_PSNR", "b_psnr"},
    {"RGB_PSNR", "rgb_psnr"}, {"Y_PSNR", "y_psnr"}, {"U_PSNR", "u_psnr"}, {"V_PSNR", "v_psnr"},
    {"YUV_PSNR", "yuv_psnr"}, {"GEO_PSNR", "geo_psnr"}};

/// The maps of mmetric's --inputMapA / --inputMapB in `args` ("" when absent).
std::pair<std::string, std::string> maps_of(const std::string& args) {
  std::pair<std::string, std::string> maps;
  std::stringstream s(args);
  for (std::string word; s >> word;) {
    if (word == "--inputMapA") s >> maps.first;
    if (word == "--inputMapB") s >> maps.second;
  }
  return maps;
}

// mmetric on a real textured frame (shared/data/reference/mpeg/textured/, README there), its maps
// given as --ref-texture / --dist-texture: every printed value within 1e-8 relative (mm prints
// 9 digits). The texel lookups follow mmetric's bilinear rule to the float operation
// (mesh_metric/src/mm_texture.cpp).
TEST(IbsmReference, TexturedFrameWithMapsGivenOnTheCommandLine) {
  constexpr double kTexturedTolerance = 1e-8;
  const std::vector<test::PcErrorCase> rows =
      test::mpeg_cases("textured/mm_ibsm_textured_reference.csv");
  ASSERT_EQ(rows.size(), 3u);
  const std::filesystem::path dir = test::reference_dir() / "mpeg" / "textured";
  double worst = 0;
  RunOptions run;
  run.threads = 2;
  for (const test::PcErrorCase& c : rows) {
    const std::map<std::string, std::string>& row = c.column;
    SCOPED_TRACE(row.at("case"));
    const auto [map_a, map_b] = maps_of(row.at("args"));
    ReadOptions ra, rb;
    ra.texture = dir / map_a;
    rb.texture = dir / map_b;
    const Input a = registry().read(dir / row.at("mesh_a"), ra);
    const Input b = registry().read(dir / row.at("mesh_b"), rb);
    const MetricResult r =
        run_metric(registry().get("ibsm"), a, b, run, options_of(row.at("args")));
    for (const auto& [column, name] : kColumns) {
      const auto got = find_value(r.values, name);
      ASSERT_TRUE(got) << name;
      const double d = deviation(*got, std::stod(row.at(column)));
      EXPECT_LE(d, kTexturedTolerance)
          << column << ": got " << *got << ", mmetric " << row.at(column);
      worst = std::max(worst, d);
    }
    const double box =
        deviation(r.details.at("box_ratio").get<double>(), std::stod(row.at("BoxRatio")));
    EXPECT_LE(box, kTexturedTolerance);
  }
  std::cout << "[ibsm textured reference] worst relative deviation " << worst << "\n";
}

TEST(IbsmReference, EveryValueOfEveryCase) {
  const std::vector<test::PcErrorCase> rows = test::mpeg_cases("mm_ibsm_reference.csv");
  ASSERT_EQ(rows.size(), 10u);
  double worst = 0;
  std::string worst_where;
  RunOptions run;
  run.threads = 2;
  for (const test::PcErrorCase& c : rows) {
    const std::map<std::string, std::string>& row = c.column;
    SCOPED_TRACE(row.at("case"));
    const Input a = registry().read(test::shared_data() / row.at("mesh_a"));
    const Input b = registry().read(test::shared_data() / row.at("mesh_b"));
    const MetricResult r = run_metric(registry().get("ibsm"), a, b, run, options_of(row.at("args")));
    auto check = [&](const std::string& what, double got, double want) {
      const double d = deviation(got, want);
      EXPECT_LE(d, kTolerance) << what << ": got " << got << ", mmetric " << want;
      if (d > worst) worst = d, worst_where = row.at("case") + " " + what;
    };
    for (const auto& [column, name] : kColumns) {
      const auto got = find_value(r.values, name);
      ASSERT_TRUE(got) << name;
      check(column, *got, std::stod(row.at(column)));
    }
    check("BoxRatio", r.details.at("box_ratio").get<double>(), std::stod(row.at("BoxRatio")));
    check("BSphereRad", r.details.at("bsphere_radius").get<double>(), std::stod(row.at("BSphereRad")));
    std::stringstream ctr(row.at("BSphereCtr"));
    for (int k = 0; k < 3; ++k) {
      double want;
      ctr >> want;
      check("BSphereCtr", r.details.at("bsphere_center").at(k).get<double>(), want);
    }
    EXPECT_DOUBLE_EQ(r.score, *find_value(r.values, "yuv_psnr"));
  }
  std::cout << "[ibsm reference] worst relative deviation " << worst << " (" << worst_where << ")\n";
}

}  // namespace
}  // namespace qm3d::render
