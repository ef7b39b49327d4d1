// Full-stack servo tick: hapticd's ServoLoop over the dlopen()ed `sim` plugin in lockstep,
// with the scene loaded from config/scenes/ and the settings from the daemon's embedded
// default config (full_stack.hpp), the handle held in contact. Targets (docs/benchmarks.md):
//   demo wall, 1 axis:           tick compute median < 1 us, p99 < 3 us
//   box-16-planes, 3 axes:       tick compute p99 < 5 us
// Time per iteration is one ServoLoop::tick(). The counters p50/p99/p999/max_compute_us
// are the loop's own compute time (TelemetryRecord::compute_us, exactly what hapticd's
// summary reports as tick_compute_us: from the tick's first clock read to the command
// written, device read() and write() included), collected over every timed tick.
// BM_ServoTick/external_wall_1axis is demo_wall_1axis's contact with the wall rendered by an
// external world ([external], free-running, passivity = "control", between_updates
// "extrapolate"; external_wall_hold_1axis with "hold"): the world's side (ExternalWorld,
// full_stack.hpp) writes an update through a second mapping of the channel every 10th tick,
// from this thread between ticks. compute_us is the tick alone; the time per iteration
// includes the world's update (one in 10 iterations; BM_ExternalWorldUpdate alone). The
// world's block stays in this core's cache: a world on another core adds the cache-line
// transfers, which bench/external_latency.py's real run sees in hapticd's summary.
// BM_SimReadWrite is the device's share of a tick and BM_MonotonicClockNow the cost of one
// of the two clock reads that measure compute_us; the servo's own share is the difference.
//
// Run: daemon_bench --benchmark_repetitions=9 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "full_stack.hpp"
#include "hapticd/env/external_channel.hpp"
#include "hapticd/env/external_world.h"
#include "hapticd/servo/pacing.hpp"
#include "hapticd/servo/tick_stats.hpp"

namespace {

using hapticd::bench::DaemonLoop;
using hapticd::bench::ExternalScenario;
using hapticd::bench::ExternalWorld;
using hapticd::bench::FullStack;
using hapticd::bench::Scenario;
using hapticd::bench::ScratchDir;

void report_compute_quantiles(benchmark::State& state,
                              const hapticd::servo::DurationHistogram& compute) {
    state.counters["p50_compute_us"] = compute.quantile_us(0.5);
    state.counters["p99_compute_us"] = compute.quantile_us(0.99);
    state.counters["p999_compute_us"] = compute.quantile_us(0.999);
    state.counters["max_compute_us"] = compute.max_us();
}

template <typename Environment>
void tick_in_contact(benchmark::State& state, FullStack& stack, Environment& environment) {
    // No telemetry ring: hapticd without --log (BM_LockstepRun measures the ring).
    DaemonLoop<Environment> loop(*stack.device, environment, stack.servo);
    if (!warm_up_into_contact(loop, stack.scenario)) {
        state.SkipWithError("the handle did not reach the scenario's contact");
        return;
    }
    hapticd::servo::DurationHistogram compute;  // this run's ticks only, not the warm-up
    for (auto _ : state) {
        const hapticd::servo::TelemetryRecord& record = loop.tick();
        compute.record(std::llround(record.compute_us * 1e3));
    }
    if (!stack.scenario.in_contact(loop.last_record())) {
        state.SkipWithError("the handle left the scenario's contact while measured");
        return;
    }
    state.SetItemsProcessed(state.iterations());
    report_compute_quantiles(state, compute);
    state.counters["contact_force_n"] = hapticd::bench::force_norm_n(loop.last_record());
}

void BM_ServoTick(benchmark::State& state, const Scenario* scenario) {
    FullStack stack(*scenario);
    hapticd::bench::with_environment(
        stack.scene, [&](auto& environment) { tick_in_contact(state, stack, environment); });
}
BENCHMARK_CAPTURE(BM_ServoTick, demo_wall_1axis, &hapticd::bench::kDemoWall1Axis);
BENCHMARK_CAPTURE(BM_ServoTick, box_16_planes_3axis, &hapticd::bench::kBox16Planes3Axis);
BENCHMARK_CAPTURE(BM_ServoTick, god_object_sphere_3axis, &hapticd::bench::kGodObjectSphere3Axis);
BENCHMARK_CAPTURE(BM_ServoTick, virtual_mass_3axis, &hapticd::bench::kVirtualMass3Axis);

/// An [external] scene's stack, its channel in a scratch directory (as the daemon's is beside
/// its socket), and the world's side mapped on it.
struct ExternalStack {
    explicit ExternalStack(const ExternalScenario& external)
        : stack(external.scenario, external.scene_text,
                {.external_channel = scratch.path() + "/bench.world", .external_group = ""}),
          world(*stack.scene.external) {}

