#include "qm3d/common/color.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "qm3d/common/error.h"
#include "test_paths.h"

namespace qm3d {
namespace {

const Lab2000hlTable& table() {
  static const auto t = Lab2000hlTable::shared(test::tables_dir());
  return *t;
}

struct ReferenceRow {
  int r, g, b;
  Lab lab, hl;
};

std::vector<ReferenceRow> reference_rows() {
  std::ifstream in(test::reference_dir() / "lab2000hl_reference_values.txt");
  std::vector<ReferenceRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string word, bar;
    ReferenceRow row{};
    s >> word >> row.r >> row.g >> row.b >> bar >> word >> row.lab.L >> row.lab.a >> row.lab.b >>
        bar >> word >> row.hl.L >> row.hl.a >> row.hl.b;
    if (s) rows.push_back(row);
  }
  return rows;
}

TEST(Color, ReproducesEveryReferenceRow) {
  const auto rows = reference_rows();
  ASSERT_EQ(rows.size(), 14u);
  for (const auto& row : rows) {
    SCOPED_TRACE(std::to_string(row.r) + " " + std::to_string(row.g) + " " + std::to_string(row.b));
    const Rgb rgb{row.r / 255.0, row.g / 255.0, row.b / 255.0};
    const Lab lab = srgb_to_cielab(rgb);
    EXPECT_NEAR(lab.L, row.lab.L, 1e-9);
    EXPECT_NEAR(lab.a, row.lab.a, 1e-9);
    EXPECT_NEAR(lab.b, row.lab.b, 1e-9);
    const Lab hl = table().from_srgb(rgb);
    EXPECT_NEAR(hl.L, row.hl.L, 1e-7);
    EXPECT_NEAR(hl.a, row.hl.a, 1e-7);
    EXPECT_NEAR(hl.b, row.hl.b, 1e-7);
  }
}

// LAB2000HL lightness is the integral of CIEDE2000's 1/S_L from 0 to L*, with
// S_L = 1 + 0.015 (L - 50)^2 / sqrt(20 + (L - 50)^2) (Sharma et al. 2005, eq. 10). Integrate it
// with Simpson's rule on each 0.001 step and compare with the whole table (4 decimals stored).
TEST(Color, LightnessTableIsTheIntegralOfInverseSL) {
  auto inv_sl = [](double l) {
    const double d2 = (l - 50) * (l - 50);
    return 1.0 / (1.0 + 0.015 * d2 / std::sqrt(20 + d2));
  };
  double integral = 0;
  double worst = 0;
  for (std::size_t i = 0; i < Lab2000hlTable::kLightnessSize; ++i) {
    const double l = i * 0.001;
    if (i > 0) {
      const double l0 = (i - 1) * 0.001;
      integral += 0.001 / 6 * (inv_sl(l0) + 4 * inv_sl((l0 + l) / 2) + inv_sl(l));
    }
    worst = std::max(worst, std::fabs(table().lightness(l) - integral));
  }
  EXPECT_LT(worst, 1e-4);
}

TEST(Color, LightnessInterpolatesLinearlyAndClamps) {
  // Between grid points 50.000 and 50.001 the value is the linear blend of the two entries.
  const double a = table().lightness(50.000), b = table().lightness(50.001);
  EXPECT_NEAR(table().lightness(50.0005), (a + b) / 2, 1e-12);
  EXPECT_DOUBLE_EQ(table().lightness(100.0), table().lightness(250.0));  // last value above 100
  EXPECT_DOUBLE_EQ(table().lightness(-3.0), table().lightness(0.0));
  EXPECT_NEAR(table().lightness(100.0), 75.1532, 1e-9);
}

TEST(Color, WhiteAndRedMatchTheSpecExamples) {
  const Lab white = table().from_srgb({1, 1, 1});
  EXPECT_NEAR(white.L, 75.15219, 1e-5);
  EXPECT_NEAR(white.a, 0.01117, 1e-5);
  const Lab red = table().from_srgb({1, 0, 0});
  EXPECT_NEAR(red.a, 35.66812, 1e-5);
  EXPECT_NEAR(red.b, 24.13477, 1e-5);
}

TEST(Color, SrgbGammaHasBothBranches) {
  EXPECT_DOUBLE_EQ(srgb_to_linear(0.02), 0.02 / 12.92);
  EXPECT_DOUBLE_EQ(srgb_to_linear(0.5), std::pow((0.5 + 0.055) / 1.055, 2.4));
  EXPECT_DOUBLE_EQ(srgb_to_linear(1.0), 1.0);
}

TEST(Color, HueDifferenceIsZeroForSameHueAndPositiveOtherwise) {
  EXPECT_DOUBLE_EQ(hue_difference({50, 3, 4}, {50, 6, 8}), 0.0);  // same hue, chroma 5 vs 10
  // Opposite hues with equal chroma 5: da^2 + db^2 = 100, dC = 0 -> dH = 10.
  EXPECT_NEAR(hue_difference({50, 3, 4}, {50, -3, -4}), 10.0, 1e-12);
  EXPECT_DOUBLE_EQ(chroma({0, 3, 4}), 5.0);
}

class TableFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("qm3d_tables_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    for (const char* f : {"L_data.txt", "RegularGridInit_0_0_1.txt", "RegularGridInit_0_0_2.txt",
                          "RegularGrid_0_0_1.txt", "RegularGrid_0_0_2.txt"}) {
      std::filesystem::copy_file(test::tables_dir() / f, dir_ / f);
    }
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string load_error() {
    try {
      Lab2000hlTable::load(dir_);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
  std::filesystem::path dir_;
};

TEST_F(TableFiles, LoadsACompleteCopy) { EXPECT_EQ(load_error(), ""); }

TEST_F(TableFiles, MissingLightnessTableIsAnErrorNamingTheFile) {
  std::filesystem::remove(dir_ / "L_data.txt");
  const std::string msg = load_error();
  EXPECT_NE(msg.find("L_data.txt"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;
  EXPECT_THROW(Lab2000hlTable::load(dir_), InputError);
}

TEST_F(TableFiles, ShortTableIsAnError) {
  std::ofstream(dir_ / "RegularGrid_0_0_2.txt") << "1.0\n2.0\n";
  const std::string msg = load_error();
  EXPECT_NE(msg.find("RegularGrid_0_0_2.txt: expected 66049 values, found 2"), std::string::npos)
      << msg;
}

TEST_F(TableFiles, MalformedValueIsAnError) {
  std::ifstream in(test::tables_dir() / "L_data.txt");
  std::ofstream out(dir_ / "L_data.txt");
  std::string line;
  for (int i = 0; std::getline(in, line); ++i) out << (i == 7 ? "0.00x4" : line) << "\n";
  out.close();
  const std::string msg = load_error();
  EXPECT_NE(msg.find("L_data.txt: line 8 is not a number"), std::string::npos) << msg;
}

TEST_F(TableFiles, MissingDirectoryIsAnError) {
  std::filesystem::remove_all(dir_);
  EXPECT_THROW(Lab2000hlTable::load(dir_), InputError);
}

TEST(Color, DataDirResolutionPrefersExplicitThenEnvironment) {
  EXPECT_EQ(resolve_data_dir("/x/y"), std::filesystem::path("/x/y"));
  ::setenv("QM3D_DATA_DIR", "/from/env", 1);
  EXPECT_EQ(resolve_data_dir(), std::filesystem::path("/from/env"));
  ::unsetenv("QM3D_DATA_DIR");
  EXPECT_FALSE(resolve_data_dir().empty());
}

TEST(Color, SharedTableIsLoadedOnce) {
  EXPECT_EQ(Lab2000hlTable::shared(test::tables_dir()).get(),
            Lab2000hlTable::shared(test::tables_dir()).get());
}

}  // namespace
}  // namespace qm3d
