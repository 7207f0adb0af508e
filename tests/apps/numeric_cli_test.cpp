// The tool on numerically hostile requests (issue 24): thread counts libgomp cannot start,
// coordinates whose squares overflow or underflow, NaN weights, radii and densities out of any
// meaningful range. Each is a one-line error and a non-zero exit, never a signal, a NaN score
// with exit 0 or an empty output file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "cli_runner.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;
using test::CliRun;

class NumericCli : public ::testing::Test {
 protected:
  void SetUp() override {
    // The process id keeps concurrent runs (several build trees) out of each other's way.
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_numeric_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
            std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "cwd");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A coloured tetrahedron with coordinates times `scale`, as an OFF file.
  fs::path tetrahedron(const std::string& name, double scale) {
    std::ostringstream off;
    off.precision(17);
    off << "COFF\n4 4 0\n";
    const double corners[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 4; ++i) {
      off << corners[i][0] * scale << ' ' << corners[i][1] * scale << ' ' << corners[i][2] * scale
          << ' ' << 60 * i << " 100 200 255\n";
    }
    off << "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    std::ofstream(dir_ / name) << off.str();
    return dir_ / name;
  }

  CliRun run(const std::string& args) { return test::run_qm3d(args, dir_ / "cwd", dir_); }

  // Exit `code`, one line on stderr containing `what`, nothing on stdout.
  static void expect_refused(const CliRun& o, int code, const std::string& what) {
    EXPECT_EQ(o.code, code) << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_NE(o.err.find(what), std::string::npos) << "expected '" << what << "' in: " << o.err;
    EXPECT_EQ(o.out, "");
  }

  fs::path dir_;
};

// 65536 and 10^6 threads crashed in libgomp (SIGSEGV), 33000 aborted.
TEST_F(NumericCli, AbsurdThreadCountsAreRefusedBeforeAnyThreadStarts) {
  const std::string m = tetrahedron("m.off", 1).string();
  for (const char* threads : {"65536", "33000", "1000000"}) {
    expect_refused(run(std::string("--threads ") + threads + " cmdm " + m + " " + m), 1,
                   std::string("qm3d: error: threads: ") + threads + " is more than the ");
    expect_refused(run(std::string("sample ") + m + " --points 10 -o out.ply --threads " + threads),
                   1, "is more than the ");
  }
  EXPECT_FALSE(fs::exists(dir_ / "cwd" / "out.ply"));
  const CliRun ok = run("--threads 2 cmdm " + m + " " + m);
  EXPECT_EQ(ok.code, 0) << ok.err;
}

// Coordinates of 1e100 .. 1e300 (squares overflow) or a box of 1e-100 .. 1e-300 (squares
// underflow) gave NaN scores with exit 0.
TEST_F(NumericCli, CoordinatesWhoseSquaresOverflowOrUnderflowAreANumericError) {
  for (const double scale : {1e100, 1e300}) {
    const std::string m = tetrahedron("big.off", scale).string();
    for (const char* metric : {"cmdm", "msdm2", "pcqm"}) {
      SCOPED_TRACE(std::string(metric) + " at " + std::to_string(scale));
      expect_refused(run(std::string(metric) + " " + m + " " + m), 2,
                     "big.off: coordinates up to ");
    }
  }
  for (const double scale : {1e-100, 1e-300}) {
    const std::string m = tetrahedron("small.off", scale).string();
    for (const char* metric : {"cmdm", "msdm2", "pcqm"}) {
      SCOPED_TRACE(std::string(metric) + " at " + std::to_string(scale));
      expect_refused(run(std::string(metric) + " " + m + " " + m), 2,
                     "small.off: the bounding box's longest side is ");
    }
  }
}

TEST_F(NumericCli, NanWeightsAndRadiiOutOfRangeAreRefused) {
  const std::string m = tetrahedron("m.off", 1).string();
  expect_refused(run("cmdm " + m + " " + m + " --weights nan,0,0,0,0,0,0,0"), 1,
                 "weights: weight 1 of 8 is nan (must be finite)");
  for (const char* radius : {"1e-300", "nan", "1e300"}) {
    const CliRun o = run("pcqm " + m + " " + m + " --radius " + radius);
    EXPECT_NE(o.code, 0) << radius;
    EXPECT_NE(o.code, -1) << radius;
    EXPECT_EQ(o.out, "") << radius;
  }
}

// --density 1e19 wrote an empty cloud with exit 0.
TEST_F(NumericCli, AnAbsurdDensityIsRefusedWithTheCountItWouldGive) {
  const std::string m = tetrahedron("m.off", 1).string();
  expect_refused(run("sample " + m + " --density 1e19 -o out.ply"), 2,
                 "more than the 1000000000 one sampling draws (lower the density)");
  EXPECT_FALSE(fs::exists(dir_ / "cwd" / "out.ply"));
  EXPECT_FALSE(fs::exists(dir_ / "out.ply"));
}

}  // namespace
}  // namespace qm3d
