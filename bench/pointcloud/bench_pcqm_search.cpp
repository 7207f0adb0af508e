// Neighbour searches of PCQM on the 1M benchmark sphere: PCL's KdTreeFLANN (float, its
// candidates re-filtered in double to get the reference's exact sets) against qm3d's double k-d
// tree, per-query and leaf-batched, in file order and in tree (spatially coherent) order.
//
// Reads $QM3D_BENCH_DIR/sphere_1000k_ref_bin.ply (gen_big_cloud.py 1000000 DIR). Radii are
// PCQM's defaults on that sphere: r = 0.004 * 2, statistics radius 2r, k = 20.
// Counter `mismatch` = queries whose exact neighbour set differs from the k-d tree's.
#include <benchmark/benchmark.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <numeric>

#include "candidate_set.h"
#include "kd_tree.h"
#include "qm3d/pointcloud/cloud_io.h"

namespace {

using qm3d::Vec3;
using namespace qm3d::pointcloud::detail;

constexpr double kRadius = 0.004 * 2.0;  // PCQM default radius_rel times maxDim of the sphere
constexpr std::size_t kK = 20;
constexpr std::size_t kQueries = 200000;  // queries per iteration (a fifth of the cloud)

struct Data {
  std::vector<Vec3> points;
  std::unique_ptr<KdTree> tree;
  pcl::KdTreeFLANN<pcl::PointXYZ> flann;
  std::vector<std::uint32_t> file_order;  // query i = point i of the file
  std::vector<std::uint32_t> tree_order;  // query i = tree point i (leaf order), as input index
};

const Data& data() {
  static const std::unique_ptr<Data> d = [] {
    auto out = std::make_unique<Data>();
    const char* dir = std::getenv("QM3D_BENCH_DIR");
    const std::string base = dir != nullptr ? dir : "/tmp/qm3d_bench";
    out->points = qm3d::pointcloud::read_cloud(base + "/sphere_1000k_ref_bin.ply").positions;
    out->tree = std::make_unique<KdTree>(out->points);
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    for (const Vec3& p : out->points) cloud->push_back(pcl::PointXYZ(p[0], p[1], p[2]));
    out->flann.setInputCloud(cloud);
    out->file_order.resize(out->points.size());
    std::iota(out->file_order.begin(), out->file_order.end(), 0u);
    out->tree_order = out->tree->input_index();
    return out;
  }();
  return *d;
}

const std::vector<std::uint32_t>& order(int which) {
  return which == 0 ? data().file_order : data().tree_order;
}

// PCL radius search, then the exact double test on the candidates (radius inflated to cover
// float rounding).
void pcl_exact_radius(const Data& d, const Vec3& q, double r, std::vector<int>& idx,
                      std::vector<float>& d2f, std::vector<Neighbour>& out) {
  d.flann.radiusSearch(pcl::PointXYZ(float(q[0]), float(q[1]), float(q[2])), r * (1 + 1e-5) + 1e-6,
                       idx, d2f, 0);
  out.clear();
  for (int i : idx) {
    const double d2 = squared_distance(q, d.points[std::size_t(i)]);
    if (d2 < r * r) out.push_back(Neighbour{d2, std::uint32_t(i)});
  }
}

void BM_PclFlannRadius(benchmark::State& state) {
  const Data& d = data();
  const auto& ord = order(int(state.range(0)));
  const double r = kRadius * double(state.range(1));
  std::vector<int> idx;
  std::vector<float> d2f;
  std::vector<Neighbour> out, mine;
  std::int64_t found = 0, mismatch = 0;
  for (auto _ : state) {
    for (std::size_t k = 0; k < kQueries; ++k) {
      const Vec3& q = d.points[ord[k]];
      pcl_exact_radius(d, q, r, idx, d2f, out);
      found += std::int64_t(out.size());
    }
  }
  // Exactness check (outside the timing): same sets as the double k-d tree.
  for (std::size_t k = 0; k < kQueries; k += 97) {
    const Vec3& q = d.points[ord[k]];
    pcl_exact_radius(d, q, r, idx, d2f, out);
    d.tree->radius_search(q, r * r, mine);
    std::vector<std::uint32_t> a, b;
    for (auto& n : out) a.push_back(n.index);
    for (auto& n : mine) b.push_back(d.tree->input_index()[n.index]);
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    mismatch += a != b;
  }
  state.counters["per_query"] =
      benchmark::Counter(double(kQueries), benchmark::Counter::kIsIterationInvariantRate |
                                               benchmark::Counter::kInvert);
  state.counters["found"] = double(found) / double(kQueries * state.iterations());
  state.counters["mismatch"] = double(mismatch);
}

void BM_PclFlannKnn(benchmark::State& state) {
  const Data& d = data();
  const auto& ord = order(int(state.range(0)));
  std::vector<int> idx;
  std::vector<float> d2f;
  for (auto _ : state) {
    for (std::size_t k = 0; k < kQueries; ++k) {
      const Vec3& q = d.points[ord[k]];
      d.flann.nearestKSearch(pcl::PointXYZ(float(q[0]), float(q[1]), float(q[2])), kK + 4, idx,
                             d2f);
      benchmark::DoNotOptimize(idx.data());
    }
  }
  state.counters["per_query"] =
      benchmark::Counter(double(kQueries), benchmark::Counter::kIsIterationInvariantRate |
                                               benchmark::Counter::kInvert);
}

void BM_KdTreeRadius(benchmark::State& state) {
  const Data& d = data();
  const auto& ord = order(int(state.range(0)));
  const double r = kRadius * double(state.range(1));
  std::vector<Neighbour> out;
  for (auto _ : state) {
    for (std::size_t k = 0; k < kQueries; ++k) {
      d.tree->radius_search(d.points[ord[k]], r * r, out);
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.counters["per_query"] =
      benchmark::Counter(double(kQueries), benchmark::Counter::kIsIterationInvariantRate |
                                               benchmark::Counter::kInvert);
}

void BM_KdTreeKnn(benchmark::State& state) {
  const Data& d = data();
  const auto& ord = order(int(state.range(0)));
  std::vector<Neighbour> out;
  for (auto _ : state) {
    for (std::size_t k = 0; k < kQueries; ++k) {
      d.tree->knn_search(d.points[ord[k]], kK, out);
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.counters["per_query"] =
      benchmark::Counter(double(kQueries), benchmark::Counter::kIsIterationInvariantRate |
                                               benchmark::Counter::kInvert);
}

// Leaf-batched: one box search per leaf of queries, then exact filtering (what PCQM does).
void BM_LeafBatchedRadius(benchmark::State& state) {
  const Data& d = data();
  const double r = kRadius * double(state.range(0));
  CandidateSet candidates;
  std::vector<Neighbour> out;
  std::size_t queries = 0;
  for (auto _ : state) {
    queries = 0;
    for (const auto& leaf : d.tree->leaves()) {
      if (queries >= kQueries) break;
      candidates.gather(*d.tree, box_of(d.tree->points(), leaf[0], leaf[1]), r * r);
      for (std::uint32_t i = leaf[0]; i < leaf[1]; ++i, ++queries) {
        candidates.radius(d.tree->points()[i], r * r, out);
        benchmark::DoNotOptimize(out.data());
      }
    }
  }
  state.counters["per_query"] = benchmark::Counter(
      double(queries), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// Query order 0 = file order, 1 = tree order; second argument = radius multiple of r.
BENCHMARK(BM_PclFlannRadius)
    ->Args({0, 1})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PclFlannKnn)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KdTreeRadius)->Args({0, 1})->Args({1, 1})->Args({1, 2})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KdTreeKnn)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LeafBatchedRadius)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
