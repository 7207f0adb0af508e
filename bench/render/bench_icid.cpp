// iCID of the 18 view pairs of a CMDM stimulus at 256² (the CMDM report's protocol; the shared
// reference views of blob4_geonoise), with 1 and 2 threads, the appearance model on (default)
// and off. Target (issue 40): the 18 pairs at least 50x faster than the authors' MATLAB code
// under Octave (~10 s uncontended, SPEC-ICID "Timings"), i.e. well under 0.2 s.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <vector>

#include "qm3d/render/icid.h"

namespace {

const std::filesystem::path kViews =
    std::filesystem::path(QM3D_SHARED_DATA_DIR) / "reference" / "icid" / "views" / "blob4_geonoise";

struct Pair {
  qm3d::render::RgbImage reference, distorted;
};

const std::vector<Pair>& view_pairs() {
  static const std::vector<Pair> pairs = [] {
    std::vector<Pair> out;
    for (int i = 0; i < 18; ++i) {
      char name[64];
      std::snprintf(name, sizeof name, "view_%02d_", i);
      out.push_back({qm3d::render::read_rgb_image(kViews / (std::string(name) + "reference.png")),
                     qm3d::render::read_rgb_image(kViews / (std::string(name) + "distorted.png"))});
    }
    return out;
  }();
  return pairs;
}

void run_18_views(benchmark::State& state, bool iam) {
  const auto table =
      qm3d::Lab2000hlTable::shared(std::filesystem::path(QM3D_DEFAULT_TABLES) / "icid");
  qm3d::render::IcidOptions o;
  o.iam = iam;
  o.threads = static_cast<int>(state.range(0));
  const auto& pairs = view_pairs();
  for (auto _ : state) {
    double sum = 0;
    for (const Pair& p : pairs) sum += qm3d::render::icid(p.reference, p.distorted, *table, o).icid;
    benchmark::DoNotOptimize(sum);
  }
}

void BM_Icid18Views256(benchmark::State& state) { run_18_views(state, true); }
BENCHMARK(BM_Icid18Views256)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Icid18Views256NoIam(benchmark::State& state) { run_18_views(state, false); }
BENCHMARK(BM_Icid18Views256NoIam)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

/// As `qm3d icid` computes them: the view pairs in parallel on `threads` threads, each pair on one.
void BM_Icid18ViewsInParallel(benchmark::State& state) {
  const auto table =
      qm3d::Lab2000hlTable::shared(std::filesystem::path(QM3D_DEFAULT_TABLES) / "icid");
  qm3d::render::IcidOptions o;
  o.threads = 1;
  const auto& pairs = view_pairs();
  const int n = static_cast<int>(pairs.size());
  std::vector<double> scores(pairs.size());
  for (auto _ : state) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(static_cast <int>(state.range(0)))
    for (int i = 0; i < n; ++i) {
      scores[i] = qm3d::render::icid(pairs[i].reference, pairs[i].distorted, *table, o).icid;
    }
    benchmark::DoNotOptimize(scores.data());
  }
}
BENCHMARK(BM_Icid18ViewsInParallel)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->Arg(8)
    ->Arg(16)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
