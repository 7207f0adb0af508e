// psnr (qm3d/pointcloud/psnr.h) against MPEG pc_error 0.14.2's own output on the 28 cases of
// shared/data/reference/mpeg/pc_error_reference.csv, through the registry entry (the options as
// the tool and Python pass them) and the library function; plus pc_error's loading rules on
// small hand-made clouds, thread independence and bad input.
#include "qm3d/pointcloud/psnr.h"
#include "qm3d/study/batch_row.h"

#include <gtest/gtest.h>

#include <random>
#include <tuple>
#include <numeric>
#include <algorithm>
#include <iterator>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "mpeg_reference.h"
#include "psnr_engine.h"
#include "psnr_reader.h"
#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/ply.h"
#include "qm3d/common/result_io.h"
#include "qm3d/pointcloud/cloud_io.h"
#include "qm3d/pointcloud/metrics.h"
#include "test_paths.h"

namespace qm3d::pointcloud {
namespace {

using test::PcErrorCase;

const Registry& cloud_registry() {
  static const Registry r = [] {
    Registry reg;
    register_metrics(reg);
    return reg;
  }();
  return r;
}

// The case's pc_error options as the registry's option values (what `qm3d psnr` passes).
OptionValues option_values(const PcErrorCase& c) {
  OptionValues v = OptionValues::object();
  if (const auto r = test::pc_error_option(c, "-r")) v["peak"] = std::stod(*r);
  if (const auto n = test::pc_error_option(c, "-n")) v["normals"] = (test::shared_data() / *n).string();
  if (const auto d = test::pc_error_option(c, "--dropdups")) v["drop_duplicates"] = std::stoi(*d);
  if (const auto p = test::pc_error_option(c, "--neighborsProc")) v["neighbours"] = std::stoi(*p);
  if (const auto a = test::pc_error_option(c, "--averageNormals")) v["average_normals"] = *a != "0";
  if (const auto m = test::pc_error_option(c, "--mseSpace")) {
    v["color_space"] = *m == "0" ? "rgb" : *m == "8" ? "ycocg" : "ycbcr";
  }
  return v;
}

std::optional<double> value_of(const NamedValues& v, const std::string& name) {
  return find_value(v, name);
}

void expect_case(const PcErrorCase& c, const MetricResult& r) {
  ASSERT_TRUE(r.ref_to_dist && r.dist_to_ref);
  for (const auto& [column, name] : test::pc_error_value_columns()) {
    test::expect_pc_error_value(c, "AB_" + column, value_of(r.ref_to_dist->values, name));
    test::expect_pc_error_value(c, "BA_" + column, value_of(r.dist_to_ref->values, name));
    test::expect_pc_error_value(c, "sym_" + column, value_of(r.values, name));
  }
  EXPECT_NEAR(r.details.at("peak").get<double>(), std::stod(c.column.at("peak")),
              1e-8 * std::stod(c.column.at("peak")));
  if (!c.column.at("nn_max").empty()) {
    EXPECT_NEAR(r.details.at("nn_max").get<double>(), std::stod(c.column.at("nn_max")),
                1e-8 * std::stod(c.column.at("nn_max")));
    EXPECT_NEAR(r.details.at("nn_min").get<double>(), std::stod(c.column.at("nn_min")),
                1e-8 * std::stod(c.column.at("nn_min")));
  }
  EXPECT_EQ(r.details.at("points_reference").get<std::size_t>(), std::stoul(c.column.at("nA")));
  EXPECT_EQ(r.details.at("points_distorted").get<std::size_t>(), std::stoul(c.column.at("nB")));
  const auto dups = [&](const char* col) {
    return c.column.at(col).empty() ? 0ul : std::stoul(c.column.at(col));
  };
  EXPECT_EQ(r.details.at("duplicates_reference").get<std::size_t>(), dups("dups_a"));
  EXPECT_EQ(r.details.at("duplicates_distorted").get<std::size_t>(), dups("dups_b"));
  EXPECT_EQ(r.score, *value_of(r.values, "d1_psnr"));
}

MetricResult run_case(const PcErrorCase& c, int threads = 0) {
  const Registry& reg = cloud_registry();
  const Input a = reg.read(test::shared_data() / c.column.at("a"));
  const Input b = reg.read(test::shared_data() / c.column.at("b"));
  RunOptions run;
  run.threads = threads;
  return run_metric(reg.get("psnr"), a, b, run, option_values(c));
}

TEST(Psnr, EveryPcErrorReferenceCaseWithin1e8) {
  const auto cases = test::pc_error_cases();
  ASSERT_EQ(cases.size(), 28u);
  for (const PcErrorCase& c : cases) {
    SCOPED_TRACE(c.name);
    expect_case(c, run_case(c));
  }
}

TEST(Psnr, JsonCarriesTheValuesWithInfinityAsNull) {
  for (const PcErrorCase& c : test::pc_error_cases()) {
    if (c.name != "vox1_ref_self" && c.name != "sph_gnoise0.001") continue;
    const nlohmann::json j = to_json(run_case(c));
    test::expect_pc_error_json(c, j);
    EXPECT_TRUE(j.contains("peak"));
    EXPECT_FALSE(j["directions"]["ref_to_dist"].contains("box_size"));
  }
}

// The registry's orientation of each result column: the score and the *_psnr values are
// qualities, the MSEs and Hausdorff distances distortions, other columns unknown.
TEST(Psnr, ColumnsKnowWhetherHigherIsBetter) {
  const MetricSpec& psnr = cloud_registry().get("psnr");
  EXPECT_EQ(psnr.column_higher_is_better("score"), true);
  EXPECT_EQ(psnr.column_higher_is_better("ref_to_dist_score"), true);
  EXPECT_EQ(psnr.column_higher_is_better("d1_psnr"), true);
  EXPECT_EQ(psnr.column_higher_is_better("dist_to_ref_c2_hausdorff_psnr"), true);
  EXPECT_EQ(psnr.column_higher_is_better("d2_mse"), false);
  EXPECT_EQ(psnr.column_higher_is_better("c0_hausdorff"), false);
  EXPECT_EQ(psnr.column_higher_is_better("seconds"), std::nullopt);
  const MetricSpec& pcqm = cloud_registry().get("pcqm");
  EXPECT_EQ(pcqm.column_higher_is_better("score"), false);
  EXPECT_EQ(pcqm.column_higher_is_better("dist_to_ref_f3"), std::nullopt);
}

TEST(Psnr, SameBitsForAnyThreadCount) {
  for (const PcErrorCase& c : test::pc_error_cases()) {
    if (c.name != "vox1_requant8dup_np2" && c.name != "sph_down0.5") continue;
    const MetricResult one = run_case(c, 1), two = run_case(c, 2), three = run_case(c, 3);
    for (const MetricResult* r : {&two, &three}) {
      ASSERT_EQ(r->values.size(), one.values.size());
      for (std::size_t i = 0; i < one.values.size(); ++i) {
        EXPECT_EQ(std::memcmp(&r->values[i].second, &one.values[i].second, sizeof(double)), 0)
            << c.name << " " << one.values[i].first;
      }
    }
  }
}

TEST(Psnr, OneDirectionIsThatPass) {
  const auto cases = test::pc_error_cases();
  const PcErrorCase& c = cases[2];  // sph_gnoise0.001
  const Registry& reg = cloud_registry();
  const Input a = reg.read(test::shared_data() / c.column.at("a"));
  const Input b = reg.read(test::shared_data() / c.column.at("b"));
  RunOptions run;
  run.direction = Direction::kRefToDist;
  const MetricResult r = run_metric(reg.get("psnr"), a, b, run, option_values(c));
  EXPECT_FALSE(r.dist_to_ref);
  for (const auto& [column, name] : test::pc_error_value_columns()) {
    test::expect_pc_error_value(c, "AB_" + column, value_of(r.values, name));
  }
}

TEST(Psnr, EstimatedNormalsGivePcErrorsD2OnTheToolsFile) {
  // vox1_ref_n.ply = vox1_ref.ply + add_pca_normals.py's normals: estimating them on vox1_ref.ply
  // must give the D2 of the case with the file.
  for (const PcErrorCase& c : test::pc_error_cases()) {
    if (c.name != "vox1_gnoise1") continue;
    const Registry& reg = cloud_registry();
    const Input a = reg.read(test::reference_dir() / "voxel" / "vox1_ref.ply");
    const Input b = reg.read(test::shared_data() / c.column.at("b"));
    OptionValues v = option_values(c);
    v["normals"] = "estimate";
    const MetricResult r = run_metric(reg.get("psnr"), a, b, {}, v);
    EXPECT_EQ(r.details.at("normals"), "estimated");
    for (const std::string col : {"d2_mse", "d2_psnr", "d2_haus", "d2_haus_psnr"}) {
      const std::string ours = col.find("haus") != std::string::npos
                                   ? col.substr(0, 3) + "hausdorff" + col.substr(7)
                                   : col;
      test::expect_pc_error_value(c, "AB_" + col, value_of(r.ref_to_dist->values, ours));
      test::expect_pc_error_value(c, "BA_" + col, value_of(r.dist_to_ref->values, ours));
      test::expect_pc_error_value(c, "sym_" + col, value_of(r.values, ours));
    }
  }
}

// ---- pc_error's loading rules -----------------------------------------------------------------

ColoredCloud cloud(std::vector<Vec3> p, std::vector<Rgb> c) { return {std::move(p), std::move(c)}; }

TEST(PsnrLoading, SortsAndAveragesDuplicatesWithTruncatedMeanColour) {
  const ColoredCloud c = cloud({{1, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}},
                               {{10 / 255.0, 0, 0}, {1, 1, 1}, {13 / 255.0, 1, 0}, {0, 0, 0}});
  const detail::MpegCloud m = detail::load_mpeg_cloud(c.positions, &c.colors, {}, 2, true);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m.duplicates, 1u);
  EXPECT_EQ(m.points[0], (detail::Point3f{0, 0, 0}));
  EXPECT_EQ(m.points[1], (detail::Point3f{0, 0, 1}));
  EXPECT_EQ(m.points[2], (detail::Point3f{1, 0, 0}));
  EXPECT_EQ(m.colours[2], (detail::Colour8{11, 127, 0}));  // (10+13)/2, (0+255)/2 truncated
  EXPECT_EQ(m.merged[2], 2);
  EXPECT_EQ(m.merged[0], 1);
  EXPECT_EQ(m.of_input, (std::vector<std::uint32_t>{2, 0, 2, 1}));
  const detail::MpegCloud dropped = detail::load_mpeg_cloud(c.positions, &c.colors, {}, 1, true);
  EXPECT_EQ(dropped.colours[2], (detail::Colour8{10, 0, 0}));  // the first in file order
  EXPECT_EQ(dropped.merged[2], 1);
  const detail::MpegCloud kept = detail::load_mpeg_cloud(c.positions, &c.colors, {}, 0, true);
  EXPECT_EQ(kept.size(), 4u);
  EXPECT_EQ(kept.duplicates, 0u);
}

// The radix sort gives the permutation of pc_error's std::sort with an index tie-break: the
// lexicographic float order, -0 equal to +0, ties in file order (checked on many ties, negative
// and signed-zero coordinates, and magnitudes across the exponent range).
TEST(PsnrLoading, SortIsTheLexicographicFloatOrderWithTiesInFileOrder) {
  std::mt19937_64 rng(7);
  const double values[] = {-0.0, 0.0, 1.0, -1.0, 0.5, -3e10, 3e10, 1e-30, -1e-30, 2.25, 1023};
  std::vector<Vec3> p(20000);
  for (Vec3& v : p) {
    for (int d = 0; d < 3; ++d) {
      v[d] = (rng() % 4 == 0) ? (static_cast<double>(rng() % 2000001) - 1e6) * 1e-3
                              : values[rng() % std::size(values)];
    }
  }
  const detail::MpegCloud m = detail::load_mpeg_cloud(p, nullptr, {}, 0, false);
  std::vector<std::uint32_t> expected(p.size());
  std::iota(expected.begin(), expected.end(), 0u);
  const auto f = [&](std::uint32_t i) {
    return detail::Point3f{static_cast<float>(p[i][0]), static_cast<float>(p[i][1]),
                           static_cast<float>(p[i][2])};
  };
  std::sort(expected.begin(), expected.end(), [&](std::uint32_t a, std::uint32_t b) {
    return f(a) == f(b) ? a < b : f(a) < f(b);
  });
  ASSERT_EQ(m.size(), p.size());
  for (std::size_t k = 0; k < p.size(); ++k) {
    ASSERT_EQ(m.of_input[expected[k]], k) << "place " << k;
    ASSERT_EQ(m.points[k], f(expected[k])) << "place " << k;
  }
}

TEST(PsnrLoading, CoordinatesAndNormalsBecomeFloat32) {
  const ColoredCloud c = cloud({{0.1, 0.2, 0.3}}, {{0, 0, 0}});
  const detail::MpegCloud m = detail::load_mpeg_cloud(c.positions, &c.colors, {{0.1, 0.2, 0.3}}, 2, false);
  EXPECT_EQ(m.points[0][0], 0.1f);
  EXPECT_EQ(m.normals[0][2], 0.3f);
}

// psnr's own reader (psnr_reader.h) gives what the general reader gives, rounded as pc_error reads
// it (the same points, colours, normals and warnings); every other layout, and a file the general
// reader refuses (a NaN coordinate), is left to the general reader.
TEST(PsnrReader, ReadsBinaryCloudsAsTheGeneralReaderAndLeavesOtherLayouts) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "qm3d_psnr_reader_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::mt19937_64 rng(3);
  const auto write = [&](const std::string& name, double offset, bool normals) {
    ply::WriteData d;
    std::vector<float> n[3];
    for (int i = 0; i < 2000; ++i) {
      d.positions.push_back({offset + (rng() % 100000) * 1e-3, (rng() % 100000) * 1e-3 - 50,
                             (rng() % 3 == 0) ? 0.0 : (rng() % 100000) * 1e-3});
      d.colors.push_back({std::uint8_t(rng()), std::uint8_t(rng()), std::uint8_t(rng())});
      for (auto& c : n) c.push_back(static_cast<float>(rng() % 2001) * 1e-3f - 1.0f);
    }
    d.scalar_names = {"quality"};  // a property the reader skips
    d.scalars.assign(d.positions.size(), 0.5f);
    if (normals) d.extra_scalars = {{"nx", n[0]}, {"ny", n[1]}, {"nz", n[2]}};
    ply::write(dir / name, d);
    return d;
  };
  for (const auto& [name, offset, normals] :
       {std::tuple{"plain.ply", 0.0, false}, std::tuple{"normals.ply", 0.0, true},
        std::tuple{"far.ply", 1e7, true}}) {  // far: the float32-rounding warning
    SCOPED_TRACE(name);
    write(name, offset, normals);
    const auto fast = detail::read_float_ply(dir / name);
    ASSERT_TRUE(fast);
    const CloudData general = read_cloud_data(dir / name, CloudFormat::kPly);
    const detail::FloatCloud expected =
        detail::float_cloud(general.cloud.positions, &general.cloud.colors, general.normals);
    EXPECT_EQ(fast->cloud.positions, expected.positions);
    EXPECT_EQ(fast->cloud.colours, expected.colours);
    EXPECT_EQ(fast->cloud.normals, expected.normals);
    EXPECT_EQ(fast->cloud.normals.empty(), !normals);
    EXPECT_EQ(fast->warnings, general.warnings);
    EXPECT_EQ(fast->warnings.empty(), offset == 0.0);
  }
  ply::WriteData d = write("ascii.ply", 0, false);
  d.format = ply::Format::kAscii;
  ply::write(dir / "ascii.ply", d);
  d.format = ply::Format::kBinaryLittleEndian;
  d.double_positions = true;
  ply::write(dir / "double.ply", d);
  d.double_positions = false;
  d.triangles = {{0, 1, 2}};
  ply::write(dir / "faces.ply", d);
  d.triangles.clear();
  d.positions[7][1] = std::nan("");
  ply::write(dir / "nan.ply", d);
  fs::copy_file(dir / "plain.ply", dir / "short.ply");
  fs::resize_file(dir / "short.ply", fs::file_size(dir / "plain.ply") - 1);
  for (const char* other : {"ascii.ply", "double.ply", "faces.ply", "nan.ply", "short.ply"}) {
    EXPECT_FALSE(detail::read_float_ply(dir / other)) << other;
  }
  fs::remove_all(dir);
}

