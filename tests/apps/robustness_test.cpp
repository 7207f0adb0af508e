// What qm3d does with unusual and malformed input (issue 6): every case either has a documented,
// tested handling, or exits with code 2 and one line on stderr naming the file and the problem —
// never a crash, a hang, a silent wrong score or a partial output file. The README's
// "What qm3d does with unusual input" table lists the same cases.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "cli_runner.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;
using test::CliRun;
using test::slurp;

class Unusual : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_unusual_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "cwd");
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path file(const std::string& name, const std::string& content) {
    std::ofstream(dir_ / name, std::ios::binary) << content;
    return dir_ / name;
  }

  // Runs `qm3d <metric> a b --map map.ply` (under a time limit) in an empty directory.
  CliRun run(const std::string& metric, const fs::path& a, const fs::path& b) {
    const fs::path map = dir_ / "map.ply";
    fs::remove(map);
    const CliRun o = test::run_qm3d(metric + " '" + a.string() + "' '" + b.string() + "' --map '" +
                                        map.string() + "'",
                                    dir_ / "cwd", dir_);
    EXPECT_TRUE(fs::is_empty(dir_ / "cwd"));
    if (o.code != 0) {
      EXPECT_FALSE(fs::exists(map)) << "partial output after a failure";
    }
    return o;
  }

  // The input is rejected: exit 2, one line on stderr naming `name`, containing `what`.
  void expect_rejected(const std::string& metric, const fs::path& p, const std::string& what) {
    const CliRun o = run(metric, p, p);
    EXPECT_EQ(o.code, 2) << metric << " " << p << "\n" << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_EQ(o.err.rfind("qm3d: error: ", 0), 0u) << o.err;
    EXPECT_NE(o.err.find(p.filename().string()), std::string::npos) << o.err;
    EXPECT_NE(o.err.find(what), std::string::npos) << "expected '" << what << "' in: " << o.err;
    EXPECT_EQ(o.out, "");
  }

  fs::path dir_;
};

const std::string kPlyHeader =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n";
const std::string kTriangle = "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n";

std::string obj(const std::string& vertices, const std::string& faces = "f 1 2 3\n") {
  return vertices + faces;
}
const std::string kObjVertices = "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\n";

TEST_F(Unusual, EmptyAndTinyFiles) {
  expect_rejected("pcqm", file("empty.ply", ""), "not a PLY file");
  expect_rejected("cmdm", file("empty.obj", ""), "no vertices");
  expect_rejected("cmdm", file("empty.off", ""), "empty file");
  expect_rejected("pcqm", file("one.ply", "p"), "not a PLY file");
  expect_rejected("cmdm", file("one.off", "O"), "not an OFF file");
  expect_rejected("pcqm", file("empty.pcd", ""), "not a PCD file");
}

TEST_F(Unusual, WrongMagicAndUnknownExtension) {
  expect_rejected("pcqm", file("magic.ply", "plx\nformat ascii 1.0\nend_header\n"), "not a PLY file");
  expect_rejected("cmdm", file("magic.off", "MESH\n3 1 0\n"), "not an OFF file");
  expect_rejected("cmdm", file("mesh.stl", "solid x\n"), "unknown format '.stl'");
  expect_rejected("pcqm", file("cloud.xyz", "0 0 0\n"), "xyz");
}

TEST_F(Unusual, TruncatedBinaryPly) {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  bytes += std::string(3 * 15 - 7, '\1');
  expect_rejected("pcqm", file("truncated.ply", bytes), "too short");
}

