// GraphSIM / MS-GraphSIM per keypoint (graphsim_engine.h). Everything in float64; the reference
// code's single() casts are evaluated as double, as the reference data's f64 columns are. Every
// distance is sqrt(dx^2 + dy^2 + dz^2) summed left to right (kd_tree.h squared_distance), every
// range test inclusive (<=), and rows are ordered lexicographically by (x, y, z, r, g, b).
#include "graphsim_engine.h"

#include <algorithm>
#include <cmath>

namespace qm3d::pointcloud::detail {
namespace {

/// The neighbour rank of the graph radius rho (graphcreation's K = 50, capped at the set size).
constexpr std::size_t kRhoRank = 50;
/// Rows of the local set whose rank-K distance is measured: round(linspace(1, N, 100)).
constexpr int kRhoSamples = 100;
/// The constant of the covariance similarity cg, fixed (T applies to mg / mug only).
constexpr double kCovarianceConstant = 0.001;
/// MS-GraphSIM keeps every other row per scale: coordinates shrink by this to the power r_s.
constexpr double kKeptFraction = 0.5;
/// Relative slack of the k-d tree's strict radius query around the inclusive test applied after.
constexpr double kQuerySlack = 1e-9;

struct Row {
  Vec3 p;
  Colour255 c;
};

bool row_less(const Row& a, const Row& b) {
  if (a.p != b.p) return a.p < b.p;
  return a.c < b.c;
}
bool row_equal(const Row& a, const Row& b) { return a.p == b.p && a.c == b.c; }

void sort_unique(std::vector<Row>& rows) {
  std::sort(rows.begin(), rows.end(), row_less);
  rows.erase(std::unique(rows.begin(), rows.end(), row_equal), rows.end());
}

double distance(const Vec3& a, const Vec3& b) { return std::sqrt(squared_distance(a, b)); }

/// The rows of one scale: sorted rows, a weight per row (0 at the centre), the centre's row.
struct Scale {
  std::vector<Row> rows;
  std::vector<double> weight;
  std::size_t centre = 0;  // the first row at the keypoint's coordinates
};

/// RGB -> LMN (RGB2LMN of the papers), each sum left to right.
std::array<double, 3> lmn(const Colour255& a) {
  return {0.06 * a[0] + 0.63 * a[1] + 0.27 * a[2], 0.3 * a[0] + 0.04 * a[1] - 0.35 * a[2],
          0.34 * a[0] - 0.60 * a[1] + 0.17 * a[2]};
}
std::array<double, 3> lmn_unit(const Colour255& a) {
  return lmn({a[0] / 255.0, a[1] / 255.0, a[2] / 255.0});
}

/// P: (c, q) and every point of X with 0 < |p - c| <= eps (points at c itself are dropped, so
/// the centre always carries the reference's colour q), unique rows, sorted.
std::vector<Row> local_set(const GraphsimCloud& x, const Vec3& c, const Colour255& q, double eps) {
  std::vector<Neighbour> found;
  x.tree.radius_search(c, eps * eps * (1 + kQuerySlack), found);
  std::vector<Row> rows{{c, q}};
  rows.reserve(found.size() + 1);
  for (const Neighbour& n : found) {
    const std::size_t i = x.tree.input_index()[n.index];
    const double d = distance(x.positions[i], c);
    if (d > 0 && d <= eps) rows.push_back({x.positions[i], x.colours[i]});
  }
  sort_unique(rows);
  return rows;
}

/// rho: the largest distance from a sampled row j to its s-th nearest row of P (itself at
/// distance 0 counted), s = min(50, N), over the rows j = round(linspace(1, N, 100)) (1-based; the
/// fractions are multiples of 1/99, never .5, so the rounding rule cannot matter).
double graph_radius(const std::vector<Row>& rows) {
  const std::size_t n = rows.size();
  const std::size_t s = std::min(kRhoRank, n);
  std::vector<double> d2(n);
  double rho2 = 0;
  long previous = -1;
  for (int i = 0; i < kRhoSamples; ++i) {
    const long j = std::lround(1.0 + i * (static_cast<double>(n - 1) / (kRhoSamples - 1))) - 1;
    if (j == previous) continue;
    previous = j;
    std::size_t within = 0;  // rows no farther than the largest so far: s of them, no news
    for (std::size_t t = 0; t < n; ++t) {
      d2[t] = squared_distance(rows[j].p, rows[t].p);
      within += d2[t] <= rho2;
    }
    if (within >= s) continue;
    std::nth_element(d2.begin(), d2.begin() + static_cast<long>(s - 1), d2.end());
    rho2 = std::max(rho2, d2[s - 1]);
  }
  return std::sqrt(rho2);  // sqrt is monotone: the largest sqrt is the sqrt of the largest
}

/// P' and its weights: (c, q) and the rows of P with 0 < |p - c| <= rho, in P's order, weight
/// exp(-d^2 / (rho^2 / 2)), 0 for the rows at c.
Scale first_scale(const std::vector<Row>& set, const Vec3& c, double rho) {
  const double sigma = rho * rho / 2;
  Scale s;
  for (const Row& r : set) {
    const double d = distance(r.p, c);
    if (r.p == c) {
      s.weight.push_back(0);
    } else if (d > 0 && d <= rho) {
      s.weight.push_back(std::exp(-(d * d) / sigma));
    } else {
      continue;
    }
    s.rows.push_back(r);
  }
  s.centre = static_cast<std::size_t>(
      std::find_if(s.rows.begin(), s.rows.end(), [&](const Row& r) { return r.p == c; }) -
      s.rows.begin());
  return s;
}

/// The edges of row i in the scale's radius graph (i-j an edge iff 0 < d_ij <= radius, W_ij =
/// exp(-d^2/sigma), no self loops), ascending in j. Every scale's rows are sorted by x (sorted
/// rows, coordinates shrunk by a monotone map), so the candidates, |x_j - x_i| <= radius (a lower
/// bound of d_ij), are the contiguous rows from `first` on (every row when !by_x); |dy|, |dz|
/// likewise skip most of them before the exact test.
void edges_of(const std::vector<Row>& rows, std::size_t i, std::size_t first, bool by_x,
              double radius, double sigma, std::vector<std::pair<std::size_t, double>>& edges) {
  const double reach = radius * (1 + kQuerySlack);
  const Vec3& p = rows[i].p;
  edges.clear();
  for (std::size_t j = first; j < rows.size() && (!by_x || rows[j].p[0] <= p[0] + reach); ++j) {
    if (j == i || std::abs(rows[j].p[1] - p[1]) > reach || std::abs(rows[j].p[2] - p[2]) > reach) {
      continue;
    }
    const double d = distance(p, rows[j].p);
    if (d > 0 && d <= radius) edges.emplace_back(j, std::exp(-(d * d) / sigma));
  }
}

/// The blur on the scale's radius graph: each row's colour becomes sum_j (W_ij * (1 / deg_i))
/// col_j, deg_i = sum_j W_ij, both summed in ascending j (its own colour excluded); a row
/// without edges keeps its colour. Coordinates stay. Each row's edges are found when needed (no
/// edge list: graphs of thousands of rows have millions of edges).
void blur(std::vector<Row>& rows, double radius, double sigma) {
  const bool by_x = std::is_sorted(rows.begin(), rows.end(),
                                   [](const Row& a, const Row& b) { return a.p[0] < b.p[0]; });
  const double reach = radius * (1 + kQuerySlack);
  std::vector<Colour255> out(rows.size());
  std::vector<std::pair<std::size_t, double>> edges;
  std::size_t first = 0;  // the first row with x >= x_i - reach (x_i never decreases)
  for (std::size_t i = 0; i < rows.size(); ++i) {
    while (by_x && rows[first].p[0] < rows[i].p[0] - reach) ++first;
    edges_of(rows, i, first, by_x, radius, sigma, edges);
    double degree = 0;
    for (const auto& e : edges) degree += e.second;
    if (degree == 0) {
      out[i] = rows[i].c;
      continue;
    }
    const double inverse = 1 / degree;
    Colour255 sum{0, 0, 0};
    for (const auto& [j, w] : edges) {
      const double f = w * inverse;
      for (int k = 0; k < 3; ++k) sum[k] += f * rows[j].c[k];
    }
    out[i] = sum;
  }
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i].c = out[i];
}

/// The next scale: rows sorted by (x, y, z, r, g, b, row), the 1st, 3rd, 5th, ... kept, the
/// centre row added back, unique and sorted; then each coordinate x <- s (x - c) + c with
/// s = 0.5^r_s (one step per scale, from the previous scale's coordinates: edges at the blur
/// radius depend on these exact values); weights exp(-d^2/sigma) of the distance to c, zeroed
/// for the first row at c.
Scale next_scale(const Scale& s, const Vec3& c, double shrink, double sigma) {
  std::vector<std::size_t> order(s.rows.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (row_equal(s.rows[a], s.rows[b])) return a < b;
    return row_less(s.rows[a], s.rows[b]);
  });
  Scale out;
  for (std::size_t k = 0; k < order.size(); k += 2) out.rows.push_back(s.rows[order[k]]);
  out.rows.push_back(s.rows[s.centre]);
  sort_unique(out.rows);
  for (Row& r : out.rows) {
    for (int k = 0; k < 3; ++k) r.p[k] = shrink * (r.p[k] - c[k]) + c[k];
  }
  bool centre_seen = false;
  for (std::size_t i = 0; i < out.rows.size(); ++i) {
    const double d = distance(out.rows[i].p, c);
    double w = std::exp(-(d * d) / sigma);
    if (!centre_seen && out.rows[i].p == c) {
      centre_seen = true;
      out.centre = i;
      w = 0;
    }
    out.weight.push_back(w);
  }
  return out;
}

