// Speed of the offline tools: coupling sizing (target: < 20 ms of solver time for one device),
// the passive check (target: < 1 ms) and the exact-model check (target: < 2 s). Results are
// recorded in docs/benchmarks.md.
#include <benchmark/benchmark.h>

#include <cmath>

#include "hapticd/theory/admittance_passive.hpp"
#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/tune/admittance_sizing.hpp"
#include "hapticd/tune/class_check.hpp"
#include "hapticd/tune/class_proof.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/exact_admittance.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "operator_classes.hpp"

namespace {

using hapticd::theory::DeviceModel;
using hapticd::theory::HoldModel;

const DeviceModel kPenDisplay{0.1, 2.0};

void BM_SizeFixedDamping(benchmark::State& state) {
    const double b_c = static_cast<double>(state.range(0)) / 10.0;
    for (auto _ : state) {
        auto s =
            hapticd::tune::size_impedance_coupling({kPenDisplay, 1000.0, HoldModel::encoder, b_c});
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
        auto c =
            hapticd::theory::check_coupling(kPenDisplay, {4000.0, 0.5}, HoldModel::encoder, 1000.0);
        benchmark::DoNotOptimize(c);
    }
}
BENCHMARK(BM_CheckEncoder)->Unit(benchmark::kMillisecond);

// The passive model with a delay in hundredths of a period: 0 and 100 are closed forms,
// 50 takes M(θ)'s one-dimensional maximum at every grid point.
void BM_CheckPassive(benchmark::State& state) {
    const hapticd::theory::LoopModel model{HoldModel::passive, state.range(0) / 100.0};
    for (auto _ : state) {
        auto c = hapticd::theory::check_coupling(kPenDisplay, {1000.0, 0.2}, model, 1000.0);
        benchmark::DoNotOptimize(c);
    }
}
BENCHMARK(BM_CheckPassive)->Arg(0)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond);

// Sizing under the passive model: b_c = 0 and the optimised pair, no delay and half a period.
void BM_SizePassive(benchmark::State& state) {
    const hapticd::theory::LoopModel model{HoldModel::passive, state.range(0) / 100.0};
    const std::optional<double> damping =
        state.range(1) == 0 ? std::optional<double>(0.0) : std::nullopt;
    for (auto _ : state) {
        auto s = hapticd::tune::size_impedance_coupling({kPenDisplay, 1000.0, model, damping});
        benchmark::DoNotOptimize(s);
    }
}
BENCHMARK(BM_SizePassive)
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({50, 0})
    ->Args({50, 1})
    ->Unit(benchmark::kMillisecond);

// The whole exact check: the default sweep and the adversaries synthesised for the design,
// with a delay in hundredths of a period.
void BM_CheckExact(benchmark::State& state) {
    const double delay = state.range(0) / 100.0;
    for (auto _ : state) {
        auto c = hapticd::tune::check_exact(kPenDisplay, {900.0, 0.0}, 1000.0, delay);
        benchmark::DoNotOptimize(c);
    }
}
BENCHMARK(BM_CheckExact)->Arg(0)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond)->Iterations(3);

hapticd::tune::StabilityAssumption rigid_wall_scene() {
    hapticd::tune::StabilityAssumption a;
    a.environments.scene = {{hapticd::tune::EnvironmentModel::rigid_wall(), "proxy plane"}};
    return a;
}

// The exact check against the pen-grip class (the class search), every passive environment
// (arg 0) or a rigid-wall scene (arg 1), at k_c = 5000 N/m, b_c = 1 N s/m.
void BM_CheckClass(benchmark::State& state) {
    hapticd::tune::StabilityAssumption a =
        state.range(0) == 0 ? hapticd::tune::StabilityAssumption{} : rigid_wall_scene();
    a.operators = hapticd::testing::pen_grip_class();
    for (auto _ : state) {
        auto c = hapticd::tune::check_exact(kPenDisplay, {5000.0, 1.0}, 1000.0, a, 0.0);
        benchmark::DoNotOptimize(c);
    }
}
BENCHMARK(BM_CheckClass)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);

// Sizing for the class: a bisection on the class check (b_c = 1 N s/m, no delay).
void BM_SizeClass(benchmark::State& state) {
    hapticd::tune::StabilityAssumption a;
    a.operators = hapticd::testing::pen_grip_class();
    for (auto _ : state) {
        auto l = hapticd::tune::exact_stiffness_limit(kPenDisplay, {0.0, 1.0}, 1000.0, a, 0.0);
        benchmark::DoNotOptimize(l);
    }
}
BENCHMARK(BM_SizeClass)->Unit(benchmark::kMillisecond)->Iterations(1);

