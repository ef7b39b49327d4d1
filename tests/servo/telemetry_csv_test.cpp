// Telemetry CSV: the column names of docs/architecture.md §4.5, and numbers that read back
// exactly.
#include "hapticd/servo/telemetry_csv.hpp"

#include <gtest/gtest.h>

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
    EXPECT_EQ(
        csv_header(1),
        "tick,t_s,x0_m,v0_mps,xe0_m,f0_n,status,flags,faults,state,wake_latency_us,compute_us,"
        "energy_j");
    const std::vector<std::string> three = split(csv_header(3));
    ASSERT_EQ(three.size(), 2u + 3u * 4u + 7u);
    EXPECT_EQ(three[10], "x2_m");
    EXPECT_EQ(three[13], "f2_n");
    EXPECT_THROW(csv_header(0), std::invalid_argument);
    EXPECT_THROW(csv_header(4), std::invalid_argument);
}

TEST(ServoTelemetryCsv, RecordRoundTripsThroughText) {
    TelemetryRecord record;
    record.tick = 123456789;
    record.t_s = 123.456789;
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

    std::array<char, kMaxCsvLineChars> buffer{};
    const std::size_t length = format_csv_record(record, 2, buffer);
    ASSERT_GT(length, 0u);
    EXPECT_EQ(buffer[length - 1], '\n');
    const std::vector<std::string> fields = split(std::string(buffer.data(), length - 1));
    ASSERT_EQ(fields.size(), split(csv_header(2)).size());
    EXPECT_EQ(fields[0], "123456789");
    EXPECT_EQ(std::stod(fields[1]), record.t_s);
    EXPECT_EQ(std::stod(fields[2]), 0.1);      // x0_m
    EXPECT_EQ(std::stod(fields[5]), -1.75);    // f0_n
    EXPECT_EQ(std::stod(fields[6]), -2.5e-5);  // x1_m
    EXPECT_EQ(std::stod(fields[9]), 0.5);      // f1_n
    EXPECT_EQ(fields[10], "10");               // status: stale | late
    EXPECT_EQ(fields[11], "2");                // flags
    EXPECT_EQ(fields[13], "2");                // state
    EXPECT_EQ(std::stod(fields[16]), -1e-9);   // energy_j

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
