// simavr is GPL-3.0-or-later; see emulated_board.hpp.
#include "emulated_board.hpp"

#include <simavr/avr_adc.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_io.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace hapticd::avr_sim {
namespace {

// ATmega328P data-space addresses of the registers the harness reads (datasheet, "Register
// Summary": I/O address + 0x20).
constexpr std::uint16_t kDdrB = 0x24, kPortB = 0x25;
constexpr std::uint16_t kDdrD = 0x2A, kPortD = 0x2B;
constexpr std::uint16_t kTccr0A = 0x44, kTccr0B = 0x45, kOcr0B = 0x48;
constexpr std::uint16_t kAdcsra = 0x7A;
constexpr std::uint8_t kCom0B1 = 1u << 5, kCom0B0 = 1u << 4, kWgmFastPwm = 0x03;
constexpr std::uint8_t kPin5 = 1u << 5, kPin0 = 1u << 0;
constexpr std::uint16_t kUcsr0A = 0xC0, kUcsr0B = 0xC1, kUcsr0C = 0xC2, kUbrr0L = 0xC4,
                        kUbrr0H = 0xC5;
constexpr std::uint32_t kSupplyMv = 5000;
/// Overruns named on standard error, each with where the firmware was; the rest are counted.
constexpr std::uint64_t kOverrunsReported = 10;

/// USART0's time per byte as the hardware sends it: start, data, parity if enabled, stop
/// bits. simavr 1.6 counts a parity bit in every byte (11 bit times for 8N1, not 10) and
/// takes the rate only when UBRR0 is written; the harness sets the real figure instead.
std::uint64_t usart0_cycles_per_byte(const std::uint8_t* data) {
    const unsigned ubrr = data[kUbrr0L] | ((data[kUbrr0H] & 0x0Fu) << 8);
    const unsigned cycles_per_bit = (ubrr + 1) * ((data[kUcsr0A] & 0x02u) != 0 ? 8u : 16u);
    const unsigned size = ((data[kUcsr0C] >> 1) & 0x03u) | ((data[kUcsr0B] & 0x04u) != 0 ? 4u : 0u);
    static constexpr unsigned kDataBits[8] = {5, 6, 7, 8, 8, 8, 8, 9};
    const unsigned parity = ((data[kUcsr0C] >> 4) & 0x03u) != 0 ? 1u : 0u;
    const unsigned stop = (data[kUcsr0C] & 0x08u) != 0 ? 2u : 1u;
    return std::uint64_t{cycles_per_bit} * (1u + kDataBits[size] + parity + stop);
}

/// Millivolts that simavr's ADC (mv * 1023 / vref, truncated) reads as `counts`.
std::uint32_t millivolts_for(int counts) {
    return static_cast<std::uint32_t>(
        std::ceil(static_cast<double>(counts) * kSupplyMv / 1023.0 - 1e-9));
}

}  // namespace

EmulatedBoard::EmulatedBoard(const std::string& firmware_elf, const PaddleConfig& paddle,
                             PositionSensor sensor, double plant_step_s)
    : plant_(paddle),
      sensor_(sensor),
      plant_step_cycles_(static_cast<std::uint64_t>(std::llround(plant_step_s * kCpuHz))) {
    if (plant_step_cycles_ == 0) throw std::runtime_error("the plant's step is below one cycle");
    elf_firmware_t firmware{};
    if (elf_read_firmware(firmware_elf.c_str(), &firmware) != 0) {
        throw std::runtime_error("cannot read the firmware ELF " + firmware_elf);
    }
    avr_ = avr_make_mcu_by_name("atmega328p");
    if (avr_ == nullptr) throw std::runtime_error("simavr has no atmega328p");
    avr_init(avr_);
    avr_load_firmware(avr_, &firmware);
    avr_->frequency = kCpuHz;
    avr_->vcc = avr_->avcc = avr_->aref = kSupplyMv;
    // Time is the harness's: a sleeping core jumps to its next event instead of usleep().
    avr_->sleep = [](avr_t*, avr_cycle_count_t) {};

    for (avr_io_t* io = avr_->io_port; io != nullptr; io = io->next) {
        if (std::strcmp(io->kind, "uart") == 0 && reinterpret_cast<avr_uart_t*>(io)->name == '0') {
            uart_ = reinterpret_cast<avr_uart_t*>(io);
        }
    }
    if (uart_ == nullptr) throw std::runtime_error("simavr's atmega328p has no USART0");
    std::uint32_t flags = 0;
    avr_ioctl(avr_, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~static_cast<std::uint32_t>(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
    avr_ioctl(avr_, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
                            &EmulatedBoard::on_uart_output, this);
    avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_OUT_TRIGGER),
                            &EmulatedBoard::on_adc_trigger, this);
    avr_register_io_write(avr_, kOcr0B, &EmulatedBoard::on_duty_write, this);
    if (sensor_ == PositionSensor::quadrature) {
        encoder_channels_ = plant_.encoder_channels();
        avr_raise_irq(avr_io_getirq(avr_, AVR_IOCTL_IOPORT_GETIRQ('D'), IOPORT_IRQ_PIN2),
                      (encoder_channels_ >> 1) & 1u);
        avr_raise_irq(avr_io_getirq(avr_, AVR_IOCTL_IOPORT_GETIRQ('D'), IOPORT_IRQ_PIN3),
                      encoder_channels_ & 1u);
    }
    avr_cycle_timer_register(avr_, plant_step_cycles_, &EmulatedBoard::plant_timer, this);
}

