// SerialFaultCampaign (docs/reliability.md): the seeded fault campaign of
// tests/hil/fault_campaign_test.cpp with the faults on the wire. The servo loop runs as the daemon
// runs a lockstep device (ServoLoop::run on the serial plugin loaded by name, the scene's penalty
// environment, a stiff grasp into a wall, link recovery on or off:
// tests/support/fault_campaign.hpp), and the reference device (DeviceEmulator, the same physics)
// answers behind a pseudo-terminal (pty_device.hpp). Between the two a line tap injects, at random
// seeded requests:
//   replies:  1-5 bit flips in a frame (which the CRC must catch: HD >= 6), 1-3 bit flips in
//             the line's bytes (COBS code bytes and delimiters too), CRC-preserving changes
//             of a sample's session, sequence numbers, counts, time, status or fault bits
//             (re-encoded: what no CRC can catch), truncated frames,
//             dropped frames, duplicated frames, replays of an older frame (stale sequence
//             numbers, earlier sessions' too), a frame held back behind the next answer
//             (reordered), a burst of garbage before, inside or after a frame, a delay of up
//             to twice the reply timeout, and a device that stops answering for a while;
//   requests: bit flips, truncation, a request lost or sent twice;
//   device:   hung for some requests (its clock runs on), or unplugged for some ticks and
//             plugged in again on a new pty behind the same path.
// Checked on every tick: the invariants of fault_campaign.hpp (|F| <= max_force; zero force
// with a fault latched, so in the tick that detects it, and on an unknown interval; finite);
// device_lost in the tick the device is unplugged; each sample the host took is a frame that
// went out (or a forged one), never one taken before and never older than the last of its
// session, so a duplicated, replayed or old frame is never a new sample; its velocity is the
// step since the last sample over the interval of the device's clock (so never from a frame
// taken twice). On every sequence: no hang (a watchdog names the seed), the outcome the
// configuration says (fault_campaign.hpp), with reconnect a device that never left (and that
// the host never lost) always recovers, and the device holds zero force after the run
// (within its watchdog if the link was gone).
//
// Real time on the host's side, lockstep on the device's: the emulator's clock advances one
// period per command, so a sequence's faults fall on the same requests and periods however
// the machine is loaded; only the wall-clock parts vary (a reply timeout, the reconnect).
// ctest runs HAPTICD_PTY_CAMPAIGN_SEQUENCES sequences (default 100, about 30 s); the record in
// docs/reliability.md ran more. HAPTICD_PTY_CAMPAIGN_SEED=S replays sequence S alone:
//   HAPTICD_PTY_CAMPAIGN_SEQUENCES=2000 build/release/bin/serial_fault_campaign_test
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "fault_campaign.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/reply_tracker.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "pty_device.hpp"
#include "scratch_dir.hpp"

