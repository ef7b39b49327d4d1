// Lockstep throughput of the 1-axis demo wall in contact (the target in docs/benchmarks.md,
// "Lockstep throughput": more than 500,000 ticks per second, 500x real time at 1 kHz):
// ServoLoop::run() as hapticd --lockstep runs it, the sim pacing the loop, in batches of
// kTicksPerRun. Wall-clock time; items_per_second is ticks per second and x_realtime is
// virtual seconds per second.
//
// Telemetry variants:
//   no_ring      hapticd --lockstep (no --log): no records pushed
//   ring_popped  records pushed into the daemon's lockstep ring (2^14) and popped by a thread
//                that polls like the telemetry writer (drain, sleep 250 us), without
//                formatting; lossless back-pressure on: the cost of producing telemetry
//   csv_writer   hapticd --lockstep --log /dev/null: the daemon's TelemetryWriter formats
//                every record as CSV; back-pressure makes the loop wait for it
// With a consumer thread both cores are busy; another process on them shows up here.
#include <benchmark/benchmark.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>

#include "full_stack.hpp"
#include "hapticd/daemon/telemetry_writer.hpp"
#include "hapticd/servo/telemetry_ring.hpp"

namespace {

using hapticd::bench::DaemonLoop;
using hapticd::bench::FullStack;
using hapticd::env::ImpedanceEnvironment;
using hapticd::servo::TelemetryRing;

constexpr std::uint64_t kTicksPerRun = 20000;          // 20 s of virtual time per iteration
constexpr std::size_t kLockstepRingRecords = 1 << 14;  // as src/daemon/run_telemetry.hpp

enum class Telemetry { no_ring, ring_popped, csv_writer };

/// Pops and discards records the way TelemetryWriter polls, until stopped.
class RingPopper {
  public:
    explicit RingPopper(TelemetryRing& ring)
        : thread_([this, &ring] {
              hapticd::servo::TelemetryRecord record;
              while (!done_.load(std::memory_order_acquire)) {
                  while (ring.try_pop(record)) benchmark::DoNotOptimize(record);
                  std::this_thread::sleep_for(std::chrono::microseconds(250));
              }
          }) {}
    ~RingPopper() {
        done_.store(true, std::memory_order_release);
        thread_.join();
    }
    RingPopper(const RingPopper&) = delete;
    RingPopper& operator=(const RingPopper&) = delete;

  private:
    std::atomic<bool> done_{false};
    std::thread thread_;
};

void BM_LockstepRun(benchmark::State& state, Telemetry telemetry) {
    const bool logging = telemetry != Telemetry::no_ring;
    FullStack stack(hapticd::bench::kDemoWall1Axis, /*lossless_log=*/logging);
    std::unique_ptr<TelemetryRing> ring;
    std::unique_ptr<RingPopper> popper;
    std::unique_ptr<hapticd::daemon::TelemetryWriter> writer;
    if (logging) ring = std::make_unique<TelemetryRing>(kLockstepRingRecords);
    if (telemetry == Telemetry::ring_popped) popper = std::make_unique<RingPopper>(*ring);
    if (telemetry == Telemetry::csv_writer) {
        writer = std::make_unique<hapticd::daemon::TelemetryWriter>(*ring, "/dev/null", 1);
        writer->start();
    }
    {
        DaemonLoop<ImpedanceEnvironment> loop(*stack.device, *stack.scene.impedance, stack.servo,
                                              ring.get());
        std::atomic<bool> stop{false};
        (void)loop.run(stop, hapticd::bench::kWarmUpTicks);
        if (!stack.scenario.in_contact(loop.last_record())) {
            state.SkipWithError("the handle did not reach the wall");
        }
        for (auto _ : state) {
            if (loop.run(stop, kTicksPerRun) != hapticd::servo::RunExit::tick_limit) {
                state.SkipWithError("the lockstep run ended on a fault");
                break;
            }
        }
        if (!stack.scenario.in_contact(loop.last_record())) {
            state.SkipWithError("the handle left the wall while measured");
        }
        const auto ticks = static_cast<double>(state.iterations() * kTicksPerRun);
        state.SetItemsProcessed(static_cast<std::int64_t>(ticks));
        state.counters["x_realtime"] =
            benchmark::Counter(ticks / stack.servo.rate_hz, benchmark::Counter::kIsRate);
        state.counters["telemetry_dropped"] = ring ? static_cast<double>(ring->dropped()) : 0.0;
    }
    popper.reset();
    if (writer) writer->finish();
}
BENCHMARK_CAPTURE(BM_LockstepRun, no_ring, Telemetry::no_ring)->UseRealTime();
BENCHMARK_CAPTURE(BM_LockstepRun, ring_popped, Telemetry::ring_popped)->UseRealTime();
BENCHMARK_CAPTURE(BM_LockstepRun, csv_writer, Telemetry::csv_writer)->UseRealTime();

}  // namespace
