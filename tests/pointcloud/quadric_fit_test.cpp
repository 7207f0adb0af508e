#include "quadric_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace qm3d::pointcloud::detail {
namespace {

std::vector<Neighbour> all_of(const std::vector<Vec3>& p) {
  std::vector<Neighbour> n;
  for (std::uint32_t i = 0; i < p.size(); ++i) n.push_back({0, i});
  return n;
}

// A 5 x 5 grid of (x, y) in [-0.1, 0.1]^2 lifted by height(x, y).
template <typename F>
std::vector<Vec3> graph_points(F height) {
  std::vector<Vec3> p;
  for (int i = -2; i <= 2; ++i) {
    for (int j = -2; j <= 2; ++j) {
      const double x = 0.05 * i, y = 0.05 * j;
      p.push_back({x, y, height(x, y)});
    }
  }
  return p;
}

TEST(GraphMeanCurvature, KnownValues) {
  EXPECT_EQ(graph_mean_curvature(0, 0, 0, 0, 0), 0.0);
  EXPECT_EQ(graph_mean_curvature(0, 0, 2, 2, 0), 2.0);  // z = x^2 + y^2 at its apex
  EXPECT_EQ(graph_mean_curvature(0, 0, 2, 0, 0), 1.0);  // a parabolic cylinder
  // Tilted plane: no curvature.
  EXPECT_EQ(graph_mean_curvature(0.3, -0.7, 0, 0, 0), 0.0);
}

TEST(QuadricFitter, PlaneHasZeroCurvatureAndProjectsOrthogonally) {
  const auto p = graph_points([](double, double) { return 0.5; });
  QuadricFitter fitter;
  const QuadricFit f = fitter.fit({0.02, -0.03, 0.7}, p, all_of(p));
  EXPECT_NEAR(f.mean_curvature, 0.0, 1e-12);
  EXPECT_NEAR(f.foot[0], 0.02, 1e-12);
  EXPECT_NEAR(f.foot[1], -0.03, 1e-12);
  EXPECT_NEAR(f.foot[2], 0.5, 1e-12);
}

TEST(QuadricFitter, ParaboloidApexHasCurvatureTwo) {
  const auto p = graph_points([](double x, double y) { return x * x + y * y; });
  QuadricFitter fitter;
  const QuadricFit f = fitter.fit({0, 0, 0.01}, p, all_of(p));
  EXPECT_NEAR(std::abs(f.mean_curvature), 2.0, 1e-9);
  EXPECT_NEAR(f.foot[2], 0.0, 1e-12);
}

TEST(QuadricFitter, NoNeighbourGivesOriginAndZero) {
  QuadricFitter fitter;
  const QuadricFit f = fitter.fit({1, 2, 3}, {}, {});
  EXPECT_EQ(f.mean_curvature, 0.0);
  EXPECT_EQ(f.foot, (Vec3{1, 2, 3}));
}

TEST(QuadricFitter, TwoPointsGiveZeroCurvature) {
  // Underdetermined: the QR's basic solution has no quadratic terms.
  const std::vector<Vec3> p{{0, 0, 0}, {0.01, 0.002, 0.001}};
  QuadricFitter fitter;
  const QuadricFit f = fitter.fit(p[0], p, all_of(p));
  EXPECT_TRUE(std::isfinite(f.foot[0]));
  EXPECT_EQ(f.mean_curvature, 0.0);
}

TEST(QuadricFitter, ReusingTheFitterGivesTheSameBits) {
  const auto big =
      graph_points([](double x, double y) { return 0.3 * x * x - y * y + 0.1 * x * y; });
  const auto small = graph_points([](double x, double y) { return x * y; });
  QuadricFitter reused;
  reused.fit({0, 0, 0}, small, all_of(small));
  const QuadricFit a = reused.fit({0.01, 0, 0}, big, all_of(big));
  const QuadricFit b = QuadricFitter().fit({0.01, 0, 0}, big, all_of(big));
  EXPECT_EQ(a.mean_curvature, b.mean_curvature);
  EXPECT_EQ(a.foot, b.foot);
}

}  // namespace
}  // namespace qm3d::pointcloud::detail