EmulatedBoard::~EmulatedBoard() {
    if (avr_ != nullptr) {
        avr_terminate(avr_);
        std::free(avr_);  // avr_make_mcu_by_name() allocated it with malloc
    }
}

std::uint64_t EmulatedBoard::cycle() const { return avr_->cycle; }

void EmulatedBoard::run_until(std::uint64_t cycle) {
    while (avr_->cycle < cycle) {
        const int state = avr_run(avr_);
        if (state == cpu_Done || state == cpu_Crashed) {
            throw std::runtime_error(
                "the firmware stopped at cycle " + std::to_string(avr_->cycle) + " (pc 0x" +
                std::to_string(avr_->pc) +
                "): " + (state == cpu_Done ? "it slept with interrupts off" : "it crashed"));
        }
    }
}

std::uint64_t EmulatedBoard::cycles_per_byte() const { return uart_->cycles_per_byte; }

std::uint64_t EmulatedBoard::send_to_board(std::uint8_t byte) {
    line_in_free_cycle_ =
        std::max(line_in_free_cycle_, cycle() + cycles_per_byte()) + cycles_per_byte();
    const bool idle = to_board_.empty() && !arriving_;
    to_board_.push_back({byte, line_in_free_cycle_});
    if (idle) {
        const std::uint64_t hand_over = line_in_free_cycle_ - cycles_per_byte();
        avr_cycle_timer_register(avr_, hand_over - cycle(), &EmulatedBoard::receive_timer, this);
    }
    return line_in_free_cycle_;
}

std::uint64_t EmulatedBoard::receive_timer(avr_t* avr, std::uint64_t when, void* self) {
    auto* board = static_cast<EmulatedBoard*>(self);
    avr_uart_t* uart = board->uart_;
    uart->rxc_raise_time = 0;  // as in plant_timer: no read throttle
    const std::uint64_t byte_cycles = board->cycles_per_byte();
    // The byte handed over last has arrived whole: the USART holds two, so if two were still
    // unread it never got in (an overrun), and it is taken back out of simavr's FIFO.
    if (board->arriving_ && board->arrival_cycle_ <= when) {
        board->arriving_ = false;
        const unsigned unread = (uart->input.write - uart->input.read) & (uart_fifo_fifo_size - 1);
        if (unread >= 3) {
            uart->input.write = (uart->input.write - 1) & (uart_fifo_fifo_size - 1);
            if (++board->receive_overruns_ <= kOverrunsReported) {
                std::fprintf(stderr,
                             "hapticd-avr-sim: a received byte overran the USART at cycle %llu: "
                             "the firmware was at 0x%04x (avr-addr2line -e the ELF says where)\n",
                             static_cast<unsigned long long>(when), avr->pc);
            }
        }
    }
    if (!board->to_board_.empty() && board->to_board_.front().done_cycle - byte_cycles <= when) {
        avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT),
                      board->to_board_.front().value);
        board->arriving_ = true;
        board->arrival_cycle_ = board->to_board_.front().done_cycle;
        board->to_board_.pop_front();
    }
    std::uint64_t next = board->arriving_ ? board->arrival_cycle_ : 0;
    if (!board->to_board_.empty()) {
        const std::uint64_t hand_over = board->to_board_.front().done_cycle - byte_cycles;
        next = next == 0 ? hand_over : std::min(next, hand_over);
    }
    return next;
}

std::uint64_t EmulatedBoard::transmit_free_timer(avr_t* avr, std::uint64_t, void* self) {
    avr_raise_interrupt(avr, &static_cast<EmulatedBoard*>(self)->uart_->udrc);
    return 0;
}

std::vector<LineByte> EmulatedBoard::take_sent() {
    std::vector<LineByte> out;
    while (!sent_.empty() && sent_.front().done_cycle <= cycle()) {
        out.push_back(sent_.front());
        sent_.pop_front();
    }
    return out;
}

MotorPins EmulatedBoard::motor_pins() const {
    const std::uint8_t* data = avr_->data;
    MotorPins pins;
    const bool d5_output = (data[kDdrD] & kPin5) != 0;
    const bool pwm = (data[kTccr0A] & kCom0B1) != 0 && (data[kTccr0A] & kCom0B0) == 0 &&
                     (data[kTccr0A] & kWgmFastPwm) == kWgmFastPwm && (data[kTccr0B] & 0x07) != 0;
    if (d5_output) {
        pins.duty = pwm ? (data[kOcr0B] + 1.0) / 256.0 : ((data[kPortD] & kPin5) != 0 ? 1.0 : 0.0);
    }
    pins.direction_high = (data[kDdrB] & kPin0) != 0 && (data[kPortB] & kPin0) != 0;
    return pins;
}

