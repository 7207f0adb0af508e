// Issue 37 (metric side): psnr, grid sampling and ibsm on hostile scales, offsets and normals.
// Each case is one that crashed, ran out of memory or gave a wrong / non-finite value with exit
// 0 and no warning; the stimuli are the bundled blob3 meshes and sphere clouds, rescaled here.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "test_paths.h"

namespace fs = std::filesystem;
using qm3d::test::CliRun;
using qm3d::test::run_qm3d;

namespace {

// AddressSanitizer reserves terabytes of address space for its shadow memory at start-up, so
// an address-space limit (ulimit -v) kills every sanitized run before main(): the memory bounds
// below are checked by the normal build, the sanitized one runs the same commands unbounded.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSpaceLimitsWork = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSpaceLimitsWork = false;
#else
constexpr bool kAddressSpaceLimitsWork = true;
#endif
#else
constexpr bool kAddressSpaceLimitsWork = true;
#endif

/// "ulimit -v KB &&" where such a limit can apply (see kAddressSpaceLimitsWork), else "".
std::string address_space_limit(const char* kb) {
  return kAddressSpaceLimitsWork ? std::string("ulimit -v ") + kb + " &&" : std::string();
}

std::string text(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

class HostileMetrics : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("qm3d_hostile_metrics_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  CliRun qm3d(const std::string& args, const std::string& env = "") {
    return run_qm3d(args, dir_, dir_, env);
  }

  static fs::path data(const std::string& name) { return qm3d::test::source_dir() / "data" / name; }

  // A bundled COFF mesh with every coordinate c written as c * scale + offset.
  std::string mesh(const std::string& name, double scale, double offset = 0) {
    std::ifstream in(data("meshes/" + name + ".off"));
    std::string header;
    std::size_t vertices = 0, faces = 0, edges = 0;
    in >> header >> vertices >> faces >> edges;
    const std::string out_name = name + "_" + text(scale) + "_" + text(offset) + ".off";
    std::ofstream out(dir_ / out_name);
    out << header << '\n' << vertices << ' ' << faces << ' ' << edges << '\n';
    for (std::size_t i = 0; i < vertices; ++i) {
      double x, y, z;
      int r, g, b;
      in >> x >> y >> z >> r >> g >> b;
      out << text(x * scale + offset) << ' ' << text(y * scale + offset) << ' '
          << text(z * scale + offset) << ' ' << r << ' ' << g << ' ' << b << '\n';
    }
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) out << line << '\n';
    return out_name;
  }

  // A bundled ASCII sphere cloud as double coordinates c * scale + offset, with normals
  // (the unit position times `normal_scale`) when normal_scale >= 0.
  std::string cloud(const std::string& name, double scale, double offset = 0,
                    double normal_scale = -1) {
    std::ifstream in(data("clouds/" + name + ".ply"));
    std::string line;
    std::size_t vertices = 0;
    while (std::getline(in, line) && line != "end_header") {
      if (line.rfind("element vertex ", 0) == 0) vertices = std::stoul(line.substr(15));
    }
    const std::string out_name =
        name + "_" + text(scale) + "_" + text(offset) + "_" + text(normal_scale) + ".ply";
    std::ofstream out(dir_ / out_name);
    out << "ply\nformat ascii 1.0\nelement vertex " << vertices
        << "\nproperty double x\nproperty double y\nproperty double z\n";
    if (normal_scale >= 0) out << "property float nx\nproperty float ny\nproperty float nz\n";
    out << "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
    for (std::size_t i = 0; i < vertices; ++i) {
      double p[3];
      int c[3];
      in >> p[0] >> p[1] >> p[2] >> c[0] >> c[1] >> c[2];
      for (double v : p) out << text(v * scale + offset) << ' ';
      if (normal_scale >= 0) {
        const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (double v : p) out << text(v / len * normal_scale) << ' ';
      }
      out << c[0] << ' ' << c[1] << ' ' << c[2] << '\n';
    }
    return out_name;
  }

  fs::path dir_;
};