/// mg: sum_i sqrt(w_i) (LMN(centre / 255) - LMN(col_i / 255)) in row order; mug = mg / (N - 1)
/// (0 for a lone centre).
struct Moments {
  std::array<double, 3> mg{0, 0, 0};
  std::array<double, 3> mug{0, 0, 0};
};
Moments gradient_moments(const Scale& s) {
  Moments m;
  const std::array<double, 3> centre = lmn_unit(s.rows[s.centre].c);
  for (std::size_t i = 0; i < s.rows.size(); ++i) {
    const std::array<double, 3> v = lmn_unit(s.rows[i].c);
    const double root = std::sqrt(s.weight[i]);
    for (int k = 0; k < 3; ++k) m.mg[k] += root * (centre[k] - v[k]);
  }
  const double others = static_cast<double>(s.rows.size() - 1);
  for (int k = 0; k < 3; ++k) m.mug[k] = others > 0 ? m.mg[k] / others : 0.0;
  return m;
}

double similarity(double a, double b, double t) { return (2 * a * b + t) / (a * a + b * b + t); }

/// The rows with a non-zero weight.
std::vector<std::size_t> weighted_rows(const Scale& s) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < s.weight.size(); ++i) {
    if (s.weight[i] != 0) out.push_back(i);
  }
  return out;
}

