#include "qm3d/mesh/mesh_io.h"

#include <gtest/gtest.h>

#include <fstream>

#include "qm3d/common/error.h"
#include "test_paths.h"

namespace qm3d::mesh {
namespace {

namespace fs = std::filesystem;

class MeshFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_meshio_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& content) {
    std::ofstream(dir_ / name, std::ios::binary) << content;
    return dir_ / name;
  }
  std::string error_of(const fs::path& p) {
    try {
      read_mesh(p);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

const char* kQuadObj =
    "# a quad\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 0.5 0.5 0.5\nf 1 2 3 4\n";

TEST_F(MeshFiles, ObjColoursInUnitRangeAreKeptAtFloatPrecision) {
  const MeshFile m = read_mesh(write("q.obj", kQuadObj));
  ASSERT_EQ(m.mesh.num_vertices(), 4u);
  EXPECT_EQ(m.mesh.colors[3].r, double(0.5f));
  EXPECT_EQ(m.mesh.triangles.size(), 2u);  // fan-triangulated
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_NE(m.warnings[0].find("1 polygons with more than 3 vertices were fan-triangulated"),
            std::string::npos);
}

TEST_F(MeshFiles, ObjColoursAbove1AreRead0To255) {
  const MeshFile m = read_mesh(write("c.obj", "v 0 0 0 255 0 128\nv 1 0 0 0 0 0\nv 0 1 0 1 1 1\nf 1 2 3\n"));
  EXPECT_EQ(m.mesh.colors[0].r, double(float(255 / 255.0)));
  EXPECT_EQ(m.mesh.colors[0].b, double(float(128 / 255.0)));
  EXPECT_EQ(m.mesh.colors[2].g, double(float(1 / 255.0)));  // per-file rule, as MEPP2
}

TEST_F(MeshFiles, ObjRelativeAndSlashedIndices) {
  const MeshFile m = read_mesh(write("r.obj", "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvt 0 0\nf -3/1 -2/1/1 -1//1\n"));
  EXPECT_EQ(m.mesh.triangles[0], (Triangle{0, 1, 2}));
}

TEST_F(MeshFiles, OffWithRgbaAndCommentsAndCountsOnHeaderLine) {
  const MeshFile m = read_mesh(write("a.off",
      "COFF # coloured\n# comment line\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 128\n"
      "0 1 0 0 0 255 0\n3 0 1 2\n"));
  EXPECT_EQ(m.mesh.colors[1].g, 1.0);
  EXPECT_EQ(m.mesh.colors[0].g, 0.0);
  const MeshFile n = read_mesh(write("b.off", "COFF 3 1 0\n0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n3 0 1 2\n"));
  EXPECT_EQ(n.mesh.colors[2].b, 1.0);
}

TEST_F(MeshFiles, SameDataInObjOffPlyGivesTheSameMesh) {
  const fs::path dir = test::reference_dir() / "cmdm";
  const MeshFile off = read_mesh(dir / "blob4_ref.off");
  const MeshFile obj = read_mesh(dir / "blob4_ref.obj");
  const MeshFile ply = read_mesh(dir / "blob4_ref.ply");
  EXPECT_EQ(off.mesh.positions, ply.mesh.positions);
  EXPECT_EQ(off.mesh.positions, obj.mesh.positions);
  EXPECT_EQ(off.mesh.triangles, ply.mesh.triangles);
  for (std::size_t i = 0; i < off.mesh.colors.size(); ++i) {
    EXPECT_EQ(off.mesh.colors[i].r, ply.mesh.colors[i].r);
    EXPECT_NEAR(off.mesh.colors[i].g, obj.mesh.colors[i].g, 1e-7);
  }
}

TEST_F(MeshFiles, UnreferencedVerticesAreDroppedWithAWarning) {
  const MeshFile m = read_mesh(write("u.obj", "v 0 0 0 1 0 0\nv 5 5 5 1 1 1\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 3 4\n"));
  EXPECT_EQ(m.mesh.num_vertices(), 3u);
  EXPECT_EQ(m.mesh.triangles[0], (Triangle{0, 1, 2}));
  EXPECT_EQ(m.file_vertex, (std::vector<std::uint32_t>{0, 2, 3}));
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_NE(m.warnings[0].find("dropped 1 vertices"), std::string::npos);
}

TEST_F(MeshFiles, ErrorsNameTheFileAndTheProblem) {
  const std::string nocolor = error_of(write("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_NE(nocolor.find("n.obj: no vertex colours"), std::string::npos) << nocolor;
  const std::string some = error_of(write("s.obj", "v 0 0 0 1 1 1\nv 1 0 0\nv 0 1 0 1 1 1\nf 1 2 3\n"));
  EXPECT_NE(some.find("colours missing for 1 of 3 vertices (first: vertex 1)"), std::string::npos) << some;
  const std::string range = error_of(write("r.obj", "v 0 0 0 1 1 300\nv 1 0 0 1 1 1\nv 0 1 0 1 1 1\nf 1 2 3\n"));
  EXPECT_NE(range.find("outside [0, 1] and [0, 255]"), std::string::npos) << range;
  const std::string index = error_of(write("i.off", "COFF\n3 1 0\n0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n3 0 1 9\n"));
  EXPECT_NE(index.find("face 0 refers to vertex 9, but there are 3 vertices"), std::string::npos) << index;
  const std::string huge = error_of(write("h.off", "COFF\n2147483648 1 0\n0 0 0 1 0 0\n"));
  EXPECT_NE(huge.find("too short"), std::string::npos) << huge;
  const std::string nan = error_of(write("x.obj", "v nan 0 0 1 1 1\nv 1 0 0 1 1 1\nv 0 1 0 1 1 1\nf 1 2 3\n"));
  EXPECT_NE(nan.find("vertex 0 has a non-finite coordinate"), std::string::npos) << nan;
  const std::string noface = error_of(write("p.obj", "v 0 0 0 1 1 1\n"));
  EXPECT_NE(noface.find("no faces"), std::string::npos) << noface;
  const std::string ext = error_of(write("m.stl", "solid"));
  EXPECT_NE(ext.find("unknown mesh format '.stl'"), std::string::npos) << ext;
  const std::string notoff = error_of(write("w.off", "PLY\n"));
  EXPECT_NE(notoff.find("not an OFF file"), std::string::npos) << notoff;
  EXPECT_THROW(read_mesh(dir_ / "missing.obj"), InputError);
  EXPECT_THROW(read_mesh(dir_), FormatError);  // a directory has no mesh extension
}

TEST_F(MeshFiles, VerticesOnlyReadingAcceptsAFacelessFile) {
  const ColoredCloud c = read_mesh_vertices(write("p.obj", "v 0 0 0 1 1 1\nv 1 1 1 0 0 0\n"));
  EXPECT_EQ(c.size(), 2u);
}

}  // namespace
}  // namespace qm3d::mesh
