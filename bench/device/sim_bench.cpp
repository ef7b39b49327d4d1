// The sim device's share of a lockstep servo tick: one read() and one write(), for 1 and 3
// axes, per operator family (the multi-mode grasp with the most absorbers the sim holds: its
// plant is the largest, 18 states), with and without Coulomb friction (which substeps 32
// times), and with a fractional loop delay.
// Run with --benchmark_repetitions=N --benchmark_report_aggregates_only=true for medians.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "hapticd/device/sim/sim_device.hpp"

namespace {

using hapticd::device::Command;
using hapticd::device::Sample;
using namespace hapticd::device::sim;

SimConfig config(int axes, HumanFamily family, double coulomb_n) {
    SimConfig c;
    c.axes = axes;
    c.clock = SimClock::lockstep;
    c.coulomb_n = coulomb_n;
    for (int i = 0; i < axes; ++i) {
        HumanModel& h = c.human[i];
        h.family = family;
        if (family != HumanFamily::hands_off) h.hand_mass_kg = 0.5;
        if (family == HumanFamily::heavy_hand || family == HumanFamily::stiff_grasp) {
            h.hand_damping_n_s_per_m = 1.0;
        }
        if (family == HumanFamily::stiff_grasp) h.hand_stiffness_n_per_m = 1000.0;
        if (family == HumanFamily::multi_mode_grasp) {
            h.hand_stiffness_n_per_m = 1000.0;
            h.hand_damping_n_s_per_m = 1.0;
            h.mode_count = kMaxOperatorModes;
            for (int k = 0; k < kMaxOperatorModes; ++k) {  // 50 Hz to 6.4 kHz, lightly damped
                const double omega = 2.0 * std::numbers::pi * 50.0 * std::pow(2.0, k);
                h.modes[static_cast<std::size_t>(k)] = {0.01, 0.01 * omega * omega, 0.01};
            }
        }
        if (family == HumanFamily::two_mass_grasp) {
            h.skin_stiffness_n_per_m = 5000.0;
            h.skin_damping_n_s_per_m = 1.0;
            h.arm_stiffness_n_per_m = 300.0;
            h.arm_damping_n_s_per_m = 5.0;
        }
    }
    return c;
}

void lockstep_tick(benchmark::State& state, HumanFamily family, double coulomb_n,
                   double delay_periods = 0.0) {
    const int axes = static_cast<int>(state.range(0));
    SimConfig c = config(axes, family, coulomb_n);
    c.delay_s = delay_periods * c.period_s();
    SimDevice dev;
    dev.open(c);
    Sample sample;
    Command command;
    command.enable = true;
    double phase = 0.0;
    for (auto _ : state) {
        dev.read(sample);
        // A small oscillating force, so the state stays bounded over billions of ticks.
        const double f = 0.5 * std::sin(phase) - 20.0 * dev.plant(0).state().position_m;
        phase += 0.01;
        command.force_n = {f, -f, 0.5 * f};
        dev.write(command);
        benchmark::DoNotOptimize(sample);
    }
    state.SetItemsProcessed(state.iterations());
    state.counters["ns_per_tick"] =
        benchmark::Counter(static_cast<double>(state.iterations()),
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_SimLockstepHandsOff(benchmark::State& s) { lockstep_tick(s, HumanFamily::hands_off, 0.0); }
void BM_SimLockstepStiffGrasp(benchmark::State& s) {
    lockstep_tick(s, HumanFamily::stiff_grasp, 0.0);
}
void BM_SimLockstepTwoMassGrasp(benchmark::State& s) {
    lockstep_tick(s, HumanFamily::two_mass_grasp, 0.0);
}
void BM_SimLockstepMultiModeGrasp(benchmark::State& s) {
    lockstep_tick(s, HumanFamily::multi_mode_grasp, 0.0);
}
void BM_SimLockstepHandsOffCoulomb(benchmark::State& s) {
    lockstep_tick(s, HumanFamily::hands_off, 0.2);
}
// A fractional loop delay: each period is two exact steps, one per piece of the split hold.
void BM_SimLockstepHandsOffDelay(benchmark::State& s) {
    lockstep_tick(s, HumanFamily::hands_off, 0.0, 2.37);
}

BENCHMARK(BM_SimLockstepHandsOff)->Arg(1)->Arg(3);
BENCHMARK(BM_SimLockstepStiffGrasp)->Arg(1)->Arg(3);
BENCHMARK(BM_SimLockstepTwoMassGrasp)->Arg(1)->Arg(3);
BENCHMARK(BM_SimLockstepMultiModeGrasp)->Arg(1)->Arg(3);
BENCHMARK(BM_SimLockstepHandsOffCoulomb)->Arg(1)->Arg(3);
BENCHMARK(BM_SimLockstepHandsOffDelay)->Arg(1)->Arg(3);

/// Realtime clock: read() + write() each read CLOCK_MONOTONIC and advance to now.
void BM_SimRealtimeTick(benchmark::State& state) {
    SimConfig c = config(static_cast<int>(state.range(0)), HumanFamily::stiff_grasp, 0.0);
    c.clock = SimClock::realtime;
    SimDevice dev;
    dev.open(c);
    Sample sample;
    Command command;
    command.enable = true;
    for (auto _ : state) {
        dev.read(sample);
        dev.write(command);
        benchmark::DoNotOptimize(sample);
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SimRealtimeTick)->Arg(1)->Arg(3);

}  // namespace

BENCHMARK_MAIN();
