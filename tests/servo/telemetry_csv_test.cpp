// Telemetry CSV: the column names of docs/architecture.md §4.5, and numbers that read back
// exactly.
#include "hapticd/servo/telemetry_csv.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <sstream>
#include <string>
#include <vector>

namespace hapticd::servo {
namespace {

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> fields;
    std::stringstream stream(line);
    std::string field;
    while (std::getline(stream, field, ',')) fields.push_back(field);
    return fields;
}

TEST(ServoTelemetryCsv, HeaderHasTheDesignColumnNames) {
    EXPECT_EQ(csv_header(1),
              "tick,t_s,unix_time_s,x0_m,v0_mps,xe0_m,f0_n,status,tick_flags,faults,state,"
              "wake_latency_us,compute_us,energy_j,mark");
    const std::vector<std::string> three = split(csv_header(3));
    ASSERT_EQ(three.size(), 3u + 3u * 4u + 8u);
    EXPECT_EQ(three[11], "x2_m");
    EXPECT_EQ(three[14], "f2_n");
    EXPECT_THROW(csv_header(0), std::invalid_argument);
    EXPECT_THROW(csv_header(4), std::invalid_argument);
}

// No column name is an attribute of a pandas DataFrame, which would hide the column from
// `frame.name` (pandas 1.5, Debian 12's python3-pandas): `flags` was one.
TEST(ServoTelemetryCsv, NoColumnIsNamedAsAPandasDataFrameAttribute) {
    for (const std::string& name : split(csv_header(3))) {
        for (const char* attribute : {"flags", "index", "columns", "values", "shape", "size", "T",
                                      "axes", "dtypes", "empty", "ndim", "style", "attrs"}) {
            EXPECT_NE(name, attribute);
        }
    }
}

TEST(ServoTelemetryCsv, RecordRoundTripsThroughText) {
    TelemetryRecord record;
    record.tick = 123456789;
    record.t_s = 123.456789;
    record.unix_time_s = 1796665117.829943;
    record.x_m = {0.1, -2.5e-5, 1.0 / 3.0};
    record.v_mps = {-0.25, 0.0, 7.0};
    record.xe_m = {0.099, 0.0, 0.0};
    record.f_n = {-1.75, 0.5, 0.0};
    record.status = kStatusStale | kStatusLate;
    record.flags = kFlagSaturated;
    record.faults = 0;
    record.state = 2;  // running
    record.wake_latency_us = 12.5;
    record.compute_us = 0.75;
    record.energy_j = -1e-9;
    record.mark = 7;

    std::array<char, kMaxCsvLineChars> buffer{};
    const std::size_t length = format_csv_record(record, 2, buffer);
    ASSERT_GT(length, 0u);
    EXPECT_EQ(buffer[length - 1], '\n');
    const std::vector<std::string> names = split(csv_header(2));
    const std::vector<std::string> fields = split(std::string(buffer.data(), length - 1));
    ASSERT_EQ(fields.size(), names.size());
    const auto field = [&](const std::string& name) {
        const auto at = std::find(names.begin(), names.end(), name);
        EXPECT_NE(at, names.end()) << name;
        return at == names.end() ? std::string()
                                 : fields[static_cast<std::size_t>(at - names.begin())];
    };
    EXPECT_EQ(field("tick"), "123456789");
    EXPECT_EQ(std::stod(field("t_s")), record.t_s);
    EXPECT_EQ(field("unix_time_s"), "1796665117.829943");
    EXPECT_EQ(std::stod(field("x0_m")), 0.1);
    EXPECT_EQ(std::stod(field("f0_n")), -1.75);
    EXPECT_EQ(field("x1_m"), "-2.5e-05");
    EXPECT_EQ(std::stod(field("f1_n")), 0.5);
    EXPECT_EQ(field("status"), "10");  // stale | late
    EXPECT_EQ(field("tick_flags"), "2");
    EXPECT_EQ(field("state"), "2");
    EXPECT_EQ(std::stod(field("energy_j")), -1e-9);
    EXPECT_EQ(field("mark"), "7");

    std::ostringstream stream;
    write_csv_header(stream, 2);
    write_csv_record(stream, record, 2);
    EXPECT_EQ(stream.str(), csv_header(2) + "\n" + std::string(buffer.data(), length));
}

TEST(ServoTelemetryCsv, TooSmallBufferWritesNothing) {
    TelemetryRecord record;
    std::array<char, 8> small{};
    EXPECT_EQ(format_csv_record(record, 1, small), 0u);
}

}  // namespace
}  // namespace hapticd::servo
