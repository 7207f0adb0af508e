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

// Triangle lines take a shortcut past the tokenizer (mesh_io.cpp read_off_triangle): the same
// faces as the general path for every spelling it accepts, and the general path's errors for
// the others.
TEST_F(MeshFiles, OffTriangleLinesReadAlikeWhateverTheirSpelling) {
  const std::string head = "COFF\n4 6 0\n0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n0 0 1 1 1 1\n";
  const MeshFile m = read_mesh(
      write("t.off", head + "3 0 1 2\n \t3\t0002 1 3  \n+3 0 2 3\n03 1 2 3\n3 0 3 1 255 0 0\n"
                            "4 0 1 2 3\n"));
  const std::vector<Triangle> expected = {{0, 1, 2}, {2, 1, 3}, {0, 2, 3}, {1, 2, 3},
                                          {0, 3, 1}, {0, 1, 2}, {0, 2, 3}};
  EXPECT_EQ(m.mesh.triangles, expected);
  const std::string big = error_of(write("b.off", head + "3 0 1 4294967296\n"));
  EXPECT_NE(big.find("line 7: bad face index '4294967296'"), std::string::npos) << big;
  const std::string sign = error_of(write("s.off", head + "3 0 1 -2\n"));
  EXPECT_NE(sign.find("line 7: bad face index '-2'"), std::string::npos) << sign;
  const std::string junk = error_of(write("j.off", head + "3 0 1 2x\n"));
  EXPECT_NE(junk.find("line 7: bad face index '2x'"), std::string::npos) << junk;
  const std::string few = error_of(write("f.off", head + "3 0 1\n"));
  EXPECT_NE(few.find("line 7: face has fewer indices than its count"), std::string::npos) << few;
  const std::string range = error_of(
      write("r.off", "COFF\n3 1 0\n0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n3 0 1 00000000004\n"));
  EXPECT_NE(range.find("refers to vertex 4"), std::string::npos) << range;
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

// ---- issue 24 ----------------------------------------------------------------------------------

// `v x y z w r g b` was read as the colour (w, r, g). 3, 4 and 6 values are read; 5, 7 and 8+ are
// errors naming the file and line (7 could be x y z w r g b or x y z r g b a).
TEST_F(MeshFiles, ObjVertexValueCountsOtherThan3_4_6AreErrors) {
  const std::string face = "v 1 0 0 1 0 0\nv 0 1 0 1 0 0\nf 1 2 3\n";
  EXPECT_EQ(error_of(write("six.obj", "v 0 0 0 0.5 0.5 0.5\n" + face)), "");
  const MeshFile four = read_mesh(write("four.obj", "v 0 0 0 2\nv 1 0 0 2\nv 0 1 0 2\nf 1 2 3\n"),
                                  MeshReadOptions{false});
  EXPECT_EQ(four.mesh.positions[1], (Vec3{1, 0, 0}));  // w ignored
  EXPECT_TRUE(four.mesh.colors.empty());
  const std::pair<const char*, const char*> bad[] = {
      {"v 0 0 0 1 0.5\n", "line 1: a vertex with 5 values"},
      {"v 0 0 0 1 0.5 0.5 0.5\n",
       "line 1: a vertex with 7 values (qm3d reads 'v x y z', "
       "'v x y z w' and 'v x y z r g b'; 7 values could be x y z w r "
       "g b or x y z r g b a)"},
      {"v 0 0 0 1 0.5 0.5 0.5 1\n", "line 1: a vertex with 8 or more values"},
      {"v 0 0 0 1 0.5 0.5 0.5 1 2 3\n", "line 1: a vertex with 8 or more values"}};
  for (const auto& [line, message] : bad) {
    const std::string e = error_of(write("bad.obj", line + face));
    EXPECT_NE(e.find((dir_ / "bad.obj").string() + ": " + message), std::string::npos) << e;
  }
}

std::string colour_obj(const std::string& odd) {
  std::string text;
  for (int i = 0; i < 100; ++i) {
    text += "v " + std::to_string(i) + " " + std::to_string(i % 3) + " 0 0.5 " +
            (i == 5 ? odd : std::string("0.25")) + " 1\n";
  }
  for (int i = 1; i + 2 <= 100; ++i) {
    text +=
        "f " + std::to_string(i) + " " + std::to_string(i + 1) + " " + std::to_string(i + 2) + "\n";
  }
  return text;
}

// One value of 1.0000001 switched the whole file to 0..255 (every colour near black) silently.
TEST_F(MeshFiles, ObjAndOffColourScaleIsReportedAndCanBeChosen) {
  const fs::path obj = write("c.obj", colour_obj("1.0000001"));
  const MeshFile automatic = read_mesh(obj);
  EXPECT_EQ(automatic.mesh.colors[0].r, double(float(1 / 255.0)));  // MEPP2's rule by default
  ASSERT_EQ(automatic.warnings.size(), 1u);
  EXPECT_EQ(automatic.warnings[0], obj.string() +
                                       ": 1 of 300 colour values above 1 (max "
                                       "1.0000001): read as 0..255 like the reference; "
                                       "--colour-scale unit reads them as 0..1");
  MeshReadOptions unit;
  unit.colour_scale = ColourScale::kUnit;
  const MeshFile chosen = read_mesh(obj, unit);
  EXPECT_EQ(chosen.mesh.colors[0].r, 0.5);
  EXPECT_EQ(chosen.mesh.colors[5].g, 1.0);
  // The same choice for a mesh read as a cloud (its vertices).
  ReadOptions cloud_unit;
  cloud_unit.colour_scale = ColourScale::kUnit;
  const CloudData vertices = read_mesh_vertices_data(obj, MeshFormat::kObj, cloud_unit);
  EXPECT_EQ(vertices.cloud.colors[0].r, 0.5);
  ASSERT_EQ(vertices.warnings.size(), 1u);
  EXPECT_NE(vertices.warnings[0].find("clamped to 1 (--colour-scale unit)"), std::string::npos);
  // A clear 0..1 file, and a COFF in 0..255, need no word.
  EXPECT_TRUE(read_mesh(write("u.obj", colour_obj("0.75"))).warnings.empty());
  const MeshFile off = read_mesh(write("c.off",
                                       "COFF\n3 1 0\n0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n"
                                       "3 0 1 2\n"));
  EXPECT_TRUE(off.warnings.empty());
  EXPECT_EQ(off.mesh.colors[1].g, 1.0);
}

}  // namespace
}  // namespace qm3d::mesh
