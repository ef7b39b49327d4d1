// Speed of haptic-tune identify (target: a 10 s log at 1 kHz well under 1 s). Results are
// recorded in docs/benchmarks.md. The runs are the tests' simulated pen display (m 0.1 kg,
// b 2 N s/m, F_c 0.2 N, F_0 0.05 N, 10 µm counts, 0.02 N force noise, 1 N RMS multisine).
#include <benchmark/benchmark.h>

#include <map>
#include <sstream>
#include <string>

#include "hapticd/tune/identification.hpp"
#include "identification_sim_run.hpp"

namespace {

using hapticd::tune::IdentifiedAxis;
using hapticd::tune::TelemetryLog;
namespace testing = hapticd::tune::testing;

/// The daemon's CSV of a simulated run of `seconds`, made once per length.
const std::string& csv(int seconds) {
    static std::map<int, std::string> cache;
    auto it = cache.find(seconds);
    if (it == cache.end()) {
        testing::SimulatedRun run;
        run.duration_s = seconds;
        it = cache.emplace(seconds, testing::daemon_csv(testing::simulate_run(run), 1)).first;
    }
    return it->second;
}

TelemetryLog parse(const std::string& text,
                   const hapticd::tune::TelemetryLogOptions& options = {}) {
    std::istringstream in(text);
    return hapticd::tune::parse_telemetry_log(in, "bench.csv", options);
}

/// identify_axis on a log already read: checks, both Ceres passes, covariance.
void BM_Identify(benchmark::State& state) {
    const TelemetryLog log = parse(csv(static_cast<int>(state.range(0))));
    int iterations = 0;
    for (auto _ : state) {
        const IdentifiedAxis fit = hapticd::tune::identify_axis(log, 0);
        iterations = fit.report.iterations;
        benchmark::DoNotOptimize(fit);
    }
    state.counters["ceres_iterations"] = iterations;
    state.counters["samples"] = static_cast<double>(log.rows());
}
BENCHMARK(BM_Identify)->Arg(2)->Arg(10)->Arg(30)->Unit(benchmark::kMillisecond);

/// Reading the daemon's CSV (10 s, 1 axis, all status columns) from memory: every column
/// kept (the default), or only what identification reads (what haptic-tune identify does).
/// bytes_per_row: the log's memory (TelemetryLog::memory_bytes) per row.
void parse_log(benchmark::State& state, const hapticd::tune::TelemetryLogOptions& options) {
    const std::string& text = csv(static_cast<int>(state.range(0)));
    std::size_t bytes = 0;
    std::size_t rows = 1;
    for (auto _ : state) {
        TelemetryLog log = parse(text, options);
        bytes = log.memory_bytes();
        rows = log.rows();
        benchmark::DoNotOptimize(log);
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
    state.counters["bytes_per_row"] = static_cast<double>(bytes) / static_cast<double>(rows);
    state.counters["file_bytes_per_row"] =
        static_cast<double>(text.size()) / static_cast<double>(rows);
}
void BM_ParseLog(benchmark::State& state) { parse_log(state, {}); }
BENCHMARK(BM_ParseLog)->Arg(10)->Unit(benchmark::kMillisecond);
void BM_ParseLogForIdentification(benchmark::State& state) {
    parse_log(state, hapticd::tune::TelemetryLogOptions::identification());
}
BENCHMARK(BM_ParseLogForIdentification)->Arg(10)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