namespace hapticd::testing {
namespace {

namespace proto = device::protocol;
using Bytes = std::vector<std::byte>;
using servo::IoResult;
using servo::Sample;

constexpr int kReplyTimeoutMs = 30;
constexpr std::int64_t kTicks = 700;
constexpr std::int64_t kFirstFault = 150;  ///< request or tick: after the handshake
constexpr std::int64_t kLastFault = 450;   ///< leaves time to recover before the end

// clang-format off
enum class Kind {
    // replies
    flip, line_flip, forge, truncate, drop, duplicate, replay, reorder, garbage, delay, silence,
    // requests
    request_flip, request_truncate, request_drop, request_duplicate,
    // the device
    hang, unplug,
};
constexpr int kKinds = 17;
constexpr std::array<const char*, kKinds> kKindNames = {
    "flip", "line_flip", "forge", "truncate", "drop", "duplicate", "replay", "reorder",
    "garbage", "delay", "silence",
    "request_flip", "request_truncate", "request_drop", "request_duplicate",
    "hang", "unplug"};
// clang-format on

struct Event {
    Kind kind = Kind::drop;
    std::int64_t at = 0;      ///< the request it starts at (unplug: the tick)
    std::int64_t length = 1;  ///< requests it lasts (silence, hang); unplug: ticks
    bool mid_tick = false;    ///< unplug: between the tick's read and its write
};

std::vector<Event> random_events(std::mt19937_64& rng) {
    std::uniform_int_distribution<int> count(1, 4), kind(0, kKinds - 1);
    std::uniform_int_distribution<std::int64_t> at(kFirstFault, kLastFault);
    std::vector<Event> events;
    for (int i = count(rng); i > 0; --i) {
        Event e;
        e.kind = static_cast<Kind>(kind(rng));
        e.at = at(rng);
        if (e.kind == Kind::silence || e.kind == Kind::hang) {
            e.length = std::uniform_int_distribution<std::int64_t>(1, 12)(rng);
        } else if (e.kind == Kind::unplug) {
            e.length = std::uniform_int_distribution<std::int64_t>(1, 150)(rng);
            e.mid_tick = std::uniform_int_distribution<int>(0, 1)(rng) == 1;
        }
        events.push_back(e);
    }
    return events;
}

/// A sample frame the host could take: one that went out whole, genuine or forged.
struct SentSample {
    std::uint32_t session = 0;
    std::uint32_t sample_sequence = 0;
    std::uint64_t time_us = 0;
    std::int64_t counts = 0;
    bool forged_time = false;  ///< its time_us is not the device's
};

/// The faults on the wire, in the pty's serving thread (under its lock). Read the results
/// once that thread has stopped.
class LineFaults {
  public:
    LineFaults(std::uint64_t seed, const std::vector<Event>& events)
        : rng_(seed), events_(events) {}

    PtyDevice::LineTap tap() {
        return {[this](Bytes& bytes) { to_device(bytes); },
                [this](Bytes& bytes) { to_host(bytes); }};
    }
    /// The device hangs: the emulator ignores requests while its clock runs. (Called before
    /// to_device() counts the request.)
    PtyDevice::RequestHook hook() {
        return [this](proto::DeviceEmulator& emulator, std::uint64_t) {
            for (const Event& e : events_) {
                if (e.kind != Kind::hang || e.at != request_ + 1) continue;
                emulator.faults().stall = static_cast<std::uint32_t>(e.length);
                ++applied_[static_cast<int>(Kind::hang)];
            }
        };
    }

    const std::vector<SentSample>& samples() const { return samples_; }
    const std::array<std::uint64_t, kKinds>& applied() const { return applied_; }

  private:
    /// An event of `kind` that covers the current request.
    const Event* covering(Kind kind) const {
        for (const Event& e : events_) {
            if (e.kind == kind && request_ >= e.at && request_ < e.at + e.length) return &e;
        }
        return nullptr;
    }
    bool fire(Kind kind) {
        if (covering(kind) == nullptr) return false;
        ++applied_[static_cast<int>(kind)];
        return true;
    }
    std::size_t pick(std::size_t n) {
        return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_);
    }
    void flip_bits(Bytes& bytes, int max_bits) {
        std::set<std::size_t> bits;
        const int n = std::uniform_int_distribution<int>(1, max_bits)(rng_);
        while (static_cast<int>(bits.size()) < n) bits.insert(pick(bytes.size() * 8));
        for (const std::size_t bit : bits)
            bytes[bit / 8] ^= std::byte{static_cast<unsigned char>(1u << (bit % 8))};
    }
    Bytes garbage() {
        Bytes bytes(1 + pick(80));
        const bool delimiters = pick(2) == 0;
        for (std::byte& b : bytes) {
            b = static_cast<std::byte>(pick(256));
            if (!delimiters && b == std::byte{0}) b = std::byte{0x41};
        }
        return bytes;
    }

