// Reads a hapticd telemetry CSV (header row, the column names of docs/architecture.md §4.5) for
// the hardware-in-the-loop tests.
#pragma once

#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticd::testing {

struct TelemetryLog {
    std::vector<std::string> columns;
    std::map<std::string, std::vector<double>> values;

    const std::vector<double>& column(const std::string& name) const {
        const auto it = values.find(name);
        if (it == values.end()) throw std::runtime_error("telemetry has no column " + name);
        return it->second;
    }
    std::size_t rows() const { return values.empty() ? 0 : values.begin()->second.size(); }
};

inline TelemetryLog read_telemetry(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path);
    TelemetryLog log;
    std::string line;
    if (!std::getline(in, line)) throw std::runtime_error(path + " is empty");
    std::stringstream header(line);
    for (std::string name; std::getline(header, name, ',');) {
        log.columns.push_back(name);
        log.values[name];
    }
    while (std::getline(in, line)) {
        std::stringstream row(line);
        std::size_t i = 0;
        for (std::string cell; std::getline(row, cell, ',') && i < log.columns.size(); ++i) {
            log.values[log.columns[i]].push_back(std::stod(cell));
        }
        if (i != log.columns.size()) throw std::runtime_error(path + ": short row: " + line);
    }
    return log;
}

}  // namespace hapticd::testing