// The loading rules on float input without the optional arrays: the same cloud, no map from
// input points, no merged counts.
TEST(PsnrLoading, OptionalArraysAreLeftOutWhenNotAsked) {
  const ColoredCloud c = cloud({{1, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}},
                               {{10 / 255.0, 0, 0}, {1, 1, 1}, {13 / 255.0, 1, 0}, {0, 0, 0}});
  const detail::MpegCloud full = detail::load_mpeg_cloud(c.positions, &c.colors, {}, 2, false);
  detail::LoadRules rules;
  rules.keep_of_input = false;
  const detail::MpegCloud lean =
      detail::load_mpeg_cloud(detail::float_cloud(c.positions, &c.colors, {}), rules);
  EXPECT_EQ(lean.points, full.points);
  EXPECT_EQ(lean.colours, full.colours);
  EXPECT_EQ(lean.duplicates, full.duplicates);
  EXPECT_TRUE(lean.of_input.empty());
  EXPECT_TRUE(lean.merged.empty());
  EXPECT_EQ(full.of_input.size(), 4u);
}

// ---- values and bad input ------------------------------------------------------------------------

TEST(Psnr, IdenticalCloudsGiveInfinitePsnrAndZeroHausdorff) {
  const ColoredCloud c = cloud({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                               {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}});
  PsnrOptions o;
  o.peak = 1;
  const MetricResult r = compute_psnr(c, {}, c, o);
  EXPECT_EQ(r.score, HUGE_VAL);
  EXPECT_EQ(*find_value(r.values, "d1_hausdorff"), 0.0);
  EXPECT_EQ(*find_value(r.values, "d1_hausdorff_psnr"), HUGE_VAL);
  EXPECT_FALSE(find_value(r.values, "d2_mse"));  // no normals
  EXPECT_FALSE(r.warnings.empty());
  EXPECT_NE(text_line(r).find("inf"), std::string::npos);
  EXPECT_NE(study::csv_row(r, {}, psnr_value_names()).find(",inf,"), std::string::npos);
  EXPECT_TRUE(to_json(r)["features"]["d1_psnr"].is_null());
}