// The class's proof (tune/class_proof.hpp) for the pen-grip class, b_c = 1 N s/m, with a delay
// in tenths of a period: the prover's coupling-independent bound (arg 1 = 0) and the bisection
// on k_c that size runs (arg 1 = 1).
void BM_ClassProof(benchmark::State& state) {
    const double delay = state.range(0) / 10.0;
    for (auto _ : state) {
        const hapticd::tune::ClassProver prover(kPenDisplay, hapticd::testing::pen_grip_class(),
                                                1000.0, delay);
        if (state.range(1) == 1) {
            auto l = prover.stiffness_limit({0.0, 1.0}, 0.0);
            benchmark::DoNotOptimize(l);
        }
        benchmark::DoNotOptimize(prover);
    }
}
BENCHMARK(BM_ClassProof)
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({10, 1})
    ->Args({99, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

// The passive model against a scene (a rigid wall, one period of delay).
void BM_CheckPassiveScene(benchmark::State& state) {
    const auto scene = rigid_wall_scene().environments.scene;
    for (auto _ : state) {
        auto c = hapticd::tune::check_passive_scene(kPenDisplay, {1200.0, 0.0}, 1000.0, scene, 1.0);
        benchmark::DoNotOptimize(c);
    }
}
BENCHMARK(BM_CheckPassiveScene)->Unit(benchmark::kMillisecond);

// The admittance display (docs/benchmarks.md, "The admittance display"): the exact admittance
// check of one design (the default sweep, 637 operators x 87 environments) with a delay in
// hundredths of a period, and the exact sizing (a bisection on it with cutting planes). Device:
// m = 2 kg, b = 5 N s/m, k_p = 2 N s/m, a pure-mass coupling, 1 kHz.
const DeviceModel kArm{2.0, 5.0};

void BM_CheckExactAdmittance(benchmark::State& state) {
    const hapticd::tune::AdmittanceDesign design{
        kArm, {2.0, 0.0}, {30.0, INFINITY}, 1000.0, state.range(0) / 100.0};
    for (auto _ : state) {
        auto c = hapticd::tune::check_exact_admittance(design);
        benchmark::DoNotOptimize(c);
    }
}
BENCHMARK(BM_CheckExactAdmittance)
    ->Arg(0)
    ->Arg(50)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

void BM_SizeAdmittanceExact(benchmark::State& state) {
    const hapticd::tune::ExactAdmittanceSizingRequest request{
        kArm, {2.0, 0.0}, 1000.0, state.range(0) / 100.0};
    for (auto _ : state) {
        auto s = hapticd::tune::size_admittance_coupling_exact(request);
        benchmark::DoNotOptimize(s);
    }
}
BENCHMARK(BM_SizeAdmittanceExact)->Arg(0)->Arg(100)->Unit(benchmark::kMillisecond)->Iterations(1);

// The passive model with a force filter (admittance_passive.hpp): one check of a pure damper
// over the 4096 + 256 + 64 frequencies, sign only (what the bisection runs) and minimised, and
// the lightest pure damper (a bisection of about 27 checks). Argument: f_aa in Hz.
void BM_CheckFilteredAdmittancePassive(benchmark::State& state) {
    const hapticd::theory::ForceSensorFilter filter{static_cast<double>(state.range(0))};
    const bool minimise = state.range(1) != 0;
    for (auto _ : state) {
        auto c = hapticd::theory::check_filtered_admittance_passive(
            kArm, {2.0, 0.0}, filter, {INFINITY, 300.0}, 1e-3, 0.0, !minimise);
        benchmark::DoNotOptimize(c);
    }
}
BENCHMARK(BM_CheckFilteredAdmittancePassive)
    ->Args({100, 0})
    ->Args({100, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

void BM_LightestPassiveDamper(benchmark::State& state) {
    const hapticd::tune::PassiveAdmittanceSizingRequest request{
        kArm, {2.0, 0.0}, 1000.0,
        0.0,  INFINITY,   hapticd::theory::ForceSensorFilter{static_cast<double>(state.range(0))}};
    for (auto _ : state) {
        auto b = hapticd::tune::lightest_passive_damper(request);
        benchmark::DoNotOptimize(b);
    }
}
BENCHMARK(BM_LightestPassiveDamper)
    ->Arg(50)
    ->Arg(100)
    ->Arg(200)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
