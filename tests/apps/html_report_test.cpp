// report/ html_report.{h,cpp}: the parts of the report (base64, histogram, hottest regions,
// decimation, option parsing, file names) and the data a written report holds. The page itself is
// checked in a browser by tests/report/test_report.sh.
#include "qm3d/report/html_report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "qm3d/common/error.h"

namespace qm3d::report {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(HtmlReport, Base64MatchesRfc4648) {
  const auto b = [](const std::string& s) { return base64(s.data(), s.size()); };
  EXPECT_EQ(b(""), "");
  EXPECT_EQ(b("f"), "Zg==");
  EXPECT_EQ(b("fo"), "Zm8=");
  EXPECT_EQ(b("foo"), "Zm9v");
  EXPECT_EQ(b("foob"), "Zm9vYg==");
  EXPECT_EQ(b("fooba"), "Zm9vYmE=");
  EXPECT_EQ(b("foobar"), "Zm9vYmFy");
  const unsigned char high[] = {0xff, 0xfe, 0x00};
  EXPECT_EQ(base64(high, 3), "//4A");
}

TEST(HtmlReport, HistogramCountsFiniteValuesFromMinToMax) {
  const Histogram h = histogram({0, 1, 2, 3, NAN, INFINITY}, 3);
  EXPECT_EQ(h.lo, 0);
  EXPECT_EQ(h.hi, 3);
  EXPECT_EQ(h.counts, (std::vector<std::size_t>{1, 1, 2}));  // the maximum is in the last bin
  const Histogram flat = histogram({2, 2, 2}, 8);
  EXPECT_EQ(flat.counts, (std::vector<std::size_t>{3}));
  EXPECT_TRUE(histogram({NAN}, 8).counts.empty());
}

TEST(HtmlReport, HottestRegionsAreApartAndSummarised) {
  // Five points on a line, 1 apart; radius 1.5: point 2 (hottest) covers 1..3.
  const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}};
  const std::vector<double> v = {0.5, 0.8, 1.0, 0.9, 0.1};
  const auto r = hottest_regions(p, v, 10, 1.5);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].element, 2u);  // 3 and 1 are within 1.5 of it, 0 and 4 are not
  EXPECT_EQ(r[0].value, 1.0);
  EXPECT_EQ(r[0].elements, 3u);
  EXPECT_DOUBLE_EQ(r[0].mean, (0.8 + 1.0 + 0.9) / 3);
  EXPECT_EQ(r[1].element, 0u);   // 0.5, 2 from point 2
  EXPECT_EQ(r[1].elements, 2u);  // 0 and 1
  EXPECT_DOUBLE_EQ(r[1].mean, (0.5 + 0.8) / 2);
  EXPECT_EQ(r[2].element, 4u);  // 0.1, 2 from point 2 and 4 from point 0
  EXPECT_EQ(hottest_regions(p, v, 1, 1.5).size(), 1u);
  EXPECT_EQ(hottest_regions(p, v, 10, 10.0).size(), 1u);  // one region covers everything
  EXPECT_THROW(hottest_regions(p, {1.0}, 1, 1.0), std::invalid_argument);
}

