// The protocol's share of a servo tick, side by side (google-benchmark; medians with
// --benchmark_repetitions=9 --benchmark_report_aggregates_only=true):
//   Codec:    encode one command, decode one sample: the host's arithmetic per tick;
//   Device:   the reference device handling one command (the firmware's side, emulated);
//   Tick:     ProtocolDevice::write + read through a loopback link into the reference device:
//             host and device together, no OS transport. Host share ~ Tick - Device.
#include <benchmark/benchmark.h>

#include <array>
#include <memory>

#include "hapticd/device/link/protocol_device.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/servo_convert.hpp"
#include "loopback_link.hpp"

namespace {

namespace proto = hapticd::device::protocol;
using hapticd::device::link::LinkContext;
using hapticd::device::link::ProtocolDevice;
using hapticd::servo::Command;
using hapticd::servo::Sample;

proto::EmulatorConfig emulator_config(int axes) {
    proto::EmulatorConfig c;
    c.sim.axes = axes;
    c.sim.rate_hz = 1000.0;
    return c;
}

Command push(int axes) {
    Command c;
    c.enable = true;
    for (int i = 0; i < axes; ++i) c.force_n[static_cast<std::size_t>(i)] = 0.25 * (i + 1);
    return c;
}

void Codec(benchmark::State& state) {
    const int axes = static_cast<int>(state.range(0));
    proto::EncoderSample reply;
    reply.session = 7;
    reply.command_sequence = 1;
    reply.axes = static_cast<std::uint8_t>(axes);
    std::array<std::byte, proto::kMaxFrameSize> sample_frame{};
    const std::size_t sample_size = proto::encode(reply, sample_frame).size;
    std::array<std::byte, proto::kMaxFrameSize> out{};
    const Command command = push(axes);
    std::uint32_t sequence = 0;
    for (auto _ : state) {
        proto::ForceCommand frame;
        proto::make_force_command(command, axes, 7, ++sequence, frame);
        benchmark::DoNotOptimize(proto::encode(frame, out));
        proto::EncoderSample decoded;
        benchmark::DoNotOptimize(
            proto::decode(std::span<const std::byte>(sample_frame.data(), sample_size), decoded));
        benchmark::DoNotOptimize(proto::to_servo_sample(decoded, sequence, 0));
    }
}

void Device(benchmark::State& state) {
    const int axes = static_cast<int>(state.range(0));
    proto::DeviceEmulator device(emulator_config(axes));
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    std::array<std::byte, proto::DeviceEmulator::kMaxReplySize> reply{};
    const std::uint32_t session = 0x1234;
    device.handle(std::span<const std::byte>(
                      frame.data(), proto::encode(proto::Hello{session, 1, 1}, frame).size),
                  reply);
    std::uint32_t sequence = 0;
    for (auto _ : state) {
        proto::ForceCommand command;
        proto::make_force_command(push(axes), axes, session, ++sequence, command);
        const std::size_t size = proto::encode(command, frame).size;
        benchmark::DoNotOptimize(
            device.handle(std::span<const std::byte>(frame.data(), size), reply));
    }
}

void Tick(benchmark::State& state) {
    const int axes = static_cast<int>(state.range(0));
    hapticd::testing::LoopbackBench bench;
    bench.device = std::make_unique<proto::DeviceEmulator>(emulator_config(axes));
    ProtocolDevice device("loop", [&bench](hapticd::device::TableReader&, const LinkContext&) {
        return std::make_unique<hapticd::testing::LoopbackLink>(bench);
    });
    hapticd::device::DeviceConfig config;
    config.axes = axes;
    config.lockstep = true;
    config.plugin_table_toml = "reconnect = false\n";
    device.open(config);
    const Command command = push(axes);
    Sample sample;
    (void)device.read(sample);
    for (auto _ : state) {
        benchmark::DoNotOptimize(device.write(command));
        benchmark::DoNotOptimize(device.read(sample));
    }
    device.close();
}

BENCHMARK(Codec)->Arg(1)->Arg(3);
BENCHMARK(Device)->Arg(1)->Arg(3);
BENCHMARK(Tick)->Arg(1)->Arg(3);

}  // namespace

BENCHMARK_MAIN();
