// PointSSIM's prepared clouds, ordered neighbour searches and quadric fit (pointssim_internal.h).
// Every rule that decides a number is the reference's (mmspg/pointssim @ 2358dd3, as
// ../shared/docs/SPEC-POINTSSIM.md describes it), written at the place it applies.
#include <omp.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "pointssim_internal.h"
#include "qm3d/common/error.h"
#include "quadric_fit.h"

namespace qm3d::pointcloud::detail {
namespace {

/// Rows per chunk of the parallel fit (each row's result is its own: the schedule does not
/// change any value).
constexpr int kChunk = 512;
/// The quadric z = p20 x^2 + p11 xy + p10 x + p02 y^2 + p01 y + p00: six coefficients.
constexpr int kTerms = 6;
/// The radius search's bound is widened by this share before the exact sqrt(d^2) <= r test, so
/// that no point the test keeps is missed through the rounding of r^2.
constexpr double kRadiusSlack = 1e-12;

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

// Our readers give c = u / 255 for 8-bit colours: u back.
std::uint8_t to_byte(double c) {
  return static_cast<std::uint8_t>(std::round(std::clamp(c, 0.0, 1.0) * 255.0));
}

bool row_less(const Vec3& a, const Vec3& b) {
  if (a[0] != b[0]) return a[0] < b[0];
  if (a[1] != b[1]) return a[1] < b[1];
  return a[2] < b[2];
}

bool same_row(const Vec3& a, const Vec3& b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; }

void check_finite(const ColoredCloud& cloud, const std::string& name) {
  for (std::size_t i = 0; i < cloud.positions.size(); ++i) {
    for (double v : cloud.positions[i]) {
      if (!std::isfinite(v)) {
        throw NumericError(name + ": point " + std::to_string(i) + " has a non-finite coordinate");
      }
    }
  }
}

// The fused colour of input points order[first, last): round(mean) per channel, the mean as
// sum / count (exact on 8-bit values), std::round: half away from zero, as MATLAB's round.
std::array<std::uint8_t, 3> fused_colour(const ColoredCloud& cloud,
                                         const std::vector<std::uint32_t>& order, std::size_t first,
                                         std::size_t last) {
  double sum[3] = {0, 0, 0};
  for (std::size_t k = first; k < last; ++k) {
    const Rgb& c = cloud.colors[order[k]];
    sum[0] += to_byte(c.r);
    sum[1] += to_byte(c.g);
    sum[2] += to_byte(c.b);
  }
  const double count = static_cast<double>(last - first);
  std::array<std::uint8_t, 3> out{};
  for (int ch = 0; ch < 3; ++ch) out[ch] = static_cast<std::uint8_t>(std::round(sum[ch] / count));
  return out;
}

// pcacov's frame of a covariance: the eigenvectors as columns in descending order of the
// singular values (|eigenvalue|), each column signed so that its largest-|.| element is
// positive, the first one winning on exact ties (MATLAB's current pcacov convention).
Eigen::Matrix3d principal_frame(const Eigen::Matrix3d& covariance) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d& values = solver.eigenvalues();
  std::array<int, 3> order{2, 1, 0};
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return std::abs(values(a)) > std::abs(values(b)); });
  Eigen::Matrix3d frame;
  for (int j = 0; j < 3; ++j) {
    Eigen::Vector3d v = solver.eigenvectors().col(order[j]);
    int largest = 0;
    for (int k = 1; k < 3; ++k) {
      if (std::abs(v(k)) > std::abs(v(largest))) largest = k;
    }
    if (v(largest) < 0) v = -v;
    frame.col(j) = v;
  }
  return frame;
}

/// The local coordinates (x, y, z) of a neighbourhood and what the fit keeps of them.
struct LocalPatch {
  std::vector<double> x, y, z;
};