TEST_F(Unusual, HeaderCountsThatDisagreeWithTheData) {
  expect_rejected("pcqm", file("more.ply", kPlyHeader + "end_header\n" + "0 0 0 1 2 3\n"), "too short");
  std::string fewer = kPlyHeader + "end_header\n" + kTriangle + "5 5 5 1 1 1\n";
  expect_rejected("pcqm", file("fewer.ply", fewer), "data continues after");
  expect_rejected("cmdm", file("more.off", "COFF\n4 1 0\n0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n3 0 1 2\n"),
                  "");
  expect_rejected("cmdm", file("fewer.off", "COFF\n3 1 0\n0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n3 0 1 2\n3 0 2 1\n"),
                  "more data than the header");
  // A header claiming 2^31 vertices fails at once instead of allocating.
  expect_rejected("pcqm", file("huge.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 2147483648\n"
                                           "property float x\nproperty float y\nproperty float z\nend_header\n"),
                  "2147483648");
  expect_rejected("cmdm", file("huge.off", "COFF\n2147483648 1 0\n0 0 0 1 1 1\n"), "too short");
}

TEST_F(Unusual, BadFaceIndices) {
  expect_rejected("cmdm", file("range.obj", obj(kObjVertices, "f 1 2 9\n")), "refers to vertex 8");
  expect_rejected("cmdm", file("negative.off", "COFF\n3 1 0\n0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n3 0 -1 2\n"),
                  "bad face index '-1'");
  expect_rejected("cmdm", file("range.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                            "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                                            "element face 1\nproperty list uchar int vertex_indices\nend_header\n" +
                                            kTriangle + "3 0 1 3\n"),
                  "refers to vertex 3");
}

TEST_F(Unusual, NonNumericAndNonFiniteValues) {
  expect_rejected("cmdm", file("text.obj", "v 0 zero 0 1 1 1\n"), "'zero' is not a number");
  expect_rejected("pcqm", file("text.ply", kPlyHeader + "end_header\n0 0 0 1 x 3\n1 0 0 1 1 1\n0 1 0 1 1 1\n"),
                  "'x' is not a number");
  expect_rejected("cmdm", file("nan.obj", obj("v nan 0 0 1 1 1\nv 1 0 0 1 1 1\nv 0 1 0 1 1 1\n")), "non-finite");
  expect_rejected("pcqm", file("inf.ply", kPlyHeader + "end_header\n0 0 inf 1 2 3\n1 0 0 1 1 1\n0 1 0 1 1 1\n"),
                  "non-finite");
}

TEST_F(Unusual, ColoursOutOfRangeMissingOrAbsent) {
  expect_rejected("cmdm", file("range.obj", obj("v 0 0 0 1 1 300\nv 1 0 0 1 1 1\nv 0 1 0 1 1 1\n")),
                  "outside [0, 1] and [0, 255]");
  expect_rejected("cmdm", file("negative.obj", obj("v 0 0 0 -1 1 1\nv 1 0 0 1 1 1\nv 0 1 0 1 1 1\n")),
                  "outside [0, 1] and [0, 255]");
  expect_rejected("cmdm", file("some.obj", obj("v 0 0 0 1 1 1\nv 1 0 0\nv 0 1 0 1 1 1\n")),
                  "colours missing for 1 of 3 vertices");
  expect_rejected("cmdm", file("none.obj", obj("v 0 0 0\nv 1 0 0\nv 0 1 0\n")), "no vertex colours");
  expect_rejected("pcqm", file("none.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                           "property float y\nproperty float z\nend_header\n0 0 0\n1 1 1\n"),
                  "no vertex colours");
}

TEST_F(Unusual, PathsThatAreNotReadableFiles) {
  expect_rejected("cmdm", dir_ / "cwd", "");  // a directory
  const CliRun missing = run("pcqm", dir_ / "nope.ply", dir_ / "nope.ply");
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("nope.ply: no such file"), std::string::npos) << missing.err;
  const fs::path under_file = file("plain.txt", "x") / "a.ply";
  EXPECT_EQ(run("pcqm", under_file, under_file).code, 2);
}

TEST_F(Unusual, PointCloudGivenToCmdm) {
  expect_rejected("cmdm", test::reference_dir() / "pcqm" / "sphere_50k_ref.ply", "no faces");
}