std::uint64_t EmulatedBoard::plant_timer(avr_t*, std::uint64_t when, void* self) {
    auto* board = static_cast<EmulatedBoard*>(self);
    board->uart_->cycles_per_byte = usart0_cycles_per_byte(board->avr_->data);
    // simavr lets the firmware read at most one byte per byte time since RXC first rose, so a
    // firmware delayed by an interrupt could never catch up; the real USART lets it read its
    // two-byte FIFO back to back. Keep that throttle from ever applying.
    board->uart_->rxc_raise_time = 0;
    const MotorPins pins = board->motor_pins();
    board->plant_.step(static_cast<double>(board->plant_step_cycles_) / kCpuHz, pins);
    if (board->sensor_ == PositionSensor::quadrature) {
        const std::uint8_t channels = board->plant_.encoder_channels();
        const std::uint8_t changed = channels ^ board->encoder_channels_;
        board->encoder_channels_ = channels;
        if ((changed & 2u) != 0) {
            avr_raise_irq(avr_io_getirq(board->avr_, AVR_IOCTL_IOPORT_GETIRQ('D'), IOPORT_IRQ_PIN2),
                          (channels >> 1) & 1u);
        }
        if ((changed & 1u) != 0) {
            avr_raise_irq(avr_io_getirq(board->avr_, AVR_IOCTL_IOPORT_GETIRQ('D'), IOPORT_IRQ_PIN3),
                          channels & 1u);
        }
    }
    if (board->observer_) board->observer_(*board, pins);
    return when + board->plant_step_cycles_;
}

void EmulatedBoard::start_profile(std::uint64_t every_cycles) {
    profile_every_cycles_ = every_cycles;
    avr_cycle_timer_register(avr_, every_cycles, &EmulatedBoard::profile_timer, this);
}

void EmulatedBoard::profile_from(std::uint64_t cycle) {
    if (profile_every_cycles_ == 0) return;
    avr_cycle_timer_register(avr_, cycle > avr_->cycle ? cycle - avr_->cycle : 1,
                             &EmulatedBoard::profile_start, this);
}

std::uint64_t EmulatedBoard::profile_start(avr_t*, std::uint64_t, void* self) {
    static_cast<EmulatedBoard*>(self)->profiling_ = true;
    return 0;
}

std::uint64_t EmulatedBoard::profile_timer(avr_t* avr, std::uint64_t when, void* self) {
    auto* board = static_cast<EmulatedBoard*>(self);
    if (board->profiling_) ++board->profile_[avr->pc];
    return when + board->profile_every_cycles_;
}

void EmulatedBoard::on_uart_output(avr_irq_t*, std::uint32_t value, void* self) {
    auto* board = static_cast<EmulatedBoard*>(self);
    board->profiling_ = false;
    // The USART's data register and shift register: a byte written while the line is idle
    // starts at once and frees the data register for the next; one written while a byte is
    // shifting out waits in it until that one is done. simavr 1.6 frees the data register
    // only when its byte is done, which halves a polled UART's rate; UDRE is raised here
    // when the hardware would.
    const std::uint64_t now = board->cycle();
    const std::uint64_t start = std::max(now, board->line_out_free_cycle_);
    board->line_out_free_cycle_ = start + board->cycles_per_byte();
    board->sent_.push_back({static_cast<std::uint8_t>(value), board->line_out_free_cycle_});
    if (start == now) {
        avr_raise_interrupt(board->avr_, &board->uart_->udrc);
    } else {
        avr_cycle_timer_register(board->avr_, start - now, &EmulatedBoard::transmit_free_timer,
                                 board);
    }
}

void EmulatedBoard::on_duty_write(avr_t* avr, std::uint16_t addr, std::uint8_t value, void* self) {
    auto* board = static_cast<EmulatedBoard*>(self);
    board->duty_writes_.push_back(avr->cycle);
    avr_core_watch_write(avr, addr, value);
}

void EmulatedBoard::on_adc_trigger(avr_irq_t*, std::uint32_t, void* self) {
    auto* board = static_cast<EmulatedBoard*>(self);
    // A conversion started: the sample-and-hold closes 1.5 ADC clocks later (ADPS2:0 sets
    // the ADC clock to F_CPU / 2^ADPS, 2 for 0).
    const std::uint8_t adps = board->avr_->data[kAdcsra] & 0x07u;
    const std::uint64_t adc_clock_cycles = adps == 0 ? 2u : (1u << adps);
    board->adc_samples_.push_back(board->avr_->cycle + adc_clock_cycles * 3u / 2u);
    // The sensor on A2; the other channels read 0 V.
    avr_raise_irq(avr_io_getirq(board->avr_, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC2),
                  millivolts_for(board->plant_.mr_adc_counts()));
}

}  // namespace hapticd::avr_sim