namespace qm3d::pointcloud::detail {
namespace {

// MEPP-team/PCQM's computeProjectionAndCurvature written with the same Eigen expressions, as the
// bit-for-bit yardstick of QuadricFitter.
QuadricFit reference_style_fit(const Vec3& o, const std::vector<Vec3>& pts) {
  Eigen::Matrix3d M;
  M.setZero();
  Eigen::Vector3d mu;
  mu.setZero();
  const int n = int(pts.size());
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d neighbor(pts[i][0], pts[i][1], pts[i][2]);
    mu = mu + neighbor;
    M = M + neighbor * neighbor.transpose();
  }
  mu = mu / double(n);
  M = 1. / double(n) * M - mu * mu.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
  Eigen::Vector3d t1 = eig.eigenvectors().col(2);
  Eigen::Vector3d t2 = eig.eigenvectors().col(1);
  Eigen::Vector3d nn = eig.eigenvectors().col(0);
  Eigen::MatrixXd A(n, 6);
  Eigen::VectorXd B(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d v(pts[i][0] - o[0], pts[i][1] - o[1], pts[i][2] - o[2]);
    double x = v.transpose() * t1;
    double y = v.transpose() * t2;
    double z = v.transpose() * nn;
    A(i, 0) = x * x;
    A(i, 1) = y * y;
    A(i, 2) = x * y;
    A(i, 3) = x;
    A(i, 4) = y;
    A(i, 5) = 1;
    B(i) = z;
  }
  Eigen::VectorXd c = A.colPivHouseholderQr().solve(B);
  Eigen::Vector3d delta = c(5) * nn;
  QuadricFit out;
  out.foot = {o[0] + delta(0), o[1] + delta(1), o[2] + delta(2)};
  double fxx = 2 * c(0), fyy = 2 * c(1), fxy = c(2), fx = c(3), fy = c(4);
  out.mean_curvature = 0.5 * ((1 + fx * fx) * fyy + (1 + fy * fy) * fxx - 2 * fxy * fx * fy) /
                       std::pow(1 + fx * fx + fy * fy, 1.5);
  return out;
}

TEST(QuadricFitter, BitIdenticalToTheReferenceExpressions) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  QuadricFitter fitter;
  for (int trial = 0; trial < 3000; ++trial) {
    const int n = 1 + trial % 40;
    const Vec3 centre{3 * g(rng), 3 * g(rng), 3 * g(rng)};
    std::vector<Vec3> pts(n);
    for (Vec3& p : pts) {
      const double x = 0.01 * g(rng), y = 0.01 * g(rng);
      p = {centre[0] + x, centre[1] + y, centre[2] + 2 * x * x - y * y + 1e-4 * g(rng)};
    }
    const Vec3 origin = pts[0];
    const QuadricFit expected = reference_style_fit(origin, pts);
    const QuadricFit got = fitter.fit_as_reference(origin, pts, all_of(pts));
    ASSERT_EQ(got.mean_curvature, expected.mean_curvature) << "trial " << trial;
    ASSERT_EQ(got.foot, expected.foot) << "trial " << trial;
  }
}

// fit() takes its fast path only where the fit is well-posed: there it agrees with the
// reference's arithmetic to rounding; elsewhere (underdetermined fits, where the reference's
// rounding decides) it is the reference's value bit for bit.
TEST(QuadricFitter, FastPathAgreesAndUnderdeterminedFitsKeepTheReferenceBits) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  QuadricFitter fitter;
  int underdetermined = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int n = 1 + trial % 40;
    const Vec3 centre{3 * g(rng), 3 * g(rng), 3 * g(rng)};
    std::vector<Vec3> pts(n);
    for (Vec3& p : pts) {
      const double x = 0.01 * g(rng), y = 0.01 * g(rng);
      p = {centre[0] + x, centre[1] + y, centre[2] + 2 * x * x - y * y + 1e-4 * g(rng)};
    }
    // Every fourth cloud repeats four positions: rank-deficient designs.
    if (trial % 4 == 3) {
      for (std::size_t i = 4; i < pts.size(); ++i) pts[i] = pts[i % 4];
    }
    const Vec3 origin = pts[0];
    const QuadricFit expected = fitter.fit_as_reference(origin, pts, all_of(pts));
    const QuadricFit got = fitter.fit(origin, pts, all_of(pts));
    ASSERT_EQ(got.underdetermined, expected.underdetermined) << "trial " << trial;
    if (expected.underdetermined) {
      ++underdetermined;
      ASSERT_EQ(got.mean_curvature, expected.mean_curvature) << "trial " << trial;
      ASSERT_EQ(got.foot, expected.foot) << "trial " << trial;
      continue;
    }
    // |H|: the normal's sign is the eigen-solver's choice (PCQM uses |H| and the foot point,
    // which do not depend on it).
    ASSERT_NEAR(std::abs(got.mean_curvature), std::abs(expected.mean_curvature),
                1e-9 * std::abs(expected.mean_curvature) + 1e-12)
        << "trial " << trial;
    for (int k = 0; k < 3; ++k) {
      ASSERT_NEAR(got.foot[k], expected.foot[k], 1e-14 * (1 + std::abs(expected.foot[k])))
          << "trial " << trial;
    }
  }
  EXPECT_GT(underdetermined, 1200);  // the test reaches the reference's path
}

// Coplanar points far from the origin (a voxelised plane): the heights are rounding residues, so
// the fit is left to the reference's arithmetic, bit for bit.
TEST(QuadricFitter, CoplanarPointsKeepTheReferenceBits) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> cell(-4, 4);
  QuadricFitter fitter;
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Vec3> pts(30);
    for (Vec3& p : pts) {
      const double x = 517.0 + cell(rng), y = 230.0 + cell(rng);
      p = {x, y, 811.0 + 0.3 * x + 0.7 * y + 0.01 * trial};  // a tilted plane
    }
    const Vec3 origin = pts[0];
    const QuadricFit expected = fitter.fit_as_reference(origin, pts, all_of(pts));
    const QuadricFit got = fitter.fit(origin, pts, all_of(pts));
    ASSERT_EQ(got.mean_curvature, expected.mean_curvature) << "trial " << trial;
    ASSERT_EQ(got.foot, expected.foot) << "trial " << trial;
  }
}

}  // namespace
}  // namespace qm3d::pointcloud::detail
