// env benchmarks: the god-object's step in the 16-plane box (config/scenes/box-16-planes.toml)
// while the device wanders in and out of it (faces, edges, corners), and the 1-axis demo
// wall's evaluate. Besides google-benchmark's mean, each reports the per-call median and
// p99 (counters p50_ns, p99_ns, from steady_clock around single calls; the clock's own
// cost of ~20 ns is included).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <glm/common.hpp>
#include <random>
#include <string>
#include <vector>

#include "hapticd/env/scene.hpp"

namespace {

using hapticd::env::Vec3;
const std::string kScenes = std::string(HAPTICD_SOURCE_DIR) + "/config/scenes/";

/// Device positions: a random walk with 5 mm steps that reaches 3 cm beyond the box walls.
std::vector<Vec3> box_walk(std::size_t count) {
    std::mt19937_64 rng(42);
    std::normal_distribution<double> jitter(0.0, 0.005);
    std::vector<Vec3> path(count);
    Vec3 x(0.0);
    for (auto& p : path) {
        x = glm::clamp(x + Vec3(jitter(rng), jitter(rng), jitter(rng)), Vec3(-0.08), Vec3(0.08));
        p = x;
    }
    return path;
}

template <typename Call>
void report_percentiles(benchmark::State& state, std::size_t calls, Call call) {
    std::vector<double> ns(calls);
    for (std::size_t i = 0; i < calls; ++i) {
        const auto start = std::chrono::steady_clock::now();
        call(i);
        const auto stop = std::chrono::steady_clock::now();
        ns[i] = std::chrono::duration<double, std::nano>(stop - start).count();
    }
    std::sort(ns.begin(), ns.end());
    state.counters["p50_ns"] = ns[ns.size() / 2];
    state.counters["p99_ns"] = ns[ns.size() * 99 / 100];
    state.counters["max_ns"] = ns.back();
}

void BM_GodObjectStepBox16(benchmark::State& state) {
    const auto scene = hapticd::env::load_scene(kScenes + "box-16-planes.toml", 3);
    auto& god = *scene.admittance;
    const hapticd::env::CouplingGains gains{2000.0, 5.0};
    const std::vector<Vec3> path = box_walk(1 << 16);
    std::size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(god.step(path[i], Vec3(0.0), gains, 1e-3));
        i = (i + 1) & (path.size() - 1);
    }
    report_percentiles(state, path.size(), [&](std::size_t k) {
        benchmark::DoNotOptimize(god.step(path[k], Vec3(0.0), gains, 1e-3));
    });
}
BENCHMARK(BM_GodObjectStepBox16);

void BM_DemoWallEvaluate(benchmark::State& state) {
    const auto scene = hapticd::env::load_scene(kScenes + "demo-wall.toml", 1);
    const auto& wall = *scene.impedance;
    std::vector<Vec3> path(1 << 12);
    for (std::size_t k = 0; k < path.size(); ++k) {
        path[k] = Vec3(0.002 * std::sin(0.01 * static_cast<double>(k)), 0.0, 0.0);  // in and out
    }
    std::size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(wall.evaluate(path[i], Vec3(0.01, 0.0, 0.0)));
        i = (i + 1) & (path.size() - 1);
    }
    report_percentiles(state, path.size(), [&](std::size_t k) {
        benchmark::DoNotOptimize(wall.evaluate(path[k], Vec3(0.01, 0.0, 0.0)));
    });
}
BENCHMARK(BM_DemoWallEvaluate);

}  // namespace

BENCHMARK_MAIN();