// cov(P, 1): the rows centred on their mean (sum / n), then (d' d) / n, each entry summed in
// row order. Also gives the mean.
Eigen::Matrix3d population_covariance(const std::vector<Vec3>& points,
                                      const std::vector<Neighbour>& rows, Eigen::Vector3d& mean) {
  const double n = static_cast<double>(rows.size());
  Eigen::Vector3d sum(0, 0, 0);
  for (const Neighbour& r : rows) {
    for (int k = 0; k < 3; ++k) sum(k) += points[r.index][k];
  }
  mean = sum / n;
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  for (const Neighbour& r : rows) {
    const Vec3& p = points[r.index];
    const double d[3] = {p[0] - mean(0), p[1] - mean(1), p[2] - mean(2)};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) c(i, j) += d[i] * d[j];
    }
  }
  return c / n;
}

// (v - mean) E as a row vector times the frame, each entry summed over k in order.
Eigen::Vector3d project(const Vec3& v, const Eigen::Vector3d& mean, const Eigen::Matrix3d& frame) {
  const double d[3] = {v[0] - mean(0), v[1] - mean(1), v[2] - mean(2)};
  Eigen::Vector3d out;
  for (int j = 0; j < 3; ++j)
    out(j) = (d[0] * frame(0, j) + d[1] * frame(1, j)) + d[2] * frame(2, j);
  return out;
}

// The sample standard deviation (n - 1) of a column, 1 where it is 0 (polyfitn_c's
// standardisation of the independent variables).
double column_scale(const std::vector<double>& v) {
  const double n = static_cast<double>(v.size());
  double sum = 0;
  for (double x : v) sum += x;
  const double mean = sum / n;
  double squares = 0;
  for (double x : v) squares += (x - mean) * (x - mean);
  const double s = std::sqrt(squares / (n - 1));
  return s == 0 ? 1.0 : s;
}

/// Per-thread workspace of the fit.
struct FitWorkspace {
  std::vector<Neighbour> rows;
  LocalPatch patch;
  std::vector<double> columns;
};

// Row i of the standardised design (terms x^2, xy, x, y^2, y, 1 of x / sx and y / sy) and its
// height.
void design_row(const LocalPatch& patch, std::size_t i, double ix, double iy,
                double out[kTerms + 1]) {
  const double x = patch.x[i] * ix, y = patch.y[i] * iy;
  out[0] = x * x;
  out[1] = x * y;
  out[2] = x;
  out[3] = y * y;
  out[4] = y;
  out[5] = 1;
  out[6] = patch.z[i];
}

// The minimum-norm least-squares solution of the standardised system.
void minimum_norm_solution(const LocalPatch& patch, double ix, double iy, double c[kTerms]) {
  const auto n = static_cast<Eigen::Index>(patch.x.size());
  Eigen::MatrixXd design(n, kTerms);
  Eigen::VectorXd heights(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    double row[kTerms + 1];
    design_row(patch, static_cast<std::size_t>(i), ix, iy, row);
    for (int t = 0; t < kTerms; ++t) design(i, t) = row[t];
    heights(i) = row[kTerms];
  }
  const Eigen::VectorXd s = design.completeOrthogonalDecomposition().solve(heights);
  for (int t = 0; t < kTerms; ++t) c[t] = s(t);
}