    void to_device(Bytes& bytes) {
        for (const std::byte b : bytes) {
            if (b == proto::kStreamDelimiter) ++request_;
        }
        if (bytes.size() < 2) return;  // a lone delimiter (the port opened)
        if (fire(Kind::request_drop)) {
            bytes.clear();
        } else if (fire(Kind::request_duplicate)) {
            const Bytes copy = bytes;
            bytes.insert(bytes.end(), copy.begin(), copy.end());
        } else if (fire(Kind::request_truncate)) {
            bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(1 + pick(bytes.size() - 2)),
                        bytes.end() - 1);
        } else if (fire(Kind::request_flip)) {
            flip_bits(bytes, 5);
        }
    }

    /// A sample's fields changed, the frame re-encoded with a good CRC.
    bool forge(Bytes& frame, SentSample& sent) {
        proto::EncoderSample s;
        if (proto::decode(frame, s) != proto::Error::none) return false;
        const auto delta = [&](int lo, int hi) {
            const int d = std::uniform_int_distribution<int>(lo, hi)(rng_);
            return pick(2) == 0 ? d : -d;
        };
        switch (pick(10)) {
            case 0:
                s.session ^= 1u + static_cast<std::uint32_t>(pick(0xFFFF));
                break;
            case 1:
                s.command_sequence += static_cast<std::uint32_t>(delta(1, 3));
                break;
            case 2:
                s.sample_sequence -= static_cast<std::uint32_t>(1 + pick(5));
                break;
            case 3:
                s.sample_sequence += static_cast<std::uint32_t>(1 + pick(5));
                break;
            case 4:
                s.counts[0] += delta(1, 20);
                break;
            case 5:
                s.counts[0] += delta(2000, 50000);
                break;
            case 6:
                s.time_us += static_cast<std::uint64_t>(delta(1, 5000));
                sent.forged_time = true;
                break;
            case 7:
                s.status |= static_cast<std::uint16_t>(1u << pick(6));
                break;
            case 8:  // far ahead: as if the device had lost a thousand samples or more
                s.sample_sequence += 1000u + static_cast<std::uint32_t>(pick(1u << 20));
                break;
            default:
                s.faults |= static_cast<std::uint16_t>(1u << pick(8));
                break;
        }
        std::array<std::byte, proto::kMaxFrameSize> out{};
        const proto::Encoded encoded = proto::encode(s, out);
        if (!encoded.ok()) return false;
        frame.assign(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(encoded.size));
        return true;
    }

    /// What goes out, frame by frame, before the line-level faults.
    struct Out {
        Bytes frame;
        bool genuine = true;  ///< as the device sent it (not a copy, not damaged, not forged)
        bool forged = false;
        SentSample sent;
    };

    void to_host(Bytes& bytes) {
        std::vector<Out> out;
        decoder_.feed(bytes, [&](std::span<const std::byte> f) {
            Out o;
            o.frame.assign(f.begin(), f.end());
            out.push_back(std::move(o));
        });
        if (!out.empty() && covering(Kind::silence) != nullptr) {
            ++applied_[static_cast<int>(Kind::silence)];
            out.clear();
        }
        if (!out.empty()) damage(out);
        // A frame held back last time goes out behind this answer.
        for (Out& o : held_) out.push_back(std::move(o));
        held_.clear();
        if (!out.empty() && fire(Kind::reorder)) {
            held_.push_back(std::move(out.front()));
            out.erase(out.begin());
        }

        Bytes line;
        const std::size_t line_target = out.empty() ? 0 : pick(out.size());
        const bool line_flip = !out.empty() && fire(Kind::line_flip);
        const bool truncate = !out.empty() && !line_flip && fire(Kind::truncate);
        for (std::size_t i = 0; i < out.size(); ++i) {
            Out& o = out[i];
            Bytes encoded(proto::stream_encoded_size(o.frame.size()));
            encoded.resize(proto::encode_stream(o.frame, encoded).size);
            bool whole = true;
            if (i == line_target && line_flip) {
                flip_bits(encoded, 3);
                whole = false;
            } else if (i == line_target && truncate) {
                encoded.erase(
                    encoded.begin() + static_cast<std::ptrdiff_t>(1 + pick(encoded.size() - 2)),
                    encoded.end() - 1);
                whole = false;
            }
            line.insert(line.end(), encoded.begin(), encoded.end());
            if (whole) delivered(o);
        }
        if (fire(Kind::garbage)) {
            const Bytes noise = garbage();
            line.insert(line.begin() + static_cast<std::ptrdiff_t>(pick(line.size() + 1)),
                        noise.begin(), noise.end());
        }
        if (fire(Kind::delay)) {
            std::this_thread::sleep_for(
                std::chrono::microseconds(pick(std::size_t{2} * kReplyTimeoutMs * 1000)));
        }
        bytes = std::move(line);
    }