/// The nearest of `candidates` (rows of `big`) to p; ties to the first (lowest row).
std::size_t nearest_row(const Scale& big, const std::vector<std::size_t>& candidates,
                        const Vec3& p) {
  std::size_t best = candidates.front();
  double best_d = distance(big.rows[best].p, p);
  for (std::size_t k = 1; k < candidates.size(); ++k) {
    const double d = distance(big.rows[candidates[k]].p, p);
    if (d < best_d) {
      best_d = d;
      best = candidates[k];
    }
  }
  return best;
}

/// The per-channel covariance (n - 1) similarity of two gradient columns, constant 0.001.
/// sqrt(var1 var2) instead of sqrt(var1) sqrt(var2): within an ulp, and exactly 1 for equal
/// columns (a cloud against itself).
double covariance_similarity(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= n;
  mb /= n;
  double cab = 0, caa = 0, cbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    cab += (a[i] - ma) * (b[i] - mb);
    caa += (a[i] - ma) * (a[i] - ma);
    cbb += (b[i] - mb) * (b[i] - mb);
  }
  cab /= n - 1;
  caa /= n - 1;
  cbb /= n - 1;
  return (cab + kCovarianceConstant) / (std::sqrt(caa * cbb) + kCovarianceConstant);
}

/// cg: the weighted rows of the smaller set each paired with their nearest weighted row of the
/// larger one (equal sizes: the distorted set is the larger), gradients sqrt(w)(LMN(q) - LMN(col))
/// on raw 0..255 colours, q the keypoint's reference colour; 0 when either set has <= 1 row.
std::array<double, 3> gradient_covariance(const Scale& r, const Scale& d, const Colour255& q) {
  const std::vector<std::size_t> a = weighted_rows(r), b = weighted_rows(d);
  if (std::min(a.size(), b.size()) <= 1) return {0, 0, 0};
  const bool ref_big = a.size() > b.size();
  const Scale& big = ref_big ? r : d;
  const Scale& small = ref_big ? d : r;
  const std::vector<std::size_t>& big_rows = ref_big ? a : b;
  const std::vector<std::size_t>& small_rows = ref_big ? b : a;
  const std::array<double, 3> centre = lmn(q);
  std::array<std::vector<double>, 3> g1, g2;
  for (std::size_t i : small_rows) {
    const std::size_t nn = nearest_row(big, big_rows, small.rows[i].p);
    const std::array<double, 3> vb = lmn(big.rows[nn].c), vs = lmn(small.rows[i].c);
    const double wb = std::sqrt(big.weight[nn]), ws = std::sqrt(small.weight[i]);
    for (int k = 0; k < 3; ++k) {
      g1[k].push_back(wb * (centre[k] - vb[k]));
      g2[k].push_back(ws * (centre[k] - vs[k]));
    }
  }
  return {covariance_similarity(g1[0], g2[0]), covariance_similarity(g1[1], g2[1]),
          covariance_similarity(g1[2], g2[2])};
}