// The least-squares quadric of the standardised coordinates (polyfitn_c with order 2: x and y
// divided by their sample deviations, the coefficients scaled back). A well-posed system is
// solved by the module's QR (quadric_fit.h); any other (fewer than six points, a degenerate
// design) by its minimum-norm solution, which is what the reference's `R \ (Q' z)` gives under
// Octave for an underdetermined system (the reference values' runtime; MATLAB gives a basic
// solution there: such values depend on the solver, SPEC-POINTSSIM "cross-check").
std::array<double, kTerms> fit_quadric(FitWorkspace& w) {
  const std::size_t n = w.patch.x.size();
  const double sx = column_scale(w.patch.x), sy = column_scale(w.patch.y);
  const double ix = 1 / sx, iy = 1 / sy;
  double c[kTerms];
  bool solved = false;
  if (n >= static_cast<std::size_t>(kTerms)) {
    w.columns.resize((kTerms + 1) * n);
    double* col[kTerms + 1];
    for (int t = 0; t <= kTerms; ++t) col[t] = &w.columns[static_cast<std::size_t>(t) * n];
    for (std::size_t i = 0; i < n; ++i) {
      double row[kTerms + 1];
      design_row(w.patch, i, ix, iy, row);
      for (int t = 0; t <= kTerms; ++t) col[t][i] = row[t];
    }
    solved = solve_well_posed_least_squares(col, n, c);
  }
  if (!solved) minimum_norm_solution(w.patch, ix, iy, c);
  // scalefact: (1 / sx^a) / sy^b for the term x^a y^b.
  return {c[0] * (1 / (sx * sx)), c[1] * ((1 / sx) / sy), c[2] * (1 / sx),
          c[3] * (1 / (sy * sy)), c[4] * (1 / sy),        c[5]};
}

/// What the fit gives a row.
struct RowEstimate {
  Vec3 normal;
  double curvature;
};

// The principal frame of the neighbourhood w.rows, and its local coordinates in w.patch:
// (P - mean) E - (p - mean) E.
Eigen::Matrix3d local_patch(const std::vector<Vec3>& points, std::size_t row, FitWorkspace& w) {
  Eigen::Vector3d mean;
  const Eigen::Matrix3d frame = principal_frame(population_covariance(points, w.rows, mean));
  const Eigen::Vector3d origin = project(points[row], mean, frame);
  const std::size_t n = w.rows.size();
  w.patch.x.resize(n);
  w.patch.y.resize(n);
  w.patch.z.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d q = project(points[w.rows[i].index], mean, frame);
    w.patch.x[i] = q(0) - origin(0);
    w.patch.y[i] = q(1) - origin(1);
    w.patch.z[i] = q(2) - origin(2);
  }
  return frame;
}

// Normal and curvature of one row from its neighbourhood w.rows (pc_estimate_norm_curv_qfit);
// NaN where the reference leaves NaN.
RowEstimate fit_row(const std::vector<Vec3>& points, std::size_t row, FitWorkspace& w) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const RowEstimate none{Vec3{nan, nan, nan}, nan};
  // One point: polyfitn_c's sample deviation of a single row is 0 / 0 under Octave, and the
  // reference keeps NaN.
  if (w.rows.size() < 2) return none;
  const Eigen::Matrix3d frame = local_patch(points, row, w);
  const auto [p20, p11, p10, p02, p01, p00] = fit_quadric(w);
  if (std::isnan(p20) && std::isnan(p11) && std::isnan(p10) && std::isnan(p02) && std::isnan(p01) &&
      std::isnan(p00)) {
    return none;  // the reference skips a fit whose coefficients are all NaN
  }
  // Normal [-p10, -p01, 1] normalised, back to the cloud's axes (times E'), normalised again.
  const double local_norm = std::sqrt((p10 * p10 + p01 * p01) + 1);
  const double u[3] = {-p10 / local_norm, -p01 / local_norm, 1 / local_norm};
  double world[3];
  for (int j = 0; j < 3; ++j) {
    world[j] = (u[0] * frame(j, 0) + u[1] * frame(j, 1)) + u[2] * frame(j, 2);
  }
  const double world_norm =
      std::sqrt((world[0] * world[0] + world[1] * world[1]) + world[2] * world[2]);
  // The reference's curvature as coded (not the textbook mean curvature: the gradient factors
  // are swapped and the cross term differs; SPEC-POINTSSIM step 3).
  const double curvature = ((1 + p10 * p10) * p20 + (1 + p01 * p01) * p02 - 4 * p20 * p02 * p11) /
                           std::pow((1 + p01 * p01) + p10 * p10, 1.5);
  return {Vec3{world[0] / world_norm, world[1] / world_norm, world[2] / world_norm}, curvature};
}

}  // namespace

