#include "run/run_stamp.hpp"

#include <unistd.h>

#include <array>
#include <cstdio>
#include <ctime>
#include <string_view>

#include "hapticd/install/version.hpp"

namespace hapticd::daemon {
namespace {

/// `start` in UTC as strftime's `format`, then ".mmmZ".
std::string utc_text(std::chrono::system_clock::time_point start, const char* format) {
    const auto since_epoch = start.time_since_epoch();
    const auto seconds = std::chrono::floor<std::chrono::seconds>(since_epoch);
    const auto millis =
        std::chrono::duration_cast<std::chrono::milliseconds>(since_epoch - seconds);
    const std::time_t whole = static_cast<std::time_t>(seconds.count());
    std::tm utc{};
    ::gmtime_r(&whole, &utc);
    std::array<char, 32> date{};
    const std::size_t n = std::strftime(date.data(), date.size(), format, &utc);
    std::array<char, 8> fraction{};
    std::snprintf(fraction.data(), fraction.size(), ".%03dZ", static_cast<int>(millis.count()));
    return std::string(date.data(), n) + fraction.data();
}

std::string host_name() {
    std::array<char, 256> name{};
    if (::gethostname(name.data(), name.size() - 1) != 0) return "unknown";
    return name.data();
}

}  // namespace

RunStamp stamp_run(std::chrono::system_clock::time_point start) {
    RunStamp stamp;
    stamp.version = install::kVersion;
    stamp.started_at = utc_text(start, "%Y-%m-%dT%H:%M:%S");
    stamp.start_name = utc_text(start, "%Y%m%dT%H%M%S");
    stamp.host = host_name();
    return stamp;
}

std::string with_start(std::string path, const RunStamp& stamp) {
    const std::string_view placeholder = kStartPlaceholder;
    for (std::size_t at = path.find(placeholder); at != std::string::npos;
         at = path.find(placeholder, at + stamp.start_name.size())) {
        path.replace(at, placeholder.size(), stamp.start_name);
    }
    return path;
}

}  // namespace hapticd::daemon
