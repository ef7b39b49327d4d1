#include "harness.hpp"

#include <sys/prctl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace hapticd::avr_sim {
namespace {

using SteadyClock = std::chrono::steady_clock;

/// Real time: at most this much emulated time between two looks at the host (20 us: a
/// host byte waits no longer than that to start onto the line).
constexpr std::uint64_t kSliceCycles = EmulatedBoard::kCpuHz / 50'000;
/// Lockstep: a request that gets no reply within this many periods is given up on.
constexpr int kLockstepMaxPeriods = 10;
/// Lockstep with a board that paces the loop: how finely the end of its answer is found (a
/// byte at 2 Mbaud).
constexpr std::uint64_t kLockstepPacedStep = 80;

}  // namespace

Harness::Harness(EmulatedBoard& board, PtyLink& link, const HarnessOptions& options)
    : board_(board), link_(link), options_(options) {
    if (!options_.record_path.empty()) {
        record_.open(options_.record_path);
        if (!record_) throw std::runtime_error("cannot write --record " + options_.record_path);
        record_ << "time_s,duty,direction,motor_force_n,position_m,velocity_mps,mr_adc\n";
        board_.on_step([this](const EmulatedBoard& b, MotorPins pins) { record(b, pins); });
    }
    if (options_.duration_s > 0.0) {
        end_cycle_ =
            board_.cycle() +
            static_cast<std::uint64_t>(std::llround(options_.duration_s * EmulatedBoard::kCpuHz));
    }
}

bool Harness::done() const { return end_cycle_ != 0 && board_.cycle() >= end_cycle_; }

void Harness::record(const EmulatedBoard& board, MotorPins pins) {
    const PaddlePlant& plant = board.plant();
    const bool changed =
        pins.duty != recorded_pins_.duty || pins.direction_high != recorded_pins_.direction_high;
    if (!changed && plant.time_s() < next_record_s_) return;
    recorded_pins_ = pins;
    next_record_s_ = plant.time_s() + options_.record_interval_s;
    record_ << plant.time_s() << ',' << pins.duty << ',' << (pins.direction_high ? 1 : 0) << ','
            << plant.motor_force_n() << ',' << plant.position_m() << ',' << plant.velocity_mps()
            << ',' << plant.mr_adc_counts() << '\n';
}

int Harness::take_host_bytes() {
    std::uint8_t bytes[256];
    int requests = 0;
    for (std::size_t n; (n = link_.read(bytes, sizeof bytes)) > 0;) {
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint64_t start_cycle = board_.cycle();
            const std::uint64_t in_cycle = board_.send_to_board(bytes[i]);
            if (bytes[i] != 0x00) {
                if (!host_frame_open_ && reply_done_) {
                    reply_done_ = false;
                    figures_.turnaround_us.push_back(
                        static_cast<double>(start_cycle - reply_done_cycle_) * 1e6 /
                        EmulatedBoard::kCpuHz);
                }
                host_frame_open_ = true;
            } else if (host_frame_open_) {
                host_frame_open_ = false;
                ++requests;
                ++figures_.requests;
                request_ends_.push_back(in_cycle);
                request_in_cycle_ = in_cycle;
                request_pending_ = true;
                board_.profile_from(in_cycle);
            }
        }
    }
    return requests;
}

int Harness::pass_board_bytes() {
    const std::vector<LineByte> sent = board_.take_sent();
    if (sent.empty()) return 0;
    std::vector<std::uint8_t> bytes;
    bytes.reserve(sent.size());
    int replies = 0;
    for (const LineByte& b : sent) {
        bytes.push_back(b.value);
        note_identity(b.value);
        if (b.value != 0x00) {
            if (!board_frame_open_) reply_first_cycle_ = b.done_cycle - board_.cycles_per_byte();
            board_frame_open_ = true;
        } else if (board_frame_open_) {
            board_frame_open_ = false;
            ++replies;
            ++figures_.replies;
            reply_ends_.push_back(b.done_cycle);
            reply_done_cycle_ = b.done_cycle;
            reply_done_ = true;
            // A frame that ended before the request was in (real time: a host late for the
            // period, whose request came while the board's next sample was going out) is not
            // its reply.
            if (request_pending_ && b.done_cycle > request_in_cycle_) {
                request_pending_ = false;
                figures_.latency_us.push_back(
                    static_cast<double>(b.done_cycle - request_in_cycle_) * 1e6 /
                    EmulatedBoard::kCpuHz);
                figures_.compute_us.push_back((static_cast<double>(reply_first_cycle_) -
                                               static_cast<double>(request_in_cycle_)) *
                                              1e6 / EmulatedBoard::kCpuHz);
            }
        }
    }
    link_.write(bytes.data(), bytes.size());
    return replies;
}

