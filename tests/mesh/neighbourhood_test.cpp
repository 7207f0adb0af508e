// One walk for every scale (neighbourhood.h, sample_neighbourhoods) gives, at each radius, exactly
// the samples of MEPP2's walk at that radius alone (sample_neighbourhood): the same multiset of
// sample values, bit for bit, for every vertex, with and without colour, both walk tests.
#include "neighbourhood.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <string>

#include "multiscale.h"
#include "qm3d/mesh/mesh_io.h"
#include "test_paths.h"

namespace qm3d::mesh::detail {
namespace {

using SampleRow = std::array<double, 9>;

std::vector<SampleRow> sorted_rows(const NeighbourhoodSamples& s) {
  std::vector<SampleRow> rows(s.size());
  const bool color = !s.light1.empty();
  for (std::size_t i = 0; i < s.size(); ++i) {
    rows[i] = {s.w1[i], s.w2[i], s.curv1[i], s.curv2[i], color ? s.light1[i] : 0,
               color ? s.light2[i] : 0, color ? s.chroma1[i] : 0, color ? s.chroma2[i] : 0,
               color ? s.hue_diff[i] : 0};
  }
  std::sort(rows.begin(), rows.end());
  return rows;
}

// The walks of a mesh with arbitrary matched points, curvatures and colours: the walk itself
// reads only the iterated mesh's geometry; the rest only has to be carried into the samples.
struct Fixture {
  ColoredMesh input;
  HalfedgeMesh mesh;
  std::vector<Vec3> matched;
  std::vector<std::vector<double>> curv, curv_match;
  std::vector<Lab> lab, lab_match;

  Fixture(const std::filesystem::path& file, int levels, DegenerateEdges degenerate) {
    input = read_mesh(file).mesh;
    mesh = build_halfedge_mesh(input, file.string(), degenerate, 1);  // views `input`
    std::mt19937 random(7);
    std::uniform_real_distribution<double> u(-1, 1);
    for (const Vec3& p : mesh.positions) matched.push_back({p[0] + 1e-3 * u(random), p[1], p[2] + 1e-3 * u(random)});
    for (int l = 0; l < levels; ++l) {
      curv.emplace_back();
      curv_match.emplace_back();
      for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        curv.back().push_back(u(random));
        curv_match.back().push_back(u(random));
      }
    }
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      lab.push_back({50 + 50 * u(random), 60 * u(random), 60 * u(random)});
      lab_match.push_back({50 + 50 * u(random), 60 * u(random), 60 * u(random)});
    }
  }

  std::vector<MatchedFields> fields(std::size_t levels, bool color) const {
    std::vector<MatchedFields> out;
    for (std::size_t l = 0; l < levels; ++l) {
      out.push_back({&mesh, &matched, &curv[l], &curv_match[l], color ? &lab : nullptr,
                     color ? &lab_match : nullptr});
    }
    return out;
  }
};

void expect_same_samples(const Fixture& f, const std::vector<WalkParameters>& walks, bool color) {
  const std::vector<MatchedFields> levels = f.fields(walks.size(), color);
  WalkScratch single;
  MultiWalkScratch multi;
  NeighbourhoodSamples alone;
  std::vector<NeighbourhoodSamples> together;
  std::size_t samples = 0, differing = 0;
  std::string first;
  for (std::uint32_t v = 0; v < f.mesh.positions.size(); ++v) {
    sample_neighbourhoods(levels, v, walks, multi, together);
    ASSERT_EQ(together.size(), walks.size());
    for (std::size_t l = 0; l < walks.size(); ++l) {
      sample_neighbourhood(levels[l], v, walks[l], single, alone);
      samples += alone.size();
      if (sorted_rows(alone) != sorted_rows(together[l]) && differing++ == 0) {
        first = "vertex " + std::to_string(v) + " at radius " + std::to_string(walks[l].radius);
      }
    }
  }
  EXPECT_EQ(differing, 0u) << "neighbourhoods whose samples differ, the first: " << first;
  EXPECT_GT(samples, 10 * walks.size() * f.mesh.positions.size());  // the balls span rings
}

std::vector<WalkParameters> radii(std::vector<double> h, double divisor, bool strict) {
  std::vector<WalkParameters> walks;
  for (double r : h) walks.push_back({r, r / divisor, strict});
  return walks;
}

TEST(Neighbourhoods, OneWalkGivesEachRadiusItsOwnSamples) {
  const Fixture f(test::reference_dir() / "cmdm" / "blob4_bothnoise.off", 4, DegenerateEdges::kRepaired);
  // Edges are about 0.07 long (a sphere of radius 1, 5120 faces): balls of a few rings, growing
  // like CMDM's three scales (h proportional to 1, 1.5, 2), then with a repeated radius.
  expect_same_samples(f, radii({0.1, 0.15, 0.2}, 3, false), true);
  expect_same_samples(f, radii({0.12, 0.12, 0.25, 0.4}, 3, false), true);
  // MSDM2's strict walk test, no colour.
  expect_same_samples(f, radii({0.1, 0.15, 0.2}, 2, true), false);
}

TEST(Neighbourhoods, OneWalkOnAQuantisedMeshWithDuplicatePositions) {
  // Quantised to 6 bits: many zero-length edges and exact ties on the sphere.
  const Fixture f(test::reference_dir() / "quantised" / "blob5_pquant6.off", 3, DegenerateEdges::kRepaired);
  expect_same_samples(f, radii({0.07, 0.105, 0.14}, 3, false), true);
  expect_same_samples(f, radii({0.07, 0.105, 0.14}, 2, true), false);
}

}  // namespace
}  // namespace qm3d::mesh::detail
