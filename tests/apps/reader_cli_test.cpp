// End-to-end tests of what the readers report and take (issue 24): --colour-scale and the
// readers' warnings on stderr, through the built `qm3d` binary.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_runner.h"
#include "qm3d/common/ply.h"
#include "qm3d/mesh/mesh_io.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

class ReaderCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_reader_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
  }
  void TearDown() override { fs::remove_all(dir_); }

  test::CliRun qm3d(const std::string& args) {
    return test::run_qm3d(args, dir_, dir_ / "io",
                          "QM3D_DATA_DIR='" + test::tables_dir().string() + "'");
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

// The bundled 2000-point cloud with its colours written as float 0..1 (c / 255), the green of
// point 5 replaced by `odd` when given.
void write_float_colour_cloud(const fs::path& out, const std::string& odd = "") {
  const ply::Content c = ply::read(test::source_dir() / "data/clouds/sphere_2k_ref.ply");
  std::ofstream o(out);
  o.precision(17);
  o << "ply\nformat ascii 1.0\nelement vertex " << c.positions.size()
    << "\nproperty float x\nproperty float y\nproperty float z\nproperty float red\n"
       "property float green\nproperty float blue\nend_header\n";
  for (std::size_t i = 0; i < c.positions.size(); ++i) {
    const auto& p = c.positions[i];
    o << p[0] << ' ' << p[1] << ' ' << p[2] << ' ' << c.colors[i].r << ' ';
    if (i == 5 && !odd.empty()) {
      o << odd;
    } else {
      o << c.colors[i].g;
    }
    o << ' ' << c.colors[i].b << '\n';
  }
}

// Issue 24: one colour value of 1.0000001 made PCQM 0.72 instead of ~0 with exit 0 and no word.
TEST_F(ReaderCli, OneFloatColourAboveOneIsAWarningAndColourScaleUnitReadsItAs0To1) {
  write_float_colour_cloud(dir_ / "ref.ply");
  write_float_colour_cloud(dir_ / "odd.ply", "1.0000001");
  const test::CliRun automatic =
      qm3d("pcqm '" + path("ref.ply") + "' '" + path("odd.ply") + "' --csv");
  ASSERT_EQ(automatic.code, 0) << automatic.err;
  // A line over 160 characters names the file by its name alone (issue 44: one short line).
  EXPECT_NE(automatic.err.find(std::string("qm3d: warning: odd.ply") +
                               ": 1 of 6000 colour values above 1 (max 1.0000001192092896): "
                               "read as 0..255 like the reference; --colour-scale unit reads "
                               "them as 0..1"),
            std::string::npos)
      << automatic.err;
  const test::CliRun unit =
      qm3d("pcqm '" + path("ref.ply") + "' '" + path("odd.ply") + "' --colour-scale unit --json");
  ASSERT_EQ(unit.code, 0) << unit.err;
  EXPECT_NE(unit.err.find("clamped to 1 (--colour-scale unit)"), std::string::npos) << unit.err;
  EXPECT_NE(unit.out.find("clamped to 1 (--colour-scale unit)"), std::string::npos)
      << "the warning is in the JSON result too";
  const double score_unit = std::stod(unit.out.substr(unit.out.find("\"score\":") + 8));
  EXPECT_LT(score_unit, 1e-3) << "one value clamped from 1.0000001 to 1 changes almost nothing";

  const test::CliRun bad =
      qm3d("pcqm '" + path("ref.ply") + "' '" + path("odd.ply") + "' --colour-scale percent");
  EXPECT_EQ(bad.code, 1) << bad.err;
  EXPECT_NE(bad.err.find("--colour-scale"), std::string::npos) << bad.err;
}

TEST_F(ReaderCli, ObjColourScaleOptionAppliesToMeshMetrics) {
  const mesh::MeshFile m = mesh::read_mesh(test::source_dir() / "data/meshes/blob3_ref.off");
  std::ofstream o(dir_ / "ref.obj");
  o.precision(9);
  for (std::size_t i = 0; i < m.mesh.positions.size(); ++i) {
    const auto& p = m.mesh.positions[i];
    o << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << ' '
      << (i == 0 ? std::string("1.0000001") : std::to_string(m.mesh.colors[i].r)) << ' '
      << m.mesh.colors[i].g << ' ' << m.mesh.colors[i].b << '\n';
  }
  for (const auto& t : m.mesh.triangles)
    o << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  o.close();
  const std::string pair = " '" + path("ref.obj") + "' '" + path("ref.obj") + "'";
  const test::CliRun automatic = qm3d("cmdm" + pair);
  ASSERT_EQ(automatic.code, 0) << automatic.err;
  EXPECT_NE(automatic.err.find("ref.obj: 1 of 1926 colour values above 1"),  // name alone: a short line
            std::string::npos)
      << automatic.err;
  const test::CliRun byte = qm3d("cmdm --colour-scale byte" + pair);
  ASSERT_EQ(byte.code, 0) << byte.err;
  EXPECT_EQ(byte.err.find("colour values above 1"), std::string::npos) << byte.err;
}

// Issue 24: coordinates declared float far from the origin lose their detail without a word
// (here at 2e5 the float32 step, 1/64, is above 1/8 of the spacing, about 0.077).
TEST_F(ReaderCli, Float32CoordinatesFarFromTheOriginAreAWarning) {
  const ply::Content c = ply::read(test::source_dir() / "data/clouds/sphere_2k_ref.ply");
  ply::WriteData far;
  for (std::size_t i = 0; i < c.positions.size(); ++i) {
    far.positions.push_back({c.positions[i][0] + 2e5, c.positions[i][1], c.positions[i][2]});
    far.colors.push_back({std::uint8_t(c.colors[i].r * 255 + 0.5), 0, 0});
  }
  ply::write(dir_ / "far.ply", far);
  const test::CliRun r = qm3d("pcqm '" + path("far.ply") + "' '" + path("far.ply") + "'");
  EXPECT_NE(r.err.find("far.ply: coordinates stored as float32"), std::string::npos)  // name alone
      << r.err;
}

}  // namespace
}  // namespace qm3d
