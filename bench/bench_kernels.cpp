// Per-call cost of the law kernels and the neighbour search (Google Benchmark). Used when tuning a
// law; the engine's throughput is measured by bench_engine (bench/run).
#include <benchmark/benchmark.h>

#include "breccia/core/rng.hpp"
#include "breccia/engine/neighbour_grid.hpp"
#include "breccia/law/registry.hpp"
#include "breccia/sample/lattice.hpp"

using namespace breccia;

namespace {

PairGeometry loaded_geometry(double overlap) {
  return pair_geometry({0, 0, 0}, 0.5e-3, Vec3{0.8, 0.35, -0.2} * (1e-3 - overlap) / 0.9, 0.5e-3,
                       {1e-3, 0, 0}, {0.1, 0.2, 0.3}, {0, 2e-3, 0}, {-0.2, 0.1, 0}, 1.4e-6, 1.4e-6,
                       false, 1.0);
}

// A loaded bond: installed at the geometry, then evaluated with the grains turned a little (for
// total laws) and moving (for incremental ones).
template <class Law>
void BM_Bond(benchmark::State& st) {
  const typename Law::Params p = Law::example_params();
  const PairGeometry g0 = pair_geometry({0, 0, 0}, 0.5e-3, unit(Vec3{0.8, 0.35, -0.2}) * 1e-3,
                                        0.5e-3, {}, {}, {}, {}, 1.4e-6, 1.4e-6, false, 1.0);
  typename Law::State s = Law::install(p, g0, {}, 1, 1);
  const PairGeometry g = loaded_geometry(0.0);
  BondFailure warm;
  Law::compute(p, s, g, {}, 1e-12, warm);  // an incremental law's first step adds nothing
  const BodyFrames turned{from_axis_angle({0.2, 1, 0.3}, 1e-5),
                          from_axis_angle({1, 0, 0.4}, -2e-5)};
  for (auto _ : st) {
    BondFailure f;
    benchmark::DoNotOptimize(Law::compute(p, s, g, turned, 1e-12, f));
  }
}
BENCHMARK(BM_Bond<ParallelBond>);
BENCHMARK(BM_Bond<BrittleBeam>);

template <class Law>
void BM_Contact(benchmark::State& st) {
  const typename Law::Params p = Law::example_params();
  const PairGeometry g = loaded_geometry(1e-6);
  typename Law::State s{};
  PairDissipation d;
  for (auto _ : st) benchmark::DoNotOptimize(Law::compute(p, s, g, 1e-12, d));
}
BENCHMARK(BM_Contact<LinearContact>);
BENCHMARK(BM_Contact<HertzMindlin>);

void BM_PairGeometry(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(loaded_geometry(1e-6));
}
BENCHMARK(BM_PairGeometry);

void BM_NeighbourSearchFcc(benchmark::State& st) {
  const ParticleStore ps = fcc_block(20, 20, 20, 0.5e-3, 2650);
  PairList list;
  for (auto _ : st) build_neighbour_pairs(ps.pos_rad, 2e-4, false, list);
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(ps.size()));
}
BENCHMARK(BM_NeighbourSearchFcc)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