SsimCloud prepare_cloud(const ColoredCloud& cloud, bool with_colours, const std::string& name) {
  check_finite(cloud, name);
  const std::size_t n = cloud.positions.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  // sortrows: lexicographic, stable.
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return row_less(cloud.positions[a], cloud.positions[b]);
  });
  SsimCloud out;
  out.of_input.resize(n);
  for (std::size_t first = 0; first < n;) {
    std::size_t last = first + 1;
    while (last < n && same_row(cloud.positions[order[last]], cloud.positions[order[first]]))
      ++last;
    const auto fused = static_cast<std::uint32_t>(out.points.size());
    out.points.push_back(cloud.positions[order[first]]);
    if (with_colours) out.colours.push_back(fused_colour(cloud, order, first, last));
    for (std::size_t k = first; k < last; ++k) out.of_input[order[k]] = fused;
    out.duplicates += last - first - 1;
    first = last;
  }
  return out;
}

OrderedSearch::OrderedSearch(const std::vector<Vec3>& points, int threads)
    : tree_(points, threads) {}

void OrderedSearch::to_rows(std::vector<Neighbour>& found) const {
  for (Neighbour& nb : found) nb.index = tree_.input_index()[nb.index];
  sort_by_distance(found);  // d^2, exact ties to the lower row
}

void OrderedSearch::knn(const Vec3& query, std::size_t k, std::vector<Neighbour>& out) const {
  const std::size_t n = size();
  const std::size_t probe = std::min(k + 1, n);
  tree_.knn_search(query, probe, out);
  if (probe == n || out[k].distance2 > out[k - 1].distance2) {
    // Every point as near as the k-th is in hand: only their order is the tree's.
    to_rows(out);
    out.resize(std::min(k, n));
    return;
  }
  // The k-th distance is tied beyond the k found: every point at most that far, then the
  // reference's order decides which ones are kept.
  const double worst = out[k - 1].distance2;
  tree_.radius_search(query, std::nextafter(worst, HUGE_VAL), out);
  to_rows(out);
  out.resize(k);
}

void OrderedSearch::within(const Vec3& query, double radius, std::vector<Neighbour>& out) const {
  const double bound = std::nextafter(radius * radius * (1 + kRadiusSlack), HUGE_VAL);
  tree_.radius_search(query, bound, out);
  out.erase(
      std::remove_if(out.begin(), out.end(),
                     [&](const Neighbour& nb) { return !(std::sqrt(nb.distance2) <= radius); }),
      out.end());
  to_rows(out);
}

SurfaceEstimates estimate_surface(const std::vector<Vec3>& points, const OrderedSearch& search,
                                  const FitNeighbourhood& fit, std::size_t k, int threads) {
  SurfaceEstimates out;
  out.normals.resize(points.size());
  out.curvatures.resize(points.size());
  if (fit.count > 0) {
    out.k = std::min(k, points.size());
    out.nearest.resize(points.size() * out.k);
  }
  const long n = static_cast<long>(points.size());
#pragma omp parallel num_threads(thread_count(threads))
  {
    FitWorkspace w;
#pragma omp for schedule(dynamic, kChunk)
    for (long i = 0; i < n; ++i) {
      const auto row = static_cast<std::size_t>(i);
      if (fit.count > 0) {
        // The nearest max(count, k) in the reference's total order: both neighbourhoods are
        // prefixes of it.
        search.knn(points[row], std::max(fit.count, k), w.rows);
        for (std::size_t j = 0; j < out.k; ++j) out.nearest[row * out.k + j] = w.rows[j].index;
        if (w.rows.size() > fit.count) w.rows.resize(fit.count);
      } else {
        search.within(points[row], fit.radius, w.rows);
      }
      const RowEstimate e = fit_row(points, row, w);
      out.normals[row] = e.normal;
      out.curvatures[row] = e.curvature;
    }
  }
  return out;
}

}  // namespace qm3d::pointcloud::detail
