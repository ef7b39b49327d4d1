// Tick compute time of the servo loop (docs/architecture.md §2.11: benchmarks, not timed tests):
// a 1-axis wall scene, a fake device returning a fixed sample, no sleeping. Target: median
// well under 1 us.
#include <benchmark/benchmark.h>

#include <cstdint>

#include "hapticd/servo/servo_loop.hpp"

namespace {

using hapticd::servo::Command;
using hapticd::servo::IoResult;
using hapticd::servo::Mat3;
using hapticd::servo::PenaltyForce;
using hapticd::servo::Sample;
using hapticd::servo::Vec3;

// Always the same sample: the handle 2 mm inside the wall.
struct FixedSampleDevice {
    Sample sample{};
    Command last{};
    IoResult read(Sample& out) noexcept {
        ++sample.sequence;
        out = sample;
        return IoResult::ok;
    }
    IoResult write(const Command& command) noexcept {
        last = command;
        return IoResult::ok;
    }
};

// One plane, x >= 0 free, stiffness and damping inside.
struct OnePlaneWall {
    double stiffness_n_per_m = 5000.0;
    double damping_n_s_per_m = 2.0;
    PenaltyForce evaluate(const Vec3& x, const Vec3& v) const noexcept {
        PenaltyForce out;
        if (x.x < 0.0) {
            out.force_n.x = -stiffness_n_per_m * x.x - damping_n_s_per_m * v.x;
            out.stiffness_n_per_m[0][0] = stiffness_n_per_m;
            out.damping_n_s_per_m[0][0] = damping_n_s_per_m;
        }
        return out;
    }
    void commit(const Vec3&, const Vec3&) noexcept {}
    void reset(const Vec3&) noexcept {}
};

// A swept handle (in and out of contact) stresses the Newton solve more than a fixed one.
struct SweepDevice {
    Sample sample{};
    std::int64_t step = 7;
    IoResult read(Sample& out) noexcept {
        sample.encoder_counts[0] += step;
        if (sample.encoder_counts[0] > 3000 || sample.encoder_counts[0] < -3000) step = -step;
        ++sample.sequence;
        out = sample;
        return IoResult::ok;
    }
    IoResult write(const Command&) noexcept { return IoResult::ok; }
};

hapticd::servo::ServoConfig bench_config() {
    hapticd::servo::ServoConfig config;
    config.axes = 1;
    config.counts_per_meter = 1e6;
    config.coupling = {.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 2.0};
    config.safety.max_force_n = 10.0;
    config.safety.soft_start = {.still_speed_mps = 1.0, .still_time_s = 0.0, .ramp_time_s = 0.0};
    config.safety.passivity.mode = hapticd::servo::PassivityMode::control;
    config.realtime.mode = hapticd::servo::RealtimeMode::off;
    return config;
}

template <typename Device>
void tick_wall_scene(benchmark::State& state, Device& device) {
    OnePlaneWall wall;
    hapticd::servo::TelemetryRing ring(1 << 12);
    hapticd::servo::ServoLoop<Device, OnePlaneWall> loop(device, wall, bench_config(), &ring);
    hapticd::servo::TelemetryRecord drained;
    std::int64_t n = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(loop.tick());
        if ((++n & 1023) == 0) {
            state.PauseTiming();
            while (ring.try_pop(drained)) {
            }
            state.ResumeTiming();
        }
    }
    state.counters["median_compute_us"] = loop.stats().compute.quantile_us(0.5);
    state.counters["p99_compute_us"] = loop.stats().compute.quantile_us(0.99);
}

void BM_ServoTick_OneAxisWall_FixedSample(benchmark::State& state) {
    FixedSampleDevice device;
    device.sample.encoder_counts[0] = -2000;
    tick_wall_scene(state, device);
}
BENCHMARK(BM_ServoTick_OneAxisWall_FixedSample);

void BM_ServoTick_OneAxisWall_Sweep(benchmark::State& state) {
    SweepDevice device;
    tick_wall_scene(state, device);
}
BENCHMARK(BM_ServoTick_OneAxisWall_Sweep);

}  // namespace

BENCHMARK_MAIN();
