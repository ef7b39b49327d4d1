#include "outputs/flight_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>

#include "hapticd/daemon/output_files.hpp"
#include "hapticd/servo/telemetry_csv.hpp"

namespace hapticd::daemon {

FlightFile write_flight_file(const OutputsDirectory& directory, const std::string& start_name,
                             const std::vector<servo::TelemetryRecord>& records, int axes) {
    const std::uint64_t last = records.empty() ? 0 : records.back().tick;
    const OutputsDirectory::NewFile created =
        directory.create("flight-" + start_name + "-tick" + std::to_string(last) + ".csv");
    FlightFile file{.path = created.path, .error = {}, .bytes = 0};
    if (created.fd < 0) {
        file.error = "cannot create " + file.path + ": " + created.error;
        return file;
    }
    try {
        std::ostringstream text;  // 5 s of ticks: a few hundred kB
        servo::write_csv_header(text, axes);
        for (const servo::TelemetryRecord& record : records) {
            servo::write_csv_record(text, record, axes);
        }
        const std::string bytes = text.str();
        if (!write_all(created.fd, bytes)) {
            file.error = "could not write all of " + file.path + ": " + std::strerror(errno);
        }
        file.bytes = bytes.size();  // what it took of the run's cap, written or not
    } catch (const std::exception& e) {
        file.error = file.path + ": " + e.what();
    }
    if (::close(created.fd) != 0 && file.error.empty()) {
        file.error = "could not write all of " + file.path + ": " + std::strerror(errno);
    }
    return file;
}

}  // namespace hapticd::daemon
