// CMDM and MSDM2 on meshes built to break them (issue 24): faces repeated tens of thousands of
// times, polygons of tens of thousands of corners, meshes so small that MEPP2's absolute epsilon
// bites. Each mesh is made here; none is written to disk.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "qm3d/mesh/cmdm.h"
#include "qm3d/mesh/mesh_io.h"
#include "qm3d/mesh/msdm2.h"
#include "test_paths.h"

namespace qm3d::mesh {
namespace {

// More copies than an 8 MB stack holds levels of CGAL's k-d tree build (256 bytes a level): the
// build recursed once per copy and crashed.
constexpr std::uint32_t kCopies = 40000;

// One coloured triangle `copies` times: on the same three vertices, or each copy on its own.
ColoredMesh repeated_triangle(std::uint32_t copies, bool shared_vertices) {
  ColoredMesh m;
  const std::uint32_t vertex_sets = shared_vertices ? 1 : copies;
  for (std::uint32_t k = 0; k < vertex_sets; ++k) {
    m.positions.insert(m.positions.end(), {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    m.colors.insert(m.colors.end(), {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}});
  }
  for (std::uint32_t k = 0; k < copies; ++k) {
    const std::uint32_t base = shared_vertices ? 0 : 3 * k;
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

TEST(DegenerateMesh, AFaceRepeatedTensOfThousandsOfTimesScoresZeroAgainstItself) {
  for (const bool shared : {true, false}) {
    SCOPED_TRACE(shared ? "one vertex set" : "a vertex set per copy");
    const ColoredMesh m = repeated_triangle(kCopies, shared);
    EXPECT_EQ(compute_cmdm(m, m).score, 0.0);
    EXPECT_EQ(compute_msdm2(m, m).score, 0.0);
  }
}

}  // namespace
}  // namespace qm3d::mesh