bool has(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

// Item 1: coordinates whose float32 arithmetic overflows (mmetric's sampler) were a SIGSEGV.
TEST_F(HostileMetrics, MeshPsnrOnHugeCoordinatesIsACleanError) {
  for (double scale : {1e14, 1e20}) {
    const CliRun r = qm3d("psnr " + mesh("blob3_ref", scale) + " " + mesh("blob3_geonoise", scale));
    EXPECT_EQ(r.code, 2) << scale << ": " << r.err;
    EXPECT_TRUE(has(r.err, "overflows float32")) << r.err;
    EXPECT_TRUE(has(r.err, "scale the mesh down")) << r.err;
  }
  const CliRun s = qm3d("sample --mode grid -o s.ply " + mesh("blob3_ref", 1e20));
  EXPECT_EQ(s.code, 2) << s.err;
}

// Item 1: grid sampling out of memory was an uncaught bad_alloc (SIGABRT); now refused up
// front with the estimate (rc 3, "out of memory"), under a 4 GB address-space limit.
TEST_F(HostileMetrics, GridSamplingTooFineIsRefusedWithItsEstimate) {
  if (!kAddressSpaceLimitsWork) GTEST_SKIP() << "no address-space limit under AddressSanitizer";
  const std::string pair =
      data("meshes/blob3_ref.off").string() + " " + data("meshes/blob3_geonoise.off").string();
  for (const char* size : {"100000", "10000"}) {
    const CliRun r =
        qm3d(std::string("psnr ") + pair + " --grid-size " + size, address_space_limit("4000000"));
    EXPECT_EQ(r.code, 3) << size << ": " << r.err;
    EXPECT_TRUE(has(r.err, "out of memory: grid sampling: grid size")) << r.err;
    EXPECT_TRUE(has(r.err, "samples")) << r.err;
    EXPECT_TRUE(has(r.err, "fits")) << r.err;
  }
}

// Item 2: at 1e12 the faces' squared normals overflow float32 (mmetric's normal is zero): the
// values are mmetric's, with a warning naming the cause and the remedy.
TEST_F(HostileMetrics, MeshPsnrAtScale1e12WarnsOfZeroNormals) {
  const CliRun r = qm3d("psnr " + mesh("blob3_ref", 1e12) + " " + mesh("blob3_geonoise", 1e12) +
                        " --grid-size 200");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(has(r.err, "squared normal overflows float32")) << r.err;
  EXPECT_TRUE(has(r.err, "scale the meshes down")) << r.err;
  const CliRun unit = qm3d("psnr " + data("meshes/blob3_ref.off").string() + " " +
                           data("meshes/blob3_geonoise.off").string() + " --grid-size 200");
  EXPECT_FALSE(has(unit.err, "overflows")) << unit.err;
}

// Item 2: mmetric's ray-triangle epsilon (1e-6, absolute) drops small faces: a warning at 0.007,
// an error naming it at 0.006 (every face below it).
TEST_F(HostileMetrics, SmallMeshesNameMmetricsAbsoluteEpsilon) {
  const CliRun small = qm3d("psnr " + mesh("blob3_ref", 0.007) + " " +
                            mesh("blob3_geonoise", 0.007) + " --grid-size 200");
  EXPECT_EQ(small.code, 0) << small.err;
  EXPECT_TRUE(has(small.err, "ray-triangle epsilon")) << small.err;
  EXPECT_TRUE(has(small.err, "scale the meshes up")) << small.err;
  const CliRun tiny =
      qm3d("psnr " + mesh("blob3_ref", 0.006) + " " + mesh("blob3_geonoise", 0.006));
  EXPECT_EQ(tiny.code, 2) << tiny.err;
  EXPECT_TRUE(has(tiny.err, "ray-triangle epsilon")) << tiny.err;
}

// Item 2: far from the origin, float32 loses precision in pc_error, mmetric and the renderer.
TEST_F(HostileMetrics, FarFromTheOriginWarns) {
  const std::string ref = mesh("blob3_ref", 1, 1e6), geo = mesh("blob3_geonoise", 1, 1e6);
  const CliRun m = qm3d("psnr " + ref + " " + geo + " --grid-size 200");
  EXPECT_EQ(m.code, 0) << m.err;
  EXPECT_TRUE(has(m.err, "far from the origin")) << m.err;
  const CliRun c = qm3d("psnr " + cloud("sphere_2k_ref", 1, 1e6) + " " +
                        cloud("sphere_2k_gnoise0.005", 1, 1e6) + " --no-color");
  EXPECT_EQ(c.code, 0) << c.err;
  EXPECT_TRUE(has(c.err, "far from the origin")) << c.err;
  const CliRun i = qm3d("ibsm " + ref + " " + geo + " --resolution 64");
  EXPECT_EQ(i.code, 0) << i.err;
  EXPECT_TRUE(has(i.err, "far from the origin")) << i.err;
  const CliRun near = qm3d("psnr " + cloud("sphere_2k_ref", 1) + " " +
                           cloud("sphere_2k_gnoise0.005", 1) + " --no-color");
  EXPECT_FALSE(has(near.err, "far from the origin")) << near.err;
}

// Item 2: pc_error's absolute tie threshold (1e-8) at scale 1e-3, and its absolute 1e-5 peak
// rule at 1e-5 ("no two distinct points" for 2000 distinct points).
TEST_F(HostileMetrics, SmallCloudsNamePcErrorsAbsoluteThresholds) {
  const CliRun milli =
      qm3d("psnr " + cloud("sphere_2k_ref", 1e-3) + " " + cloud("sphere_2k_cnoise10", 1e-3));
  EXPECT_EQ(milli.code, 0) << milli.err;
  EXPECT_TRUE(has(milli.err, "absolute tie threshold")) << milli.err;
  const CliRun unit =
      qm3d("psnr " + cloud("sphere_2k_ref", 1) + " " + cloud("sphere_2k_cnoise10", 1));
  EXPECT_FALSE(has(unit.err, "tie threshold")) << unit.err;
  const CliRun tiny =
      qm3d("psnr " + cloud("sphere_2k_ref", 1e-5) + " " + cloud("sphere_2k_cnoise10", 1e-5));
  EXPECT_EQ(tiny.code, 2) << tiny.err;
  EXPECT_TRUE(has(tiny.err, "absolute 1e-5")) << tiny.err;
  EXPECT_FALSE(has(tiny.err, "so no nearest-neighbour distance gives")) << tiny.err;
}

// Item 2: zero or huge normals gave D2 = +-inf with warnings: [].
TEST_F(HostileMetrics, NonUnitNormalsWarn) {
  const std::string dist = cloud("sphere_2k_gnoise0.005", 1);
  const CliRun zero = qm3d("psnr " + cloud("sphere_2k_ref", 1, 0, 0) + " " + dist + " --no-color");
  EXPECT_EQ(zero.code, 0) << zero.err;
  EXPECT_TRUE(has(zero.err, "not unit length")) << zero.err;
  const CliRun huge =
      qm3d("psnr " + cloud("sphere_2k_ref", 1, 0, 1e30) + " " + dist + " --no-color");
  EXPECT_EQ(huge.code, 0) << huge.err;
  EXPECT_TRUE(has(huge.err, "not unit length")) << huge.err;
  EXPECT_TRUE(has(huge.err, "d2_mse is inf")) << huge.err;
  const CliRun unit = qm3d("psnr " + cloud("sphere_2k_ref", 1, 0, 1) + " " + dist + " --no-color");
  EXPECT_FALSE(has(unit.err, "not unit length")) << unit.err;
}

// Item 4: one face repeated 50,000 times took 4.4 GB; each distinct face is now sampled once
// (mmetric drops every sample of a repeat as a duplicate): the same cloud, within 1.5 GB.
TEST_F(HostileMetrics, RepeatedFacesAreSampledOnce) {
  const auto write = [&](const std::string& name, int repeats) {
    std::ofstream out(dir_ / name);
    out << "OFF\n4 " << repeats + 1 << " 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 3\n";
    for (int i = 0; i < repeats; ++i) out << "3 0 1 2\n";
  };
  write("once.off", 1);
  write("many.off", 50000);
  const CliRun once = qm3d("sample --mode grid --grid-size 256 -o once.ply once.off");
  ASSERT_EQ(once.code, 0) << once.err;
  const CliRun many =
      qm3d("sample --mode grid --grid-size 256 -o many.ply many.off", address_space_limit("1500000"));
  ASSERT_EQ(many.code, 0) << many.err;
  EXPECT_EQ(qm3d::test::slurp(dir_ / "once.ply"), qm3d::test::slurp(dir_ / "many.ply"));
}

// Item 4: an OBJ whose 100 materials name one 3 MB texture decoded it 100 times (2.5 GB); the
// file is now decoded once, within 1.5 GB.
TEST_F(HostileMetrics, ATextureNamedByManyMaterialsIsDecodedOnce) {
  {
    std::ofstream ppm(dir_ / "tex.ppm", std::ios::binary);
    ppm << "P6\n1024 1024\n255\n";
    const std::string row(1024 * 3, static_cast<char>(200));
    for (int y = 0; y < 1024; ++y) ppm << row;
  }
  std::ofstream mtl(dir_ / "many.mtl");
  std::ofstream obj(dir_ / "many.obj");
  obj << "mtllib many.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n";
  for (int i = 0; i < 100; ++i) {
    mtl << "newmtl m" << i << "\nKd 1 1 1\nmap_Kd tex.ppm\n";
    obj << "usemtl m" << i << "\nf 1/1 2/2 3/3\n";
  }
  mtl.close();
  obj.close();
  const CliRun r =
      qm3d("sample --mode grid --grid-size 64 -o s.ply many.obj", address_space_limit("1500000"));
  EXPECT_EQ(r.code, 0) << r.err;
}

// Item 5: psnr on two meshes scores grid samples: --map was refused only after scoring (a PLY
// writer error) and --report failed with "internal error"; --map is now refused up front
// naming it, and the report is written (without a map layer) with the score.
TEST_F(HostileMetrics, MeshPsnrMapIsRefusedUpFrontAndReportIsWritten) {
  const std::string pair = data("meshes/blob3_ref.off").string() + " " +
                           data("meshes/blob3_geonoise.off").string() + " --grid-size 100";
  const CliRun map = qm3d("psnr " + pair + " --map m.ply");
  EXPECT_EQ(map.code, 1) << map.err;
  EXPECT_TRUE(has(map.err, "map: psnr scores two meshes on their grid samples")) << map.err;
  EXPECT_FALSE(fs::exists(dir_ / "m.ply"));
  const CliRun report = qm3d("psnr " + pair + " --report r.html");
  EXPECT_EQ(report.code, 0) << report.err;
  EXPECT_TRUE(has(report.out, "PSNR = ")) << report.out;
  EXPECT_TRUE(fs::exists(dir_ / "r.html"));
}

}  // namespace
