// The ATmega328P of the Hapkit board, emulated by simavr, with the paddle around it
// (paddle_plant.hpp): the firmware ELF runs unchanged; the harness reads its motor pins from
// the registers, answers its ADC with the MR sensor's voltage (or drives the encoder pins),
// and moves bytes in and out of USART0 with the line's timing.
//
// simavr is GPL-3.0-or-later: this file and the program that links it (hapticd-avr-sim) are
// separate from hapticd and its libraries, which never link simavr (docs/firmware.md).
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "paddle_plant.hpp"

struct avr_t;
struct avr_irq_t;
struct avr_uart_t;

namespace hapticd::avr_sim {

enum class PositionSensor { mr, quadrature };

/// One byte the firmware sent: the cycle at which its stop bit left the line.
struct LineByte {
    std::uint8_t value = 0;
    std::uint64_t done_cycle = 0;
};

class EmulatedBoard {
  public:
    static constexpr std::uint64_t kCpuHz = 16'000'000;

    /// Loads the ELF (throws std::runtime_error naming the file if it cannot); the plant
    /// steps every plant_step_s of emulated time.
    EmulatedBoard(const std::string& firmware_elf, const PaddleConfig& paddle,
                  PositionSensor sensor, double plant_step_s);
    ~EmulatedBoard();
    EmulatedBoard(const EmulatedBoard&) = delete;
    EmulatedBoard& operator=(const EmulatedBoard&) = delete;

    /// Runs the firmware until its clock reaches `cycle`. Throws if the core stops (a crash
    /// or a sleep with interrupts off).
    void run_until(std::uint64_t cycle);

    std::uint64_t cycle() const;
    double time_s() const { return static_cast<double>(cycle()) / kCpuHz; }

    /// A byte from the host onto the line into the MCU's RX pin. Bytes follow each other at
    /// the line's rate; the cycle at which this one has arrived whole is returned. As on the
    /// real USART, a byte that arrives while two are still unread is lost (an overrun).
    std::uint64_t send_to_board(std::uint8_t byte);

    /// Bytes lost because the firmware had not read the two before them in time.
    std::uint64_t receive_overruns() const { return receive_overruns_; }

    /// The bytes the firmware has sent that have left the line by now, in order.
    std::vector<LineByte> take_sent();

    /// The UART's time per byte as the firmware configured it (cycles).
    std::uint64_t cycles_per_byte() const;

    /// The motor pins now, from Timer0's and the ports' registers.
    MotorPins motor_pins() const;

    const PaddlePlant& plant() const { return plant_; }

    /// Samples the program counter every `every_cycles` from profile_from(cycle) until the
    /// firmware writes its next byte to the UART: where it spends its time answering (byte
    /// address -> samples; symbols from avr-nm).
    void start_profile(std::uint64_t every_cycles);
    void profile_from(std::uint64_t cycle);
    const std::map<std::uint32_t, std::uint64_t>& profile() const { return profile_; }

    /// The cycles, in order, at which the ADC sampled its input (a conversion's start plus 1.5
    /// ADC clocks, the ATmega328P's sample-and-hold instant), and at which the firmware wrote
    /// the motor's duty (OCR0B), even an unchanged one: what the loop delay is measured
    /// between, outside the firmware (Harness).
    const std::vector<std::uint64_t>& adc_samples() const { return adc_samples_; }
    const std::vector<std::uint64_t>& duty_writes() const { return duty_writes_; }

    /// Called after every plant step (time, pins), e.g. to record them.
    void on_step(std::function<void(const EmulatedBoard&, MotorPins)> observer) {
        observer_ = std::move(observer);
    }

  private:
    static std::uint64_t plant_timer(avr_t* avr, std::uint64_t when, void* self);
    static std::uint64_t profile_timer(avr_t* avr, std::uint64_t when, void* self);
    static std::uint64_t profile_start(avr_t* avr, std::uint64_t when, void* self);
    static void on_uart_output(avr_irq_t* irq, std::uint32_t value, void* self);
    static void on_adc_trigger(avr_irq_t* irq, std::uint32_t value, void* self);
    static void on_duty_write(avr_t* avr, std::uint16_t addr, std::uint8_t value, void* self);
    static std::uint64_t receive_timer(avr_t* avr, std::uint64_t when, void* self);
    static std::uint64_t transmit_free_timer(avr_t* avr, std::uint64_t when, void* self);

    avr_t* avr_ = nullptr;
    avr_uart_t* uart_ = nullptr;
    PaddlePlant plant_;
    PositionSensor sensor_;
    std::uint64_t plant_step_cycles_;
    std::function<void(const EmulatedBoard&, MotorPins)> observer_;
    /// Host bytes on their way, each handed to simavr's receiver a byte time before it has
    /// arrived whole (simavr makes a byte readable a byte time after it is handed over), and
    /// taken back out at its arrival if the USART would have had no room for it.
    std::deque<LineByte> to_board_;
    bool arriving_ = false;                  // a byte handed over has yet to arrive
    std::uint64_t arrival_cycle_ = 0;        // ... at this cycle
    std::uint64_t line_in_free_cycle_ = 0;   // when the RX line is free for the next byte
    std::uint64_t line_out_free_cycle_ = 0;  // when the TX shift register is free
    std::uint64_t receive_overruns_ = 0;
    std::deque<LineByte> sent_;
    std::uint8_t encoder_channels_ = 0;
    std::uint64_t profile_every_cycles_ = 0;
    bool profiling_ = false;
    std::map<std::uint32_t, std::uint64_t> profile_;
    std::vector<std::uint64_t> adc_samples_;
    std::vector<std::uint64_t> duty_writes_;
};

}  // namespace hapticd::avr_sim
