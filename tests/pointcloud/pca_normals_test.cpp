// PCA normals (src/pca_normals.h) against the normals ../shared/tools/add_pca_normals.py wrote
// into reference/mpeg/vox1_ref_n.ply, plus hand-made clouds for the tie, flip and LAPACK rules.
#include "pca_normals.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "qm3d/common/error.h"
#include "qm3d/pointcloud/cloud_io.h"
#include "test_paths.h"

namespace qm3d::pointcloud::detail {
namespace {

using Normals = std::vector<std::array<float, 3>>;

// The float nx ny nz of a binary little-endian PLY whose vertex properties are float or uchar
// scalars (what add_pca_normals.py writes). Local to this test until the cloud reader keeps
// normals.
Normals read_ply_normals(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string end_marker = "end_header\n";
  const std::size_t body = data.find(end_marker) + end_marker.size();
  std::istringstream header(data.substr(0, body));
  std::size_t count = 0, stride = 0, nx_offset = 0;
  for (std::string line; std::getline(header, line);) {
    std::istringstream words(line);
    std::string keyword, type, name;
    words >> keyword;
    if (keyword == "element") words >> name >> count;
    if (keyword != "property") continue;
    words >> type >> name;
    if (name == "nx") nx_offset = stride;
    stride += type == "float" ? 4 : 1;
  }
  Normals normals(count);
  for (std::size_t i = 0; i < count; ++i)
    std::memcpy(normals[i].data(), data.data() + body + i * stride + nx_offset, 12);
  return normals;
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

std::size_t identical_normals(const Normals& a, const Normals& b) {
  std::size_t same = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    same +=
        same_bits(a[i][0], b[i][0]) && same_bits(a[i][1], b[i][1]) && same_bits(a[i][2], b[i][2]);
  return same;
}

std::vector<Vec3> vox1_positions() {
  return read_cloud(test::reference_dir() / "voxel" / "vox1_ref.ply").positions;
}

TEST(PcaNormals, Vox1EqualsTheToolsFileBitForBit) {
  const Normals expected = read_ply_normals(test::reference_dir() / "mpeg" / "vox1_ref_n.ply");
  const Normals normals = estimate_pca_normals(vox1_positions(), 1);
  ASSERT_EQ(normals.size(), expected.size());
  const std::size_t same = identical_normals(normals, expected);
  std::cout << same << " of " << normals.size() << " normals bit-identical\n";
  EXPECT_EQ(same, normals.size());
  for (std::size_t i = 0, shown = 0; i < normals.size() && shown < 5; ++i) {
    if (same_bits(normals[i][0], expected[i][0]) && same_bits(normals[i][1], expected[i][1]) &&
        same_bits(normals[i][2], expected[i][2]))
      continue;
    ++shown;
    ADD_FAILURE() << "point " << i << ": " << normals[i][0] << " " << normals[i][1] << " "
                  << normals[i][2] << " expected " << expected[i][0] << " " << expected[i][1] << " "
                  << expected[i][2];
  }
}

TEST(PcaNormals, SameBitsForOneAndTwoThreads) {
  const std::vector<Vec3> positions = vox1_positions();
  const Normals one = estimate_pca_normals(positions, 1);
  const Normals two = estimate_pca_normals(positions, 2);
  EXPECT_EQ(identical_normals(one, two), one.size());
}

// A 5 x 5 integer grid in the plane z = 0 (row-major indices) and, far above, one more point
// that lifts the centroid to z > 0.
std::vector<Vec3> plane_with_far_point() {
  std::vector<Vec3> p;
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 5; ++x) p.push_back({double(x), double(y), 0});
  p.push_back({2, 2, 1000});
  return p;
}

TEST(PcaNormals, PlaneNormalsAreFlippedTowardsOutsideTheCentroid) {
  const Normals normals = estimate_pca_normals(plane_with_far_point(), 1);
  for (std::size_t i = 0; i < 25; ++i) {
    // LAPACK returns (0, 0, 1) for the zero eigenvalue; n · (p - c) < 0 (c above the plane)
    // negates it, zeros included.
    EXPECT_TRUE(same_bits(normals[i][0], -0.0f)) << i;
    EXPECT_TRUE(same_bits(normals[i][1], -0.0f)) << i;
    EXPECT_EQ(normals[i][2], -1.0f) << i;
  }
}

TEST(PcaNormals, ZeroDotProductKeepsLapacksSign) {
  std::vector<Vec3> plane = plane_with_far_point();
  plane.pop_back();  // centroid (2, 2, 0) in the plane: n · (p - c) = 0 everywhere
  const Normals normals = estimate_pca_normals(plane, 1);
  for (std::size_t i = 0; i < normals.size(); ++i) {
    EXPECT_TRUE(same_bits(normals[i][0], 0.0f)) << i;
    EXPECT_TRUE(same_bits(normals[i][1], 0.0f)) << i;
    EXPECT_EQ(normals[i][2], 1.0f) << i;
  }
}

// Point 0 at the origin, 10 points strictly closer than 2 in varied directions, and `tied`
// points all exactly at distance 2 (squared 4): with 0 itself they make 11 + tied candidates for
// 12 places, so the 12th is the tied point of lowest index.
std::vector<Vec3> tie_cloud(const std::vector<Vec3>& tied) {
  std::vector<Vec3> p = {{0, 0, 0},     {1, 0, 0},    {0, 1, 0},     {-1, 0, 0},
                         {0, -1, 0.5},  {1, 1, 0.25}, {-1, 1, 0},    {1, -1, -0.25},
                         {-1, -1, 0.5}, {0, 0, 1},    {0.5, 0.5, -1}};
  p.insert(p.end(), tied.begin(), tied.end());
  return p;
}

bool same_up_to_sign(const std::array<float, 3>& a, const std::array<float, 3>& b) {
  return (a[0] == b[0] && a[1] == b[1] && a[2] == b[2]) ||
         (a[0] == -b[0] && a[1] == -b[1] && a[2] == -b[2]);
}

TEST(PcaNormals, TwelfthPlaceTieGoesToTheLowerIndex) {
  const Vec3 t1{2, 0, 0}, t2{0, 0, -2}, t3{0, 2, 0};
  // The origin's normal with the ties equals the one with only the lowest-index tied point.
  const auto origin_normal = [](const std::vector<Vec3>& tied) {
    return estimate_pca_normals(tie_cloud(tied), 1)[0];
  };
  const auto with_ties = origin_normal({t2, t1, t3});
  EXPECT_TRUE(same_up_to_sign(with_ties, origin_normal({t2})));
  EXPECT_FALSE(same_up_to_sign(with_ties, origin_normal({t1})));
  EXPECT_FALSE(same_up_to_sign(with_ties, origin_normal({t3})));
  EXPECT_TRUE(same_up_to_sign(origin_normal({t3, t2, t1}), origin_normal({t3})));
}

TEST(PcaNormals, FewerThanTwelvePointsIsAnError) {
  EXPECT_THROW(estimate_pca_normals(std::vector<Vec3>(11, Vec3{0, 0, 0}), 1), NumericError);
}

TEST(SymmetricEigen3, DiagonalMatrixIsSortedAscending) {
  const SymmetricEigen3 eigen = symmetric_eigenvectors_3x3({{{3, 0, 0}, {0, 1, 0}, {0, 0, 2}}});
  EXPECT_EQ(eigen.values, (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(eigen.vectors[0], (Vec3{0, 1, 0}));
  EXPECT_EQ(eigen.vectors[1], (Vec3{0, 0, 1}));
  EXPECT_EQ(eigen.vectors[2], (Vec3{1, 0, 0}));
}

TEST(SymmetricEigen3, GenericMatrixIsAnOrthonormalEigenbasis) {
  const std::array<Vec3, 3> a{{{4, 1, 0.5}, {1, 3, -0.25}, {0.5, -0.25, 1}}};
  const SymmetricEigen3 eigen = symmetric_eigenvectors_3x3(a);
  for (int k = 0; k < 3; ++k) {
    for (int r = 0; r < 3; ++r) {
      double av = 0;
      for (int c = 0; c < 3; ++c) av += a[r][c] * eigen.vectors[k][c];
      EXPECT_NEAR(av, eigen.values[k] * eigen.vectors[k][r], 1e-14);
    }
    for (int j = 0; j < 3; ++j) {
      double dot = 0;
      for (int c = 0; c < 3; ++c) dot += eigen.vectors[k][c] * eigen.vectors[j][c];
      EXPECT_NEAR(dot, k == j ? 1.0 : 0.0, 1e-15);
    }
  }
  EXPECT_LT(eigen.values[0], eigen.values[1]);
  EXPECT_LT(eigen.values[1], eigen.values[2]);
}

// vox1_ref.ply's point 46: a neighbourhood on two axis-aligned voxel planes whose normal's y
// component is 0 in exact arithmetic. numpy.linalg.eigh (LAPACK dsyevd) returns -2^-53 there,
// which float32 keeps (flipped, vox1_ref_n.ply stores +1.110223e-16); these are its bits.
TEST(SymmetricEigen3, ReproducesLapacksRoundingNoise) {
  const std::array<Vec3, 3> covariance{
      {{0x1p-2, 0, -0x1p-2}, {0, 0x1.5555555555555p-1, 0}, {-0x1p-2, 0, 0x1p-1}}};
  const SymmetricEigen3 eigen = symmetric_eigenvectors_3x3(covariance);
  EXPECT_EQ(eigen.values, (std::array<double, 3>{0x1.8722191a02d60p-4, 0x1.4f1bbcdcbfa53p-1,
                                                 0x1.5555555555554p-1}));
  EXPECT_EQ(eigen.vectors[0], (Vec3{0x1.b38880b4603e4p-1, -0x1p-53, 0x1.0d2ca0da1530dp-1}));
}

}  // namespace
}  // namespace qm3d::pointcloud::detail
