// The firmware in the loop: hapticd-avr-sim running the reference firmware's ELF on an
// emulated ATmega328P in an emulated Hapkit paddle, its serial port at a path in the test's
// scratch directory (docs/firmware.md). Started when constructed, stopped (SIGTERM) by stop()
// or when destroyed; stop() returns the figures it measured (--stats).
#pragma once

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "scratch_dir.hpp"

namespace hapticd::testing {

/// hapticd-avr-sim's --record: time_s, duty, direction, motor_force_n, position_m,
/// velocity_mps, mr_adc; a row per interval and one whenever a motor pin changes.
struct PinRecord {
    std::map<std::string, std::vector<double>> columns;
    const std::vector<double>& operator[](const std::string& name) const {
        const auto found = columns.find(name);
        if (found == columns.end()) throw std::runtime_error("the pin record has no " + name);
        return found->second;
    }
    std::size_t rows() const { return columns.empty() ? 0 : columns.begin()->second.size(); }
};

inline PinRecord read_pin_record(const std::string& path) {
    std::ifstream in(path);
    std::string line;
    if (!std::getline(in, line)) throw std::runtime_error("no pin record in " + path);
    std::vector<std::string> names;
    for (std::stringstream header(line); std::getline(header, line, ',');) names.push_back(line);
    PinRecord record;
    for (std::string row; std::getline(in, row);) {
        std::stringstream fields(row);
        for (const std::string& name : names) {
            std::string field;
            std::getline(fields, field, ',');
            record.columns[name].push_back(std::stod(field));
        }
    }
    return record;
}

class EmulatedHapkit {
  public:
    /// `options`: hapticd-avr-sim's own (--clock, --mass, --operator, ...); the firmware
    /// (`firmware`, the reference build by default), the link, --stats and --record
    /// (pins.csv) are added.
    EmulatedHapkit(const ScratchDir& dir, std::vector<std::string> options,
                   const std::string& firmware = HAPTICD_FIRMWARE_ELF)
        : link_(dir.file("hapkit")),
          stats_(dir.file("avr-sim.json")),
          record_(dir.file("pins.csv")) {
        std::vector<std::string> argv = {
            HAPTICD_AVR_SIM_BIN, "--firmware", firmware,   "--link", link_,
            "--stats",           stats_,       "--record", record_};
        argv.insert(argv.end(), options.begin(), options.end());
        process_ =
            std::make_unique<ChildProcess>(argv, dir.file("avr-sim.out"), dir.file("avr-sim.err"));
        // The link appears once the board is loaded and the pty made.
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
        while (!std::filesystem::exists(link_)) {
            if (process_->wait(std::chrono::milliseconds(0)) ||
                std::chrono::steady_clock::now() > until) {
                throw std::runtime_error("hapticd-avr-sim did not start: " + process_->err());
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
    }
    ~EmulatedHapkit() {
        if (process_) process_->signal(SIGTERM);  // ChildProcess's destructor reaps it
    }
    EmulatedHapkit(const EmulatedHapkit&) = delete;
    EmulatedHapkit& operator=(const EmulatedHapkit&) = delete;

    /// The board's serial port, for [device.serial] port.
    const std::string& port() const { return link_; }

    /// Stops the emulation; its figures (hapticd-avr-sim --stats), null if it wrote none.
    nlohmann::json stop() {
        process_->signal(SIGTERM);
        process_->wait(std::chrono::seconds(20));
        exit_code_ = process_->exit_code();
        err_ = process_->err();
        process_.reset();
        std::ifstream in(stats_);
        return in ? nlohmann::json::parse(in) : nlohmann::json();
    }
    int exit_code() const { return exit_code_; }
    const std::string& err() const { return err_; }

    /// The motor pins and the paddle, as recorded (after stop()).
    PinRecord pins() const { return read_pin_record(record_); }

  private:
    std::string link_, stats_, record_;
    std::unique_ptr<ChildProcess> process_;
    int exit_code_ = -1;
    std::string err_;
};

}  // namespace hapticd::testing