void Harness::note_identity(std::uint8_t byte) {
    namespace protocol = device::protocol;
    if (board_frames_.push(std::byte{byte}) != protocol::StreamDecoder::Event::frame) return;
    protocol::Identity identity;
    if (protocol::decode(board_frames_.frame(), identity) == protocol::Error::none) {
        board_paces_ = identity.paced();
    }
}

void Harness::run_real_time(const std::atomic<bool>& stop) {
    // Waits end when asked: Linux's default 50 us of timer slack would be 5 % of a period
    // added to the emulated line's latency.
    ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
    const SteadyClock::time_point start = SteadyClock::now();
    const std::uint64_t start_cycle = board_.cycle();
    while (!stop.load() && !done()) {
        const double wall_s = std::chrono::duration<double>(SteadyClock::now() - start).count();
        const auto due = start_cycle + static_cast<std::uint64_t>(wall_s * EmulatedBoard::kCpuHz);
        if (board_.cycle() < due) {
            figures_.lag_max_s =
                std::max(figures_.lag_max_s,
                         static_cast<double>(due - board_.cycle()) / EmulatedBoard::kCpuHz);
            std::uint64_t until = std::min(due, board_.cycle() + kSliceCycles);
            if (end_cycle_ != 0) until = std::min(until, end_cycle_);
            board_.run_until(until);
            pass_board_bytes();
            take_host_bytes();
            continue;
        }
        // Ahead of the wall clock: wait for it, or for the host.
        const auto ahead_ns = static_cast<std::int64_t>(static_cast<double>(board_.cycle() - due) *
                                                        1e9 / EmulatedBoard::kCpuHz);
        if (link_.wait_readable(std::max<std::int64_t>(ahead_ns, 20'000))) take_host_bytes();
    }
}

void Harness::run_lockstep(const std::atomic<bool>& stop) {
    const auto period_cycles =
        static_cast<std::uint64_t>(std::llround(options_.period_s * EmulatedBoard::kCpuHz));
    while (!stop.load() && !done()) {
        // Emulated time stands still until a whole request has come.
        const int requests = take_host_bytes();
        if (requests == 0) {
            link_.wait_readable(100'000'000);
            continue;
        }
        unanswered_ += requests;
        // One period of emulated time per request (a board that paces the loop: until its
        // answer is out), longer while answers are still going out (up to
        // kLockstepMaxPeriods; what is still unanswered then is given up on).
        const std::uint64_t start = board_.cycle();
        const std::uint64_t limit = start + kLockstepMaxPeriods * period_cycles;
        const std::uint64_t step = board_paces_ ? kLockstepPacedStep : period_cycles / 10;
        for (std::uint64_t until = board_paces_ ? start + step : start + period_cycles; !done();) {
            board_.run_until(std::min(until, limit));
            unanswered_ = std::max(0, unanswered_ - pass_board_bytes());
            if (board_.cycle() >= limit) break;
            if (board_.cycle() >= until && unanswered_ == 0) break;
            if (board_.cycle() >= until) until += step;
        }
        unanswered_ = 0;
    }
}

void Harness::measure_loop_delay() {
    const std::vector<std::uint64_t>& samples = board_.adc_samples();
    const std::vector<std::uint64_t>& writes = board_.duty_writes();
    // The last element <= x, or nullptr.
    const auto last_at_or_before = [](const std::vector<std::uint64_t>& v, std::uint64_t x) {
        const auto it = std::upper_bound(v.begin(), v.end(), x);
        return it == v.begin() ? nullptr : &*(it - 1);
    };
    for (std::size_t i = 0; i < request_ends_.size(); ++i) {
        const std::uint64_t request = request_ends_[i];
        const std::uint64_t next = i + 1 < request_ends_.size()
                                       ? request_ends_[i + 1]
                                       : std::numeric_limits<std::uint64_t>::max();
        const std::uint64_t* reply = last_at_or_before(reply_ends_, request);
        if (reply == nullptr) continue;
        const std::uint64_t* sampled = last_at_or_before(samples, *reply);
        const auto write = std::upper_bound(writes.begin(), writes.end(), request);
        if (sampled == nullptr || write == writes.end() || *write >= next) continue;
        figures_.loop_delay_us.push_back(static_cast<double>(*write - *sampled) * 1e6 /
                                         EmulatedBoard::kCpuHz);
    }
}

HarnessFigures Harness::run(const std::atomic<bool>& stop) {
    const SteadyClock::time_point start = SteadyClock::now();
    const std::uint64_t start_cycle = board_.cycle();
    if (options_.clock == Clock::lockstep) {
        run_lockstep(stop);
    } else {
        run_real_time(stop);
    }
    measure_loop_delay();
    figures_.emulated_s = static_cast<double>(board_.cycle() - start_cycle) / EmulatedBoard::kCpuHz;
    figures_.wall_s = std::chrono::duration<double>(SteadyClock::now() - start).count();
    return figures_;
}

}  // namespace hapticd::avr_sim
