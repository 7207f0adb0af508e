// Micro-benchmarks of the colour core and of CMDM on the reference blob pair (2.5k vertices).
// The end-to-end speed targets are measured by bench/run_benchmarks.sh.
#include <benchmark/benchmark.h>

#include "qm3d/common/color.h"
#include "qm3d/mesh/cmdm.h"
#include "qm3d/mesh/mesh_io.h"

namespace {

const std::filesystem::path kCmdmData = std::filesystem::path(QM3D_SHARED_DATA_DIR) / "reference" / "cmdm";

void BM_SrgbToLab2000hl(benchmark::State& state) {
  const auto table = qm3d::Lab2000hlTable::shared(QM3D_DEFAULT_TABLES);
  qm3d::Rgb rgb{0.2, 0.5, 0.7};
  for (auto _ : state) {
    rgb.r = rgb.r > 0.99 ? 0.0 : rgb.r + 0.001;
    benchmark::DoNotOptimize(table->from_srgb(rgb));
  }
}
BENCHMARK(BM_SrgbToLab2000hl);

void BM_LoadTables(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(qm3d::Lab2000hlTable::load(QM3D_DEFAULT_TABLES));
}
BENCHMARK(BM_LoadTables)->Unit(benchmark::kMillisecond);

void BM_CmdmBlob4(benchmark::State& state) {
  const auto ref = qm3d::mesh::read_mesh(kCmdmData / "blob4_ref.off").mesh;
  const auto dist = qm3d::mesh::read_mesh(kCmdmData / "blob4_bothnoise.off").mesh;
  qm3d::mesh::CmdmOptions o;
  o.data_dir = QM3D_DEFAULT_TABLES;
  for (auto _ : state) benchmark::DoNotOptimize(qm3d::mesh::compute_cmdm(ref, dist, o).score);
}
BENCHMARK(BM_CmdmBlob4)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
