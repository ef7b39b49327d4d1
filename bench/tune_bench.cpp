// Speed of the offline tools: coupling sizing (target: < 20 ms of solver time for one device)
// and the exact-model check (target: < 2 s). Results are recorded in docs/benchmarks.md.
#include <benchmark/benchmark.h>

#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/exact_model.hpp"

namespace {

using hapticd::theory::DeviceModel;
using hapticd::theory::HoldModel;

const DeviceModel kPenDisplay{0.1, 2.0};

void BM_SizeFixedDamping(benchmark::State& state) {
    const double b_c = static_cast<double>(state.range(0)) / 10.0;
    for (auto _ : state) {
        auto s = hapticd::tune::size_impedance_coupling({kPenDisplay, 1000.0, HoldModel::encoder, b_c});
        benchmark::DoNotOptimize(s);
    }
}
// b_c = 0 binds at DC; b_c = 1 N s/m binds at an interior tangency.
BENCHMARK(BM_SizeFixedDamping)->Arg(0)->Arg(10)->Unit(benchmark::kMillisecond);

void BM_SizeOptimizeDamping(benchmark::State& state) {
    const HoldModel model = state.range(0) == 0 ? HoldModel::paper : HoldModel::encoder;
    for (auto _ : state) {
        auto s = hapticd::tune::size_impedance_coupling({kPenDisplay, 1000.0, model, std::nullopt});
        benchmark::DoNotOptimize(s);
    }
}
BENCHMARK(BM_SizeOptimizeDamping)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_CheckEncoder(benchmark::State& state) {
    for (auto _ : state) {
        auto c = hapticd::theory::check_coupling(kPenDisplay, {4000.0, 0.5}, HoldModel::encoder, 1000.0);
        benchmark::DoNotOptimize(c);
    }
}
BENCHMARK(BM_CheckEncoder)->Unit(benchmark::kMillisecond);

void BM_CheckExact(benchmark::State& state) {
    for (auto _ : state) {
        auto c = hapticd::tune::check_exact(kPenDisplay, {4000.0, 0.0}, 1000.0);
        benchmark::DoNotOptimize(c);
    }
}
BENCHMARK(BM_CheckExact)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