    /// The frame-level faults of this answer.
    void damage(std::vector<Out>& out) {
        const std::size_t target = pick(out.size());
        if (fire(Kind::drop)) {
            out.clear();
            return;
        }
        if (fire(Kind::flip)) {
            flip_bits(out[target].frame, 5);
            out[target].genuine = false;
        } else if (covering(Kind::forge) != nullptr && forge(out[target].frame, out[target].sent)) {
            ++applied_[static_cast<int>(Kind::forge)];
            out[target].genuine = false;
            out[target].forged = true;
        }
        if (fire(Kind::duplicate)) {
            Out copy = out[target];
            copy.genuine = false;
            copy.forged = false;  // the forged one is already on its way
            out.push_back(copy);
        }
        if (!history_.empty() && fire(Kind::replay)) {
            Out old;
            old.frame = history_[pick(history_.size())];
            old.genuine = false;
            if (pick(2) == 0) {
                out.insert(out.begin(), old);  // before this answer
            } else {
                out[target] = old;  // instead of it
            }
        }
    }

    /// `o` went out whole: a sample the host may take, and a frame to replay later.
    void delivered(Out& o) {
        if (o.genuine) {
            history_.push_back(o.frame);
            if (history_.size() > 64) history_.pop_front();
        }
        proto::EncoderSample s;
        if ((o.genuine || o.forged) && proto::decode(o.frame, s) == proto::Error::none) {
            samples_.push_back(
                {s.session, s.sample_sequence, s.time_us, s.counts[0], o.sent.forged_time});
        }
    }

    std::mt19937_64 rng_;
    const std::vector<Event>& events_;
    std::int64_t request_ = -1;  ///< requests (delimiters) the host sent, minus one
    proto::StreamDecoder decoder_;
    std::deque<Bytes> history_;  ///< the last frames that went out whole
    std::vector<Out> held_;      ///< reordered: behind the next answer
    std::vector<SentSample> samples_;
    std::array<std::uint64_t, kKinds> applied_{};
};

/// The serial plugin as the servo loop sees it, with the campaign's unplugs (before a
/// tick's read, or between its read and its write) and a record of every read.
class UnpluggingDevice {
  public:
    struct Read {
        IoResult result = IoResult::ok;
        Sample sample;
    };

    UnpluggingDevice(device::Device& device, PtyDevice& pty, const std::vector<Event>& events)
        : device_(device), pty_(pty), events_(events) {
        reads_.reserve(kTicks + 1);
    }

    IoResult read(Sample& sample) noexcept {
        ++tick_;
        follow_plug(/*at_write=*/false);
        const IoResult result = device_.read(sample);
        reads_.push_back({result, sample});
        return result;
    }
    IoResult write(const servo::Command& command) noexcept {
        follow_plug(/*at_write=*/true);
        return device_.write(command);
    }

    const std::vector<Read>& reads() const { return reads_; }
    bool plug_failed() const { return plug_failed_; }
    std::uint64_t unplugs() const { return unplugs_; }

