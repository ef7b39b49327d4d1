// hapticd-avr-sim's run: the emulated board (emulated_board.hpp) behind the pty
// (pty_link.hpp), on the harness's clock, with the device's latency measured cycle-exact.
#pragma once

#include <atomic>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "emulated_board.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "pty_link.hpp"

namespace hapticd::avr_sim {

enum class Clock {
    real_time,  ///< emulated time held to the wall clock
    /// For hapticd --lockstep: emulated time stands still while the host computes. A board
    /// that answers at once gets a period of emulated time per request; one that paces the
    /// loop (its identity says so: docs/protocol.md 5.8) runs until its answer is out, so the
    /// host's command follows its sample with no time between, as from an infinitely fast
    /// host.
    lockstep,
};

struct HarnessOptions {
    Clock clock = Clock::real_time;
    double period_s = 1e-3;   ///< lockstep: emulated time per request
    double duration_s = 0.0;  ///< emulated seconds to run; 0: until SIGINT or SIGTERM
    std::string record_path;  ///< the pins and the plant, as CSV; empty: none
    double record_interval_s = 1e-4;
};

/// What a run measured. Device latency: from the last byte of a request in (its delimiter
/// off the line) to the last byte of its reply out, in emulated time.
struct HarnessFigures {
    std::uint64_t requests = 0;
    std::uint64_t replies = 0;
    std::vector<double> latency_us;
    /// Of that, from the request's last byte in to the reply's first byte written: the
    /// firmware's own time, without the reply's time on the line.
    std::vector<double> compute_us;
    /// From a reply's last byte out to the next request's first byte onto the line: the
    /// host's turnaround, the pseudo-terminal's both ways included.
    std::vector<double> turnaround_us;
    /// The loop delay as the board's pins show it, per command: from the sampling instant of
    /// the counts in the last sample out before the command (the ADC's sample-and-hold) to
    /// the firmware's first write of the motor's duty after the command's last byte
    /// (docs/protocol.md 5.7; what haptic-tune diag reads from the board's acknowledgements).
    std::vector<double> loop_delay_us;
    double emulated_s = 0.0;
    double wall_s = 0.0;
    double lag_max_s = 0.0;  ///< real time: how far emulated time fell behind the wall clock
};

class Harness {
  public:
    Harness(EmulatedBoard& board, PtyLink& link, const HarnessOptions& options);

    /// Runs until the duration or `stop`; returns the figures.
    HarnessFigures run(const std::atomic<bool>& stop);

  private:
    void run_real_time(const std::atomic<bool>& stop);
    void run_lockstep(const std::atomic<bool>& stop);
    /// Host bytes to the board; the number of whole requests (a delimiter after data) that
    /// came.
    int take_host_bytes();
    /// Board bytes that have left the line to the host; the number of replies that ended.
    int pass_board_bytes();
    /// A byte the board sent, through the host's own stream decoder: whether an identity in
    /// them says that the board paces the loop.
    void note_identity(std::uint8_t byte);
    void record(const EmulatedBoard& board, MotorPins pins);
    bool done() const;

    EmulatedBoard& board_;
    PtyLink& link_;
    HarnessOptions options_;
    HarnessFigures figures_;
    std::uint64_t end_cycle_ = 0;
    bool host_frame_open_ = false;
    bool board_frame_open_ = false;
    std::uint64_t reply_first_cycle_ = 0;
    device::protocol::StreamDecoder board_frames_;
    bool board_paces_ = false;  // its last identity said it paces the loop
    std::uint64_t reply_done_cycle_ = 0;
    bool reply_done_ = false;
    std::uint64_t request_in_cycle_ = 0;
    bool request_pending_ = false;
    /// Lockstep: requests not answered yet. A bye after a command in one write, or a hello
    /// after a session that ended mid-exchange, leaves more than one in flight; emulated
    /// time runs until each has its reply (or the request is given up on).
    int unanswered_ = 0;
    std::vector<std::uint64_t> request_ends_;  ///< each request's last byte in, cycles
    std::vector<std::uint64_t> reply_ends_;    ///< each board frame's last byte out, cycles
    /// figures_.loop_delay_us from the cycles above and the board's.
    void measure_loop_delay();
    std::ofstream record_;
    double next_record_s_ = 0.0;
    MotorPins recorded_pins_{-1.0, false};
};

}  // namespace hapticd::avr_sim