/// The channel products |p_ch| = |sim(mg) sim(mug) cg| of one scale.
std::array<double, 3> channel_products(const Scale& r, const Scale& d, const Colour255& q,
                                       double threshold) {
  const Moments mr = gradient_moments(r), md = gradient_moments(d);
  const std::array<double, 3> cg = gradient_covariance(r, d, q);
  std::array<double, 3> p{};
  for (int k = 0; k < 3; ++k) {
    p[k] = std::abs(similarity(mr.mg[k], md.mg[k], threshold) *
                    similarity(mr.mug[k], md.mug[k], threshold) * cg[k]);
  }
  return p;
}

double pooled(const std::array<double, 3>& p, const std::array<double, 3>& w) {
  return (std::abs(p[0] * w[0]) + std::abs(p[1] * w[1]) + std::abs(p[2] * w[2])) /
         (w[0] + w[1] + w[2]);
}

/// One cloud's scale 0 around the keypoint, with its rho.
Scale keypoint_graph(const GraphsimCloud& x, const Vec3& c, const Colour255& q, double eps,
                     double& rho) {
  const std::vector<Row> set = local_set(x, c, q, eps);
  rho = graph_radius(set);
  return first_scale(set, c, rho);
}

}  // namespace

GraphsimCloud::GraphsimCloud(std::vector<Vec3> p, std::vector<Colour255> c, int threads)
    : positions(std::move(p)), colours(std::move(c)), tree(positions, threads) {}

KeypointScores score_keypoint(const GraphsimCloud& reference, const GraphsimCloud& distorted,
                              std::size_t keypoint, double eps, const GraphsimParams& params) {
  const Vec3& c = reference.positions[keypoint];
  const Colour255& q = reference.colours[keypoint];
  double rho_r = 0, rho_d = 0;
  Scale r = keypoint_graph(reference, c, q, eps, rho_r);
  Scale d = keypoint_graph(distorted, c, q, eps, rho_d);
  KeypointScores out;
  out.lone = weighted_rows(r).size() <= 1;
  out.channels = channel_products(r, d, q, params.threshold);
  out.per_scale.push_back(pooled(out.channels, params.weights));
  const double shrink = std::pow(kKeptFraction, params.sample_ratio);
  // Scale 0's graph has sigma rho^2/2; the later ones (r_b rho / r_b)^2 / 2, as the reference
  // recovers rho from the blur radius it passes along.
  const double rb = params.blur_ratio;
  double sigma_r = rho_r * rho_r / 2, sigma_d = rho_d * rho_d / 2;
  for (int k = 1; k < params.scales; ++k) {
    blur(r.rows, rb * rho_r, sigma_r);
    blur(d.rows, rb * rho_d, sigma_d);
    const double r1 = rb * rho_r / rb, d1 = rb * rho_d / rb;
    sigma_r = r1 * r1 / 2;
    sigma_d = d1 * d1 / 2;
    r = next_scale(r, c, shrink, sigma_r);
    d = next_scale(d, c, shrink, sigma_d);
    out.per_scale.push_back(pooled(channel_products(r, d, q, params.threshold), params.weights));
  }
  return out;
}

}  // namespace qm3d::pointcloud::detail