TEST(HtmlReport, DisplaySubsetKeepsEveryKthAboveTheBudget) {
  EXPECT_EQ(display_subset(3, 5), (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(display_subset(5, 2), (std::vector<std::uint32_t>{0, 3}));  // k = ceil(5 / 2) = 3
  EXPECT_EQ(display_subset(6, 3), (std::vector<std::uint32_t>{0, 2, 4}));
  EXPECT_LE(display_subset(4'000'001, 2'000'000).size(), 2'000'000u);
}

TEST(HtmlReport, RangeIsTwoOrderedNumbers) {
  EXPECT_EQ(parse_range("0,0.5"), (std::array<double, 2>{0, 0.5}));
  EXPECT_EQ(parse_range("-1e-3,2"), (std::array<double, 2>{-1e-3, 2}));
  for (const char* bad : {"", "1", "1,", ",1", "a,b", "1,2x", "2,1", "1,1", "nan,1"}) {
    EXPECT_THROW(parse_range(bad), std::invalid_argument) << bad;
  }
}

TEST(HtmlReport, MissingThreeJsIsAnErrorNamingTheFile) {
  try {
    resolve_three_js("/nonexistent/three.min.js");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/three.min.js: three.js not found"),
              std::string::npos);
  }
}

TEST(HtmlReport, FileNamesAreStableSafeAndDistinct) {
  const std::string a = report_file_name("refs/a b.ply", "dist/x<y>.ply");
  EXPECT_EQ(a, report_file_name("refs/a b.ply", "dist/x<y>.ply"));
  EXPECT_EQ(a.rfind("x_y__vs_a_b-", 0), 0u) << a;
  EXPECT_EQ(a.substr(a.size() - 5), ".html");
  EXPECT_NE(a, report_file_name("other/a b.ply", "dist/x<y>.ply"));
}

// A report of a 5-point cloud pair, written with a stand-in for three.js.
class WrittenReport : public ::testing::Test {
 protected:
  void SetUp() override {
    // One directory per test and process: ctest runs this fixture's tests concurrently.
    dir_ = fs::temp_directory_path() /
           ("qm3d_html_report_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / "three.js") << "var THREE = {};";
    spec_.name = "pcqm";
    spec_.title = "PCQM";
    spec_.reads = Input::Kind::kCloud;
    spec_.default_direction = Direction::kRefToDist;
    result_.metric = "pcqm";
    result_.score = 0.25;
    result_.feature_names = feature_names("F");
    result_.warnings = {"a warning </script> in a name"};
    DirectionResult d;
    d.score = 0.25;
    d.per_element = {0.1, 0.2, 0.3, 0.4, 0.5};
    result_.ref_to_dist = d;
    for (int i = 0; i < 5; ++i) {
      cloud_.positions.push_back({double(i), 0, 0});
      cloud_.colors.push_back({0.2 * i, 0.5, 1.0});
    }
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes the report and returns its data (the JSON of the page) and its text.
  nlohmann::json write(std::size_t budget, std::string& text) {
    ReportSettings s;
    s.three_js = dir_ / "three.js";
    s.display_budget = budget;
    s.fixed_range = std::array<double, 2>{0, 1};
    const Input ref = Input::from_cloud(cloud_, "ref.ply"),
                dist = Input::from_cloud(cloud_, "dist.ply");
    write_html_report(dir_ / "r.html", {{&spec_, &result_}}, ref, dist, s);
    text = slurp(dir_ / "r.html");
    const std::string open = "<script type=\"application/json\" id=\"qm3d-data\">";
    const std::size_t from = text.find(open) + open.size();
    return nlohmann::json::parse(text.substr(from, text.find("</script>", from) - from));
  }

  fs::path dir_;
  MetricSpec spec_;
  MetricResult result_;
  ColoredCloud cloud_;
};

TEST_F(WrittenReport, HoldsScoresLayersAndGeometry) {
  std::string text;
  const nlohmann::json d = write(kDisplayBudget, text);
  for (const char* marker : {"@@TITLE@@", "@@THREE_JS@@", "@@DATA@@", "@@BLOBS@@"}) {
    EXPECT_EQ(text.find(marker), std::string::npos) << marker;  // every marker filled
  }
  EXPECT_NE(text.find("var THREE = {};"), std::string::npos);
  EXPECT_EQ(text.find("</script> in a name"), std::string::npos);  // escaped inside the JSON
  EXPECT_EQ(d["metrics"][0]["score"], 0.25);
  EXPECT_EQ(d["metrics"][0]["warnings"][0], "a warning </script> in a name");
  EXPECT_EQ(d["range"], nlohmann::json::array({0.0, 1.0}));
  ASSERT_EQ(d["layers"].size(), 1u);
  const auto& layer = d["layers"][0];
  EXPECT_EQ(layer["direction"], "ref-to-dist");
  EXPECT_EQ(layer["on"], "reference");
  EXPECT_EQ(layer["geometry"], 0);
  EXPECT_EQ(layer["max"], 0.5);
  EXPECT_EQ(layer["regions"][0]["x"], 4.0);  // the hottest point
  EXPECT_EQ(d["geometries"][0]["shown"], 5);
  EXPECT_EQ(d["geometries"][0]["draw"], "points");
  EXPECT_TRUE(d["notes"].empty());
  // 5 points: positions 60 bytes = 80 base64 characters.
  const std::string blob =
      "id=\"qm3d-blob-" + std::to_string(d["geometries"][0]["positions"].get<int>()) + "\">";
  const std::size_t at = text.find(blob) + blob.size();
  EXPECT_EQ(text.find("</script>", at) - at, 80u);
}

TEST_F(WrittenReport, DecimatesAboveTheBudgetAndSaysSo) {
  std::string text;
  const nlohmann::json d = write(2, text);
  EXPECT_EQ(d["geometries"][0]["shown"], 2);  // every 3rd of 5
  EXPECT_EQ(d["geometries"][0]["elements"], 5);
  ASSERT_FALSE(d["notes"].empty());
  EXPECT_NE(d["notes"][0].get<std::string>().find("display budget of 2"), std::string::npos);
  EXPECT_EQ(d["layers"][0]["max"], 0.5);  // statistics on every element
}

// An identical pair's per-element values are rounding noise (+-1e-17): a flat map of zeros, said
// so, not a blue-to-red map of noise.
TEST_F(WrittenReport, IdenticalPairIsAFlatMapOfZeros) {
  result_.ref_to_dist->per_element = {1e-17, -2e-17, 0, 3e-18, -1e-17};
  std::string text;
  const nlohmann::json d = write(kDisplayBudget, text);
  const auto& layer = d["layers"][0];
  EXPECT_EQ(layer["min"], 0.0);
  EXPECT_EQ(layer["max"], 0.0);
  EXPECT_EQ(layer["flat"], true);
  EXPECT_NE(text.find("no distortion"), std::string::npos);
  // Real values far below 1 stay: a 1e-9 distortion is not noise.
  result_.ref_to_dist->per_element = {0, 1e-9, 2e-9, 0, 0};
  const nlohmann::json small = write(kDisplayBudget, text);
  EXPECT_EQ(small["layers"][0]["flat"], false);
  EXPECT_EQ(small["layers"][0]["max"], 2e-9);
}

// A long tail: the default colour range ends at the 99th percentile (shown and switchable in
// the page), not at the one huge value.
TEST_F(WrittenReport, ColourScaleClippedAtThe99thPercentileByDefault) {
  std::vector<double> v(200);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = 0.001 * static_cast<double>(i % 10);
  v[7] = 1000;
  v[8] = 900;
  result_.ref_to_dist->per_element = v;
  cloud_.positions.assign(200, {0, 0, 0});
  for (std::size_t i = 0; i < 200; ++i) cloud_.positions[i] = {double(i), 0, 0};
  cloud_.colors.assign(200, {0.5, 0.5, 0.5});
  std::string text;
  const nlohmann::json d = write(kDisplayBudget, text);
  const auto& layer = d["layers"][0];
  EXPECT_EQ(layer["max"], 1000.0);
  EXPECT_EQ(layer["clip_percentile"], 99.0);
  EXPECT_DOUBLE_EQ(layer["clip_value"].get<double>(), 0.009);  // rank 198 of 200
  EXPECT_NE(text.find("value=\"clip\" checked"), std::string::npos);
  EXPECT_NE(text.find("id=\"clip-pct\""), std::string::npos);
}

TEST(HtmlReport, PercentileIsTheNearestRank) {
  EXPECT_EQ(percentile({5, 1, 4, 2, 3}, 99), 5.0);
  EXPECT_EQ(percentile({5, 1, 4, 2, 3}, 40), 2.0);
  EXPECT_EQ(percentile({NAN, 7}, 50), 7.0);
  EXPECT_EQ(percentile({}, 99), 0.0);
  EXPECT_EQ(without_noise({1e-13, -5e-13, 2e-12, 1}, 1)[0], 0.0);
  EXPECT_EQ(without_noise({1e-13, -5e-13, 2e-12, 1}, 1)[2], 2e-12);
  EXPECT_EQ(without_noise({5e-10}, 1000)[0], 0.0);  // 1e-12 of a 1000-wide object
}

// Scores in the index with 6 significant digits (the cell's data-value keeps every digit).
TEST(HtmlReport, IndexShowsSixSignificantDigits) {
  const fs::path file = fs::temp_directory_path() /
                        ("qm3d_html_report_digits_" + std::to_string(::getpid()) + ".html");
  write_report_index(file, {{"r.ply", "a.ply", "cmdm", 1.0 / 3, "", ""}}, "t");
  const std::string text = slurp(file);
  fs::remove(file);
  EXPECT_NE(text.find(">0.333333</td>"), std::string::npos) << text;
  EXPECT_EQ(text.find(">0.3333333333"), std::string::npos);
  EXPECT_NE(text.find("data-value=\"0.3333333333"), std::string::npos);  // every digit
}

TEST(HtmlReport, IndexSortsByScoreAndLinksReports) {
  const fs::path file = fs::temp_directory_path() /
                        ("qm3d_html_report_index_" + std::to_string(::getpid()) + ".html");
  write_report_index(file,
                     {{"r.ply", "low.ply", "cmdm", 0.1, "", "low.html"},
                      {"r.ply", "bad.ply", "cmdm", std::nullopt, "cannot read", ""},
                      {"r.ply", "high.ply", "cmdm", 0.9, "", "high.html"}},
                     "t");
  const std::string text = slurp(file);
  fs::remove(file);
  const auto high = text.find("high.ply"), low = text.find("low.ply"), bad = text.find("bad.ply");
  ASSERT_NE(high, std::string::npos);
  EXPECT_LT(high, low);
  EXPECT_LT(low, bad);
  EXPECT_NE(text.find("<a href=\"high.html\">"), std::string::npos);
  EXPECT_NE(text.find("cannot read"), std::string::npos);
}

// A quality column (psnr) puts its lowest score first and tints it most; +inf (unchanged
// geometry) is the least distorted, written for JavaScript's parseFloat.
TEST(HtmlReport, IndexOrdersAQualityLowestFirst) {
  const fs::path file = fs::temp_directory_path() /
                        ("qm3d_html_report_qindex_" + std::to_string(::getpid()) + ".html");
  write_report_index(file,
                     {{"r.ply", "mid.ply", "psnr", 30.0, "", "", true},
                      {"r.ply", "same.ply", "psnr", HUGE_VAL, "", "", true},
                      {"r.ply", "worst.ply", "psnr", 10.0, "", "", true},
                      {"r.ply", "best.ply", "psnr", 50.0, "", "", true}},
                     "t");
  const std::string text = slurp(file);
  fs::remove(file);
  const auto worst = text.find("worst.ply"), mid = text.find("mid.ply"),
             best = text.find("best.ply"), same = text.find("same.ply");
  ASSERT_NE(worst, std::string::npos);
  EXPECT_LT(worst, mid);
  EXPECT_LT(mid, best);
  EXPECT_LT(best, same);
  EXPECT_NE(text.find("data-worse=\"lower\""), std::string::npos);
  EXPECT_NE(text.find("data-value=\"Infinity\""), std::string::npos);
  EXPECT_NE(text.find("data-value=\"10\" style=\"background:rgba(215,48,39,0.45)\""),
            std::string::npos);
  EXPECT_NE(text.find("data-value=\"50\" style=\"background:rgba(215,48,39,0.00)\""),
            std::string::npos);
}

}  // namespace
}  // namespace qm3d::report