TEST_F(Unusual, DegenerateCloudsAreRejected) {
  expect_rejected("pcqm", file("single.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                             "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                                             "end_header\n1 2 3 10 20 30\n"),
                  "zero size");
  expect_rejected("pcqm", file("same.ply", kPlyHeader + "end_header\n1 2 3 1 2 3\n1 2 3 1 2 3\n1 2 3 1 2 3\n"), "zero size");
  expect_rejected("cmdm", file("same.obj", obj("v 1 1 1 1 0 0\nv 1 1 1 0 1 0\nv 1 1 1 0 0 1\n")), "");
}

// Documented handling: these inputs are scored (exit 0), with a warning where the input changed.
TEST_F(Unusual, DuplicatePointsAreKept) {
  const std::string cloud = kPlyHeader + "end_header\n" + kTriangle;
  std::string dup = cloud;
  dup.replace(dup.find("element vertex 3"), 16, "element vertex 4");
  dup += "0 0 0 255 0 0\n";
  const CliRun o = run("pcqm", file("dup.ply", dup), file("cloud.ply", cloud));
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("PCQM = "), std::string::npos);
}

TEST_F(Unusual, DegenerateNonManifoldAndIsolatedAreRepairedWithWarnings) {
  const std::string quad = "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 0\n";
  // a face repeating a vertex (dropped), a zero-area face (kept), an isolated vertex (dropped)
  const fs::path degenerate = file("degenerate.obj", quad + "v 2 2 2 1 1 1\nv 0.5 0 0 1 1 1\n"
                                                            "f 1 2 3\nf 1 3 4\nf 1 1 2\nf 1 6 2\n");
  const CliRun d = run("cmdm", degenerate, degenerate);
  EXPECT_EQ(d.code, 0) << d.err;
  EXPECT_NE(d.err.find("dropped 1 vertices that no face uses"), std::string::npos) << d.err;
  EXPECT_NE(d.err.find("dropped 1 faces that repeat a vertex"), std::string::npos) << d.err;
  // three triangles sharing one edge: non-manifold, repaired by duplicating vertices
  const fs::path fan = file("fan.obj", "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 0 -1 0 1 1 0\n"
                                       "v 0 0 1 0 1 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n");
  const CliRun n = run("cmdm", fan, fan);
  EXPECT_EQ(n.code, 0) << n.err;
  EXPECT_NE(n.err.find("non-manifold mesh repaired"), std::string::npos) << n.err;
  EXPECT_LT(std::stod(n.out.substr(n.out.find('=') + 1)), 1e-12) << n.out;
}

TEST_F(Unusual, LargeCoordinateOffsetsGiveTheSameCmdm) {
  std::ifstream in(test::reference_dir() / "cmdm" / "blob4_ref.off");
  std::ifstream in2(test::reference_dir() / "cmdm" / "blob4_colnoise.off");
  auto shifted = [](std::istream& s) {
    std::ostringstream o;
    o.precision(17);
    std::string line;
    std::getline(s, line);
    o << line << "\n";
    std::getline(s, line);
    o << line << "\n";
    int nv = std::stoi(line);
    for (int i = 0; i < nv && std::getline(s, line); ++i) {
      std::istringstream v(line);
      double x, y, z;
      std::string rest;
      v >> x >> y >> z;
      std::getline(v, rest);
      o << x + 1e7 << " " << y - 1e7 << " " << z + 1e7 << rest << "\n";
    }
    o << s.rdbuf();
    return o.str();
  };
  const fs::path a = file("a.off", shifted(in)), b = file("b.off", shifted(in2));
  const CliRun far = run("cmdm", a, b);
  const CliRun near = run("cmdm", test::reference_dir() / "cmdm" / "blob4_ref.off",
                           test::reference_dir() / "cmdm" / "blob4_colnoise.off");
  ASSERT_EQ(far.code, 0) << far.err;
  const double s_far = std::stod(far.out.substr(7)), s_near = std::stod(near.out.substr(7));
  EXPECT_NEAR(s_far, s_near, 1e-5 * s_near);
}

}  // namespace
}  // namespace qm3d