  private:
    /// Unplugs or plugs in the device as the events say for this point of the tick.
    void follow_plug(bool at_write) noexcept {
        bool gone = false;
        for (const Event& e : events_) {
            const bool started = tick_ > e.at || (tick_ == e.at && (at_write || !e.mid_tick));
            if (e.kind == Kind::unplug && started && tick_ < e.at + e.length) gone = true;
        }
        if (gone == gone_) return;
        if (gone) ++unplugs_;
        try {
            gone ? pty_.hang_up() : pty_.plug_in();
        } catch (...) {
            plug_failed_ = true;
        }
        gone_ = gone;
    }

    device::Device& device_;
    PtyDevice& pty_;
    const std::vector<Event>& events_;
    std::int64_t tick_ = -1;
    bool gone_ = false;
    bool plug_failed_ = false;
    std::uint64_t unplugs_ = 0;
    std::vector<Read> reads_;
};

/// Ends the process, naming the seed, if a sequence runs for more than `limit` (a hang).
class HangWatch {
  public:
    HangWatch(std::uint64_t seed, std::chrono::seconds limit)
        : thread_([this, seed, limit] {
              std::unique_lock<std::mutex> lock(mutex_);
              if (!done_cv_.wait_for(lock, limit, [this] { return done_; })) {
                  std::cerr << "serial fault campaign: seed " << seed << " hung for "
                            << limit.count() << " s\n";
                  std::abort();
              }
          }) {}
    ~HangWatch() {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            done_ = true;
        }
        done_cv_.notify_all();
        thread_.join();
    }

  private:
    std::mutex mutex_;
    std::condition_variable done_cv_;
    bool done_ = false;
    std::thread thread_;
};

device::DeviceConfig device_config(const std::string& port, bool reconnect) {
    device::DeviceConfig c;
    c.axes = 1;
    c.rate_hz = 1.0 / campaign::kPeriodS;
    c.lockstep = true;
    c.plugin_table_toml =
        "port = \"" + port + "\"\nreply_timeout_ms = " + std::to_string(kReplyTimeoutMs) +
        "\nreconnect_interval_ms = 10\n" + "reconnect = " + (reconnect ? "true" : "false") + "\n";
    c.source = "campaign.toml";
    return c;
}

/// Each sample the host took is one that went out, not taken before, not older than the
/// last of its session; its velocity is the step since the last sample of the history over
/// the device's clock (0 where the history starts).
void check_samples(const std::vector<servo::TelemetryRecord>& records,
                   const std::vector<UnpluggingDevice::Read>& reads,
                   const std::vector<SentSample>& sent) {
    std::multimap<std::uint32_t, const SentSample*> by_sequence;
    for (const SentSample& s : sent) by_sequence.emplace(s.sample_sequence, &s);
    std::set<std::pair<std::uint32_t, std::uint32_t>> taken;  // (session, sample_sequence)
    std::map<std::uint32_t, std::uint32_t> last_of_session;
    std::uint64_t last_time_us = 0;
    bool history = false;
    double history_x = 0.0, history_t = 0.0;
    for (std::size_t n = 0; n < records.size(); ++n) {
        const servo::TelemetryRecord& rec = records[n];
        if ((rec.flags & servo::kFlagNoSample) == 0u) {
            const Sample& s = reads[n].sample;
            const auto time_us = static_cast<std::uint64_t>(std::llround(s.device_time_s * 1e6));
            const SentSample* match = nullptr;
            bool any = false;
            const auto [begin, end] =
                by_sequence.equal_range(static_cast<std::uint32_t>(s.sequence));
            for (auto it = begin; it != end && match == nullptr; ++it) {
                const SentSample& c = *it->second;
                if (c.time_us != time_us || c.counts != s.encoder_counts[0]) continue;
                any = true;
                const auto last = last_of_session.find(c.session);
                const bool newer = last == last_of_session.end() ||
                                   proto::sequence_distance(last->second, c.sample_sequence) > 0;
                if (newer && taken.count({c.session, c.sample_sequence}) == 0) match = &c;
            }
            ASSERT_TRUE(any) << "tick " << n << ": took a sample the device never sent (sequence "
                             << s.sequence << ", " << time_us << " us)";
            ASSERT_NE(match, nullptr) << "tick " << n << ": took a frame again, or an older one "
                                      << "(sequence " << s.sequence << ", " << time_us << " us)";
            taken.insert({match->session, match->sample_sequence});
            last_of_session[match->session] = match->sample_sequence;
            if (!match->forged_time) {
                ASSERT_GE(time_us, last_time_us) << "tick " << n << ": a sample from the past";
                last_time_us = time_us;
            }
            double expected_v = 0.0;
            if (history && (rec.flags & servo::kFlagIntervalUnknown) == 0u) {
                const double periods =
                    std::round((s.device_time_s - history_t) / campaign::kPeriodS);
                expected_v =
                    (rec.x_m[0] - history_x) / (std::max(1.0, periods) * campaign::kPeriodS);
            }
            ASSERT_NEAR(rec.v_mps[0], expected_v, 1e-9) << "tick " << n << ": velocity";
            history = true;
            history_x = rec.x_m[0];
            history_t = s.device_time_s;
        } else if ((rec.faults & servo::kLinkFaults) != 0u) {
            history = false;  // a gap under a link fault: the next sample starts again
        }
        if ((rec.flags & servo::kFlagLinkRecovered) != 0u) history = false;
    }
}

