// Benchmarks of the PCL point map: one 30 Hz XPLORER slab insert into a map
// of ~1e6 points, the 1 cm voxel filter, and PLY export of 1e6 points.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include "mapping_pcl/point_map.hpp"
#include "mapping_pcl/xplorer_stamping.hpp"

using namespace mapping_pcl;

namespace {
PointMap million(double auto_growth) {
  MapParams p;
  p.auto_filter_growth = auto_growth;
  PointMap m(p);
  std::vector<Vec3> pts;
  pts.reserve(1000000);
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j)
      for (int k = 0; k < 100; ++k) pts.emplace_back(i * 0.005, j * 0.005, k * 0.005);
  m.insert(pts);
  return m;
}
}  // namespace

static void BM_SlabInsert1M(benchmark::State& state) {
  PointMap m = million(0.0);
  XplorerContactMapper mapper(XplorerMapParams{}, m);
  ContactSample s;
  s.position = Vec3(0.0, 0.0, 0.7);
  s.height = 0.7;
  s.force_body = Eigen::Vector2d(-2.0, 0.0);
  for (auto _ : state) {
    s.t += 1.0 / 30.0;
    s.position.y() += 0.005;
    benchmark::DoNotOptimize(mapper.update(s));
  }
  state.counters["map_points"] = static_cast<double>(m.size());
}
BENCHMARK(BM_SlabInsert1M)->Unit(benchmark::kMicrosecond);

static void BM_VoxelFilter1M(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    PointMap m = million(0.0);
    state.ResumeTiming();
    m.voxel_filter(0.01);
    benchmark::DoNotOptimize(m.size());
  }
}
BENCHMARK(BM_VoxelFilter1M)->Unit(benchmark::kMillisecond)->Iterations(3);

static void BM_PlyExport1M(benchmark::State& state) {
  const PointMap m = million(0.0);
  const PlyFormat f = state.range(0) ? PlyFormat::kBinaryLittleEndian : PlyFormat::kAscii;
  const std::string path = "bench_point_map_export.ply";
  for (auto _ : state) write_ply(path, m.cloud(), f);
  std::remove(path.c_str());
  state.SetLabel(state.range(0) ? "binary_little_endian" : "ascii");
}
BENCHMARK(BM_PlyExport1M)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);

BENCHMARK_MAIN();