    ScratchDir scratch;  // removed last
    FullStack stack;
    ExternalWorld world;
};

// Same name, so that the external world's row sits with the built-in scenes'.
void BM_ServoTick(benchmark::State& state, const ExternalScenario* external) {
    ExternalStack setup(*external);
    FullStack& stack = setup.stack;
    ExternalWorld& world = setup.world;
    hapticd::env::AdmittanceEnvironment& environment = *stack.scene.admittance;
    DaemonLoop<hapticd::env::AdmittanceEnvironment> loop(*stack.device, environment, stack.servo);
    // The world writes after every world_every_ticks-th tick; the next tick takes it.
    const auto every = static_cast<std::uint64_t>(external->world_every_ticks);
    std::uint64_t ticks = 0;
    std::uint64_t missed = 0;  // daemon's block caught in a write: never, on one thread
    for (int i = 0; i < hapticd::bench::kWarmUpTicks; ++i) {
        (void)loop.tick();
        if (++ticks % every == 0 && !world.update()) ++missed;
    }
    const auto live = [&] {
        const hapticd::servo::EnvironmentPortReport port = environment.port_report();
        return port.world_state == HAPTICD_WORLD_LIVE && port.update + 1 >= world.updates() &&
               port.rejected_updates == 0 && port.stale_episodes == 0;
    };
    if (!stack.scenario.in_contact(loop.last_record()) || !live()) {
        state.SkipWithError("the handle did not reach the external wall's contact, live");
        return;
    }
    const std::uint64_t updates_before = world.updates();
    hapticd::servo::DurationHistogram compute;  // this run's ticks only, not the warm-up
    for (auto _ : state) {
        const hapticd::servo::TelemetryRecord& record = loop.tick();
        compute.record(std::llround(record.compute_us * 1e3));
        if (++ticks % every == 0 && !world.update()) ++missed;
    }
    if (!stack.scenario.in_contact(loop.last_record()) || !live() || missed != 0) {
        state.SkipWithError(
            "the handle left the external wall's contact, or the world was not "
            "live, while measured");
        return;
    }
    state.SetItemsProcessed(state.iterations());
    report_compute_quantiles(state, compute);
    state.counters["contact_force_n"] = hapticd::bench::force_norm_n(loop.last_record());
    state.counters["world_updates"] = static_cast<double>(world.updates() - updates_before);
    state.counters["tool_um"] = loop.last_record().xe_m[0] * 1e6;
    state.counters["energy_removed_j"] = environment.port_report().energy_removed_j;
}
BENCHMARK_CAPTURE(BM_ServoTick, external_wall_1axis, &hapticd::bench::kExternalWall1Axis);
BENCHMARK_CAPTURE(BM_ServoTick, external_wall_hold_1axis, &hapticd::bench::kExternalWallHold1Axis);

// The device's share: read() + write() through the plugin's Device (virtual calls), the
// same sim table, a constant 2 N command. The sim's cost does not depend on its state
// (one matrix-vector product per axis and period, docs/sim-device.md).
void BM_SimReadWrite(benchmark::State& state, const Scenario* scenario) {
    FullStack stack(*scenario);
    hapticd::device::Device& device = *stack.device;
    hapticd::servo::Sample sample;
    hapticd::servo::Command command;
    command.enable = true;
    command.force_n = {-2.0, -2.0, -2.0};
    for (auto _ : state) {
        benchmark::DoNotOptimize(device.read(sample));
        benchmark::DoNotOptimize(device.write(command));
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_SimReadWrite, 1axis, &hapticd::bench::kDemoWall1Axis);
BENCHMARK_CAPTURE(BM_SimReadWrite, 3axis, &hapticd::bench::kBox16Planes3Axis);

// One CLOCK_MONOTONIC read (vDSO; this VM's clocksource is kvm-clock). A tick makes two to
// time itself, and compute_us contains about one of them.
void BM_MonotonicClockNow(benchmark::State& state) {
    hapticd::servo::MonotonicClock clock;
    for (auto _ : state) benchmark::DoNotOptimize(clock.now_ns());
}
BENCHMARK(BM_MonotonicClockNow);

// The world's side of one update, alone (the share of BM_ServoTick/external_wall_1axis's time
// per iteration that is not the tick: one of these every 10 ticks): read the daemon's block,
// write the world's. A channel with no daemon ticking it: the same words every time.
void BM_ExternalWorldUpdate(benchmark::State& state) {
    ScratchDir scratch;
    std::string note;
    hapticd::env::ExternalChannel channel(scratch.path() + "/bench.world",
                                          hapticd::env::ChannelShape{}, "", note);
    ExternalWorld world(channel.path());
    for (auto _ : state) benchmark::DoNotOptimize(world.update());
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ExternalWorldUpdate);

}  // namespace

BENCHMARK_MAIN();