struct Counts {
    std::uint64_t sequences = 0, ticks = 0, faults_detected = 0, recoveries = 0, unplugs = 0;
    std::array<std::uint64_t, kKinds> applied{};
};

/// One sequence; a broken invariant is a fatal failure naming the seed and the tick.
void run_sequence(std::uint64_t seed, Counts& counts) {
    const HangWatch watch(seed, std::chrono::seconds(120));
    std::mt19937_64 rng(seed);
    const bool reconnect = std::uniform_int_distribution<int>(0, 1)(rng) == 1;
    const std::vector<Event> events = random_events(rng);
    std::string trace =
        "seed " + std::to_string(seed) + (reconnect ? " reconnect:" : " no reconnect:");
    for (const Event& e : events) {
        trace += std::string(" ") + kKindNames[static_cast<int>(e.kind)] + "@" +
                 std::to_string(e.at) + "x" + std::to_string(e.length);
    }
    SCOPED_TRACE(trace);

    LineFaults line(rng(), events);
    proto::EmulatorConfig emulator;
    emulator.sim = campaign::sim_config();
    emulator.serial_number = "EMU-CAMPAIGN";
    const ScratchDir dir;
    PtyDevice pty(emulator, dir.file("by-id"));
    pty.set_line_tap(line.tap());
    pty.set_request_hook(line.hook());
    device::DeviceHandle handle = device::load_device("serial");
    handle->open(device_config(pty.port(), reconnect));

    UnpluggingDevice device(*handle, pty, events);
    env::Scene scene = campaign::wall_scene();
    servo::TelemetryRing ring(4096);
    servo::RunExit exit{};
    std::uint32_t faults_seen = 0;
    std::uint64_t recoveries = 0;
    {
        servo::ServoLoop<UnpluggingDevice, env::ImpedanceEnvironment> loop(
            device, *scene.impedance, campaign::servo_config(reconnect), &ring);
        const std::atomic<bool> stop{false};
        exit = loop.run(stop, kTicks);
        faults_seen = loop.faults_seen();
        recoveries = loop.stats().link_recoveries;
        ASSERT_EQ(loop.stats().ticks, device.reads().size());
        ASSERT_EQ(ring.dropped(), 0u);
    }
    handle->close();
    pty.hang_up();  // the serving thread stops: the line's record is ours to read
    ASSERT_FALSE(device.plug_failed());
    // Zero force on every exit path: at once after a bye, within the watchdog without one.
    pty.with_emulator([](proto::DeviceEmulator& e) {
        for (std::uint32_t k = 0; k <= e.watchdog_timeout_us() / 1000; ++k) e.advance_period();
        ASSERT_EQ(e.output_force_n()[0], 0.0);
    });
    const std::vector<servo::TelemetryRecord> records = campaign::drain(ring);
    ASSERT_EQ(records.size(), device.reads().size());

    campaign::check_every_tick(records);
    if (::testing::Test::HasFatalFailure()) return;
    for (const Event& e : events) {
        if (e.kind != Kind::unplug || e.at >= static_cast<std::int64_t>(records.size())) continue;
        const servo::TelemetryRecord& rec = records[static_cast<std::size_t>(e.at)];
        ASSERT_NE(rec.faults & servo::kFaultDeviceLost, 0u) << "unplugged at tick " << e.at;
        ++counts.unplugs;
    }
    check_samples(records, device.reads(), line.samples());
    if (::testing::Test::HasFatalFailure()) return;
    campaign::check_outcome(records, exit, faults_seen, reconnect);
    if (::testing::Test::HasFatalFailure()) return;
    // With reconnect, the link faults of a device that never left, and that the host never
    // lost, always clear: every fault on the wire is over within a few requests, long before
    // the timeout. (A device that left comes back through the reconnect thread, in wall time:
    // check_outcome's timeout rule holds for it.)
    const bool left = (faults_seen & servo::kFaultDeviceLost) != 0u ||
                      std::any_of(events.begin(), events.end(),
                                  [](const Event& e) { return e.kind == Kind::unplug; });
    if (reconnect && !left && (faults_seen & ~servo::kLinkFaults) == 0u) {
        ASSERT_NE(exit, servo::RunExit::fault) << "the link never recovered";
    }

    ++counts.sequences;
    counts.ticks += records.size();
    counts.recoveries += recoveries;
    if (faults_seen != 0u) ++counts.faults_detected;
    for (int k = 0; k < kKinds; ++k) counts.applied[k] += line.applied()[k];
    counts.applied[static_cast<int>(Kind::unplug)] += device.unplugs();
}

