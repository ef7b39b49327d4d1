#include "flight_file.hpp"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "hapticd/servo/telemetry_csv.hpp"

namespace hapticd::daemon {
namespace {

std::string directory_of(const std::string& file) {
    const std::filesystem::path parent = std::filesystem::path(file).parent_path();
    return parent.empty() ? std::string(".") : parent.string();
}

}  // namespace

std::optional<std::string> flight_directory(const RunOptions& options) {
    if (const char* logs = std::getenv("LOGS_DIRECTORY"); logs != nullptr && *logs != '\0') {
        const std::string all(logs);
        return all.substr(0, all.find(':'));
    }
    if (options.log_path) return directory_of(*options.log_path);
    if (options.summary_path && *options.summary_path != "-") {
        return directory_of(*options.summary_path);
    }
    return std::nullopt;
}

FlightFile write_flight_file(const std::string& directory, const std::string& start_name,
                             const std::vector<servo::TelemetryRecord>& records, int axes) {
    FlightFile file;
    const std::uint64_t last = records.empty() ? 0 : records.back().tick;
    file.path = (std::filesystem::path(directory) /
                 ("flight-" + start_name + "-tick" + std::to_string(last) + ".csv"))
                    .string();
    try {
        std::ofstream out(file.path, std::ios::trunc);
        if (!out) {
            file.error = "cannot create " + file.path + ": " + std::strerror(errno);
            return file;
        }
        servo::write_csv_header(out, axes);
        for (const servo::TelemetryRecord& record : records) {
            servo::write_csv_record(out, record, axes);
        }
        out.flush();
        if (!out) file.error = "could not write all of " + file.path + ": " + std::strerror(errno);
    } catch (const std::exception& e) {
        file.error = file.path + ": " + e.what();
    }
    return file;
}

}  // namespace hapticd::daemon