TEST(Psnr, RefusesBadInputNamingTheFile) {
  const ColoredCloud coloured = cloud({{0, 0, 0}, {1, 0, 0}}, {{1, 0, 0}, {0, 1, 0}});
  const ColoredCloud plain = cloud({{0, 0, 0}, {1, 0, 0}}, {});
  PsnrOptions o;
  o.peak = 1;
  try {
    compute_psnr(coloured, {}, plain, o, "ref.ply", "dist.ply");
    FAIL() << "no colours accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("dist.ply: no vertex colours"), std::string::npos) << e.what();
  }
  o.colour = false;
  EXPECT_NO_THROW(compute_psnr(coloured, {}, plain, o));
  try {
    compute_psnr(coloured, {{{0, 0, 1}}, {}, {}}, coloured, o, "ref.ply", "dist.ply");
    FAIL() << "one normal for two points accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("ref.ply: 1 normals for 2"), std::string::npos) << e.what();
  }
  try {
    compute_psnr(coloured, {{{0, 0, 1}, {NAN, 0, 1}}, {}, {}}, coloured, o, "ref.ply", "d.ply");
    FAIL() << "NaN normal accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("ref.ply: the normal of point 1 is not finite"),
              std::string::npos)
        << e.what();
  }
  ReferenceNormals short_file{{{0, 0, 1}}, {{0, 0, 0}}, "n.ply"};
  try {
    compute_psnr(coloured, short_file, coloured, o, "ref.ply", "dist.ply");
    FAIL() << "a normals file of one point accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("n.ply: 1 points"), std::string::npos) << e.what();
  }
  o.peak = 0;
  EXPECT_THROW(compute_psnr(coloured, {}, coloured, o), std::invalid_argument);
  o.peak.reset();
  const ColoredCloud one = cloud({{0, 0, 0}}, {});
  EXPECT_THROW(compute_psnr(one, {}, one, o), NumericError);  // no peak from one point
}

TEST(Psnr, NormalsFileMustHoldNormals) {
  const auto dir = std::filesystem::temp_directory_path() / "qm3d_psnr_normals";
  std::filesystem::create_directories(dir);
  ply::WriteData w;
  w.positions = {{0, 0, 0}, {1, 0, 0}};
  ply::write(dir / "plain.ply", w);
  const Registry& reg = cloud_registry();
  const Input a = reg.read(dir / "plain.ply");
  OptionValues v = {{"peak", 1.0}, {"no_color", true}, {"normals", (dir / "plain.ply").string()}};
  try {
    run_metric(reg.get("psnr"), a, a, {}, v);
    FAIL() << "a normals file without normals accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("plain.ply: no normals"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace qm3d::pointcloud
