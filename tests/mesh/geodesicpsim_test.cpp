// GeodesicPSIM against its reference's table (shared/data/reference/geodesicpsim): every case
// within 1e-9 relative; per-keypoint dumps explain a difference.
#include "qm3d/mesh/geodesicpsim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "geodesicpsim_cases.h"
#include "qm3d/common/error.h"

namespace qm3d::mesh {
namespace {

namespace fs = std::filesystem;
using test::CsvRow;

constexpr double kRelTolerance = 1e-9;  // the acceptance bound

double rel_diff(double a, double b) { return std::fabs(a - b) / std::max(std::fabs(b), 1e-300); }

// Every keypoint of the reference's per-keypoint dump against ours (flag, texel counts,
// smoothness, curvature, the eight per-patch similarities, patch size and shift); returns the
// number of keypoints that differ and describes the first few in `why`.
int keypoint_differences(const std::string& name, const GeodesicPsimResult& r, std::string& why) {
  const fs::path dump = test::geodesicpsim_dir() / "patches" / (name + ".patches.csv.gz");
  if (!fs::exists(dump)) return 0;
  std::istringstream in(test::gunzip_text(dump));
  std::ostringstream out;
  out.precision(17);
  int differ = 0;
  for (const CsvRow& row : test::parse_csv(in)) {
    const auto k = static_cast<std::size_t>(std::stoi(row.at("k")));
    if (k >= r.keypoints.size()) return ++differ;
    const auto& kp = r.keypoints[k];
    std::string what;
    if (std::stoi(row.at("flag")) != kp.flag) {
      what = "flag " + std::to_string(kp.flag) + " vs " + row.at("flag");
    } else if (!row.at("pcs_k").empty()) {
      const std::pair<const char*, double> cols[] = {{"ref_npix", kp.ref_texels},
                                                     {"dis_npix", kp.dis_texels},
                                                     {"ref_smooth_Y", kp.ref_smoothness[0]},
                                                     {"ref_smooth_U", kp.ref_smoothness[1]},
                                                     {"ref_smooth_V", kp.ref_smoothness[2]},
                                                     {"dis_smooth_Y", kp.dis_smoothness[0]},
                                                     {"dis_smooth_U", kp.dis_smoothness[1]},
                                                     {"dis_smooth_V", kp.dis_smoothness[2]},
                                                     {"ref_cur", kp.ref_curvature},
                                                     {"dis_cur", kp.dis_curvature},
                                                     {"pcs_k", kp.pcs},
                                                     {"dmc_k", kp.dmc},
                                                     {"lm_k", kp.lm},
                                                     {"var_k", kp.lvar},
                                                     {"c1m_k", kp.c1m},
                                                     {"c1var_k", kp.c1var},
                                                     {"c2m_k", kp.c2m},
                                                     {"c2var_k", kp.c2var},
                                                     {"ref_patch_size", kp.patch_size},
                                                     {"center_shift", kp.center_shift}};
      for (const auto& [col, ours] : cols) {
        const double theirs = std::stod(row.at(col));
        if (rel_diff(ours, theirs) > kRelTolerance && std::fabs(ours - theirs) > 1e-12) {
          std::ostringstream d;
          d.precision(17);
          d << col << " " << ours << " vs " << theirs;
          what = d.str();
          break;
        }
      }
    }
    if (what.empty()) continue;
    if (++differ <= 5) out << "k " << k << ": " << what << "\n";
  }
  why = out.str();
  return differ;
}

// The farthest-point keypoints against the reference's (17 digits: the same doubles).
int keypoint_position_differences(const std::string& name, const GeodesicPsimResult& r) {
  const fs::path dump = test::geodesicpsim_dir() / "patches" / (name + ".keypoints.csv.gz");
  if (!fs::exists(dump)) return 0;
  std::istringstream in(test::gunzip_text(dump));
  int differ = 0;
  for (const CsvRow& row : test::parse_csv(in)) {
    const auto k = static_cast<std::size_t>(std::stoi(row.at("k")));
    if (k >= r.keypoints.size()) break;
    const auto& p = r.keypoints[k].position;
    if (p[0] != std::stod(row.at("x")) || p[1] != std::stod(row.at("y")) ||
        p[2] != std::stod(row.at("z"))) {
      ++differ;
    }
  }
  return differ;
}

class GeodesicPsimReference : public ::testing::TestWithParam<CsvRow> {};

TEST_P(GeodesicPsimReference, MatchesTheReferenceTable) {
  const CsvRow& row = GetParam();
  const fs::path dir = test::geodesicpsim_inputs();
  GeodesicPsimOptions o;
  if (row.at("N_arg") != "default") o.keypoints = std::stoi(row.at("N_arg"));
  const GeodesicPsimResult r =
      compute_geodesicpsim(dir / row.at("ref_obj"), dir / row.at("dis_obj"), o);
  std::string why;
  EXPECT_EQ(keypoint_differences(row.at("case"), r, why), 0) << why;
  EXPECT_EQ(keypoint_position_differences(row.at("case"), r), 0);
  EXPECT_EQ(r.keypoints_used, std::stoi(row.at("N_used")));
  EXPECT_EQ(r.subdivided, row.at("subdivided"));
  EXPECT_EQ(r.flag1, std::stoi(row.at("flag1"))) << why;
  EXPECT_EQ(r.flag2, std::stoi(row.at("flag2"))) << why;
  EXPECT_EQ(r.flag3, std::stoi(row.at("flag3"))) << why;
  EXPECT_EQ(r.effective_patches, std::stoi(row.at("effective_patches")));
  const std::pair<const char*, double> values[] = {
      {"score", r.score}, {"pcs", r.pcs}, {"dmc", r.dmc}, {"pca", r.pca}, {"pcv", r.pcv}};
  for (const auto& [col, ours] : values) {
    EXPECT_LE(rel_diff(ours, std::stod(row.at(col))), kRelTolerance)
        << col << " " << ours << " vs " << row.at(col) << "\n"
        << why;
  }
}

std::string case_name(const ::testing::TestParamInfo<CsvRow>& info) {
  return info.param.at("case");
}

INSTANTIATE_TEST_SUITE_P(Table, GeodesicPsimReference,
                         ::testing::ValuesIn(test::geodesicpsim_reference_rows()), case_name);

TEST(GeodesicPsim, IdenticalMeshesScoreOne) {
  const fs::path dir = test::geodesicpsim_inputs();
  GeodesicPsimOptions o;
  o.keypoints = 200;
  const auto r = compute_geodesicpsim(dir / "tblob4_ref.obj", dir / "tblob4_ref.obj", o);
  EXPECT_EQ(r.score, 1.0);
  EXPECT_EQ(r.flag1, 200);
}

TEST(GeodesicPsim, OneAndTwoThreadsGiveTheSameBits) {
  const fs::path dir = test::geodesicpsim_inputs();
  GeodesicPsimOptions o;
  o.keypoints = 300;
  o.threads = 1;
  const auto a = compute_geodesicpsim(dir / "tblob4_ref.obj", dir / "tblob4_geonoise2.obj", o);
  o.threads = 2;
  const auto b = compute_geodesicpsim(dir / "tblob4_ref.obj", dir / "tblob4_geonoise2.obj", o);
  EXPECT_EQ(a.score, b.score);
  EXPECT_EQ(a.pcs, b.pcs);
  EXPECT_EQ(a.dmc, b.dmc);
  for (std::size_t k = 0; k < a.keypoints.size(); ++k) {
    EXPECT_EQ(std::isnan(a.keypoints[k].local_score()), std::isnan(b.keypoints[k].local_score()));
  }
}

// The reference computes its keypoints in 11 blocks of floor(N / 10): with N = 19 that is 11
// keypoints, the other 8 are never computed (skipped, flag 0).
TEST(GeodesicPsim, KeypointsPastTheReferencesBlocksAreSkipped) {
  const fs::path dir = test::geodesicpsim_inputs();
  GeodesicPsimOptions o;
  o.keypoints = 19;
  const auto r = compute_geodesicpsim(dir / "tblob4_ref.obj", dir / "tblob4_texjpeg10.obj", o);
  EXPECT_EQ(r.keypoints_used, 19);
  EXPECT_EQ(r.skipped, 8);
  EXPECT_EQ(r.flag1, 11);
  for (int k = 11; k < 19; ++k) EXPECT_EQ(r.keypoints[k].flag, 0);
}

// ---- Bad input: one line naming the file ---------------------------------------------------

fs::path scratch(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "qm3d_geodesicpsim_bad";
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

void expect_error_naming(const fs::path& bad, const fs::path& good, std::string named = "") {
  if (named.empty()) named = bad.filename().string();
  try {
    compute_geodesicpsim(good, bad);
    FAIL() << "no error for " << bad;
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(named), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(GeodesicPsim, UntexturedMissingTextureAndNoFacesNameTheFile) {
  const fs::path good = test::geodesicpsim_inputs() / "tblob4_ref.obj";
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
  expect_error_naming(scratch("untextured.obj", tri + "f 1 2 3\nf 1 3 4\n"), good);
  scratch("missing.mtl", "newmtl m\nmap_Kd nowhere.png\n");
  expect_error_naming(
      scratch("missing_tex.obj",
              "mtllib missing.mtl\n" + tri + "vt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n"),
      good, "nowhere.png");
  expect_error_naming(scratch("nofaces.obj", tri + "vt 0 0\n"), good);
}

}  // namespace
}  // namespace qm3d::mesh