TEST(SerialFaultCampaign, EveryTickOfEverySequenceKeepsTheSafetyInvariants) {
    const std::uint64_t sequences =
        campaign::env_count("HAPTICD_PTY_CAMPAIGN_SEQUENCES").value_or(100);
    Counts counts;
    if (const auto only = campaign::env_count("HAPTICD_PTY_CAMPAIGN_SEED")) {
        run_sequence(*only, counts);
        return;
    }
    const auto start = std::chrono::steady_clock::now();
    for (std::uint64_t seed = 1; seed <= sequences; ++seed) {
        run_sequence(seed, counts);
        if (::testing::Test::HasFatalFailure()) return;
    }
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "serial fault campaign: " << counts.sequences << " sequences, " << counts.ticks
              << " ticks, " << wall_s << " s; " << counts.faults_detected
              << " sequences latched a fault, " << counts.recoveries << " link recoveries, "
              << counts.unplugs << " unplugs checked; faults applied:";
    for (int k = 0; k < kKinds; ++k) std::cout << " " << kKindNames[k] << " " << counts.applied[k];
    std::cout << "\n";
    EXPECT_EQ(counts.sequences, sequences);
    // The campaign exercises what it claims to (not a vacuous pass).
    EXPECT_GT(counts.faults_detected, sequences / 8);
    EXPECT_GT(counts.recoveries, sequences / 20);
    for (int k = 0; k < kKinds; ++k) {
        EXPECT_GT(counts.applied[k], sequences / 40) << kKindNames[k];
    }
}

}  // namespace
}  // namespace hapticd::testing
