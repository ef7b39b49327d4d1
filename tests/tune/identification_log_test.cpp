// The telemetry-log reader of haptic-tune identify: against the daemon's own CSV writer
// (servo/telemetry_csv.hpp), against logs a user's script writes, and every format error
// with its file, line and column.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include "hapticd/servo/telemetry_csv.hpp"
#include "hapticd/tune/identification.hpp"
#include "hapticd/tune/telemetry_log.hpp"
#include "identification_sim_run.hpp"
#include "scratch_dir.hpp"

namespace hapticd::tune {
namespace {

TelemetryLog parse(const std::string& csv, const std::string& name = "run.csv") {
    std::istringstream in(csv);
    return parse_telemetry_log(in, name);
}

std::string format_error(const std::string& csv) {
    try {
        parse(csv);
    } catch (const LogFormatError& e) {
        return e.what();
    }
    ADD_FAILURE() << "parsed without error:\n" << csv;
    return {};
}

#define EXPECT_CONTAINS(text, part) \
    EXPECT_NE(std::string(text).find(part), std::string::npos) << "in: " << (text)

TEST(IdentificationLog, ReadsTheDaemonsWriterBitForBit) {
    // Awkward numbers in every column: the writer's shortest round-trip form must come back
    // as the same doubles.
    std::vector<servo::TelemetryRecord> records(5);
    for (std::size_t n = 0; n < records.size(); ++n) {
        servo::TelemetryRecord& r = records[n];
        r.tick = 1000000007ull + n;
        r.t_s = 0.1 * static_cast<double>(n) + 1e-13;
        for (int axis = 0; axis < 2; ++axis) {
            r.x_m[axis] =
                std::nextafter(1.0 / 3.0, 1.0) * (axis + 1) - 1e-5 * static_cast<double>(n);
            r.v_mps[axis] = -2.5e-300 * static_cast<double>(n);
            r.xe_m[axis] = 1e17 + static_cast<double>(n);
            r.f_n[axis] = -0.0 + 3.14159 * static_cast<double>(axis) - static_cast<double>(n);
        }
        r.status = servo::kStatusLate;
        r.flags = servo::kFlagSoftStart | servo::kFlagDisarmed;
        r.faults = 0;
        r.wake_latency_us = 12.5;
        r.compute_us = 0.25;
        r.energy_j = -1e-9;
    }
    const TelemetryLog log = parse(testing::daemon_csv(records, 2), "daemon.csv");
    EXPECT_EQ(log.axes, 2);
    EXPECT_EQ(log.rows(), records.size());
    const std::vector<std::string> expected_columns = {
        "tick",       "t_s",      "unix_time_s", "x0_m",
        "v0_mps",     "xe0_m",    "f0_n",        "x1_m",
        "v1_mps",     "xe1_m",    "f1_n",        "status",
        "tick_flags", "faults",   "state",       "wake_latency_us",
        "compute_us", "energy_j", "mark"};
    EXPECT_EQ(log.columns, expected_columns);
    EXPECT_EQ(log.lines.front(), 2u);
    EXPECT_EQ(log.lines.back(), 6u);
    for (std::size_t n = 0; n < records.size(); ++n) {
        const servo::TelemetryRecord& r = records[n];
        EXPECT_EQ((*log.column("tick"))[n], static_cast<double>(r.tick));
        EXPECT_EQ((*log.column("t_s"))[n], r.t_s);
        for (int axis = 0; axis < 2; ++axis) {
            const std::string i = std::to_string(axis);
            EXPECT_EQ((*log.column("x" + i + "_m"))[n], r.x_m[axis]);
            EXPECT_EQ((*log.column("v" + i + "_mps"))[n], r.v_mps[axis]);
            EXPECT_EQ((*log.column("xe" + i + "_m"))[n], r.xe_m[axis]);
            EXPECT_EQ((*log.column("f" + i + "_n"))[n], r.f_n[axis]);
        }
        EXPECT_EQ((*log.column("status"))[n], r.status);
        EXPECT_EQ((*log.column("tick_flags"))[n], r.flags);
        EXPECT_EQ((*log.column("energy_j"))[n], r.energy_j);
    }
    EXPECT_EQ(log.column("nope"), nullptr);
    EXPECT_EQ(log.where(2), "daemon.csv:4");
    EXPECT_EQ(log.where(2, "f1_n"), "daemon.csv:4:11 (f1_n)");
}

TEST(IdentificationLog, ReadsAFileFromDisk) {
    const hapticd::testing::ScratchDir dir;
    const std::string path = dir.file("run.csv");
    {
        std::ofstream out(path);
        servo::write_csv_header(out, 1);
        servo::TelemetryRecord r;
        r.t_s = 0.5;
        r.x_m[0] = 1e-5;
        r.f_n[0] = -0.25;
        servo::write_csv_record(out, r, 1);
    }
    const TelemetryLog log = read_telemetry_log(path);
    EXPECT_EQ(log.source, path);
    EXPECT_EQ(log.axes, 1);
    EXPECT_EQ((*log.column("f0_n"))[0], -0.25);
}

TEST(IdentificationLog, ReadsAScriptsLogWithOnlyTheRequiredColumns) {
    // A lab's own script: time, position and force only, in its own order, with a comment,
    // CRLF line ends, spaces, a quoted header, a '+' sign, an extra column and a blank line.
    const TelemetryLog log = parse(
        "# recorded by lab_rig.py\r\n"
        "\"f0_n\", t_s , x0_m,temperature_c\r\n"
        "+0.5, 0.000, 0.00000, 21.5\r\n"
        "\r\n"
        "-0.25, 0.001, 0.00001, 21.5\r\n"
        "3., 0.002, 1E-5, 21.6\r\n");
    EXPECT_EQ(log.axes, 1);
    EXPECT_EQ(log.rows(), 3u);
    EXPECT_EQ(log.lines, (std::vector<std::size_t>{3, 5, 6}));
    EXPECT_EQ((*log.column("f0_n"))[0], 0.5);
    EXPECT_EQ((*log.column("f0_n"))[2], 3.0);
    EXPECT_EQ((*log.column("t_s"))[1], 0.001);
    EXPECT_EQ((*log.column("x0_m"))[2], 1e-5);
    EXPECT_EQ((*log.column("temperature_c"))[2], 21.6);
    EXPECT_EQ(log.column("tick"), nullptr);
}

TEST(IdentificationLog, KeepsOnlyTheColumnsIdentificationReadsWithinTheirOwnSize) {
    // docs/identification.md, "Memory": a 172 MB daemon log once took 2 GB to identify, 12
    // parsed columns grown by doubling among the causes. The reader's memory, counted by
    // capacity: with
    // TelemetryLogOptions::identification(), the kept columns (t_s, x0_m, f0_n, status,
    // flags, faults: 6 of the daemon's 12 for one axis) at 8 bytes a row, reserved once;
    // the default keeps all 12 and the line numbers, still reserved once.
    const testing::SimulatedRun run;
    std::vector<servo::TelemetryRecord> records = testing::simulate_run(run);
    std::string csv = testing::daemon_csv(records, 1);
    // Comments and a blank line inside the rows: where() must still name the right lines.
    for (const std::size_t at : {csv.size() / 3, csv.size() / 2}) {
        const std::size_t line_end = csv.find('\n', at) + 1;
        csv.insert(line_end, "# a comment\n\n");
    }
    const TelemetryLog lean = [&] {
        std::istringstream in(csv);
        return parse_telemetry_log(in, "lean.csv", TelemetryLogOptions::identification());
    }();
    const TelemetryLog full = parse(csv, "lean.csv");
    const std::size_t n = records.size();
    ASSERT_EQ(lean.rows(), n);
    ASSERT_EQ(full.rows(), n);
    for (const char* name : {"t_s", "x0_m", "f0_n", "status", "tick_flags", "faults"}) {
        ASSERT_NE(lean.column(name), nullptr) << name;
        EXPECT_EQ(*lean.column(name), *full.column(name)) << name;
    }
    for (const char* name : {"tick", "v0_mps", "xe0_m", "wake_latency_us", "energy_j"}) {
        EXPECT_EQ(lean.column(name), nullptr) << name;
        EXPECT_NE(full.column(name), nullptr) << name;
    }
    EXPECT_TRUE(lean.lines.empty());
    for (std::size_t row = 0; row < n; ++row) {
        ASSERT_EQ(lean.where(row, "f0_n"), full.where(row, "f0_n")) << row;
        ASSERT_EQ(lean.line(row), full.lines[row]) << row;
    }
    EXPECT_EQ(lean.line_runs.size(), 3u);

    // 1 % over the kept bytes allows for the comment lines counted when reserving, and a few
    // hundred bytes for the bookkeeping; a column too many (8 bytes a row) or growth by
    // doubling (up to 16) fails.
    const auto per_row = [&](const TelemetryLog& log) {
        return static_cast<double>(log.memory_bytes()) / static_cast<double>(n);
    };
    const double lean_bound = 6 * sizeof(double) * 1.01 + 512.0 / static_cast<double>(n);
    EXPECT_LE(per_row(lean), lean_bound);
    EXPECT_GE(per_row(lean), 6 * sizeof(double));
    const double full_bound = (15 + 1) * sizeof(double) * 1.01 + 1024.0 / static_cast<double>(n);
    EXPECT_LE(per_row(full), full_bound);

    // And identification reads the same numbers from either.
    const IdentifiedAxis a = identify_axis(lean, 0);
    const IdentifiedAxis b = identify_axis(full, 0);
    EXPECT_EQ(a.estimate.mass_kg, b.estimate.mass_kg);
    EXPECT_EQ(a.estimate.damping_n_s_per_m, b.estimate.damping_n_s_per_m);
    EXPECT_EQ(a.std_error.mass_kg, b.std_error.mass_kg);
}

TEST(IdentificationLog, AStreamThatCannotSeekStillReads) {
    // A pipe cannot be read ahead to count its lines: the columns then grow as they are read.
    std::stringbuf buffer("t_s,x0_m,f0_n\n0,0,1\n0.001,1e-5,2\n");
    struct NoSeek : std::streambuf {
        explicit NoSeek(std::stringbuf* from) : from_(from) {}
        int_type underflow() override { return from_->sgetc(); }
        int_type uflow() override { return from_->sbumpc(); }
        std::stringbuf* from_;
    } pipe(&buffer);
    std::istream in(&pipe);
    const TelemetryLog log = parse_telemetry_log(in, "pipe", TelemetryLogOptions::identification());
    ASSERT_EQ(log.rows(), 2u);
    EXPECT_EQ((*log.column("f0_n"))[1], 2.0);
    EXPECT_EQ(log.where(1), "pipe:3");
}

TEST(IdentificationLog, AUserScriptsLogIdentifiesLikeTheDaemonsOwn) {
    // The same simulated run, written once by the daemon's writer and once the way a script
    // would (printf with fixed decimals, t_s/x0_m/f0_n only, a comment on top).
    const testing::SimulatedRun run;
    const std::vector<servo::TelemetryRecord> records = testing::simulate_run(run);
    std::string script = "# t in s, x in m, f in N\nt_s,x0_m,f0_n\n";
    char line[128];
    for (const servo::TelemetryRecord& r : records) {
        std::snprintf(line, sizeof line, "%.3f,%.5f,%.6f\n", r.t_s, r.x_m[0], r.f_n[0]);
        script += line;
    }
    const IdentifiedAxis daemon = identify_axis(parse(testing::daemon_csv(records, 1)), 0);
    const IdentifiedAxis user = identify_axis(parse(script, "script.csv"), 0);
    EXPECT_NEAR(user.estimate.mass_kg, daemon.estimate.mass_kg, 0.2 * daemon.std_error.mass_kg);
    EXPECT_NEAR(user.estimate.damping_n_s_per_m, daemon.estimate.damping_n_s_per_m,
                0.2 * daemon.std_error.damping_n_s_per_m);
    EXPECT_NEAR(user.estimate.coulomb_n, daemon.estimate.coulomb_n,
                0.2 * daemon.std_error.coulomb_n);
    EXPECT_NEAR(user.resolution_m, 1e-5, 1e-15);
    EXPECT_NEAR(user.rate_hz, 1000.0, 1e-6);
    EXPECT_LT(std::abs(user.estimate.mass_kg / run.mass_kg - 1.0), 0.02);
    EXPECT_LT(std::abs(user.estimate.damping_n_s_per_m / run.damping_n_s_per_m - 1.0), 0.02);
    EXPECT_LT(std::abs(user.estimate.coulomb_n / run.coulomb_n - 1.0), 0.10);
}

TEST(IdentificationLog, NamesTheFileLineAndColumnOfEveryFormatError) {
    EXPECT_CONTAINS(format_error(""), "run.csv: empty log: no header row");
    EXPECT_CONTAINS(format_error("# only a comment\n\n"), "empty log");
    const std::string no_time = format_error("tick,x0_m,f0_n\n0,0,0\n");
    EXPECT_CONTAINS(no_time, "run.csv:1: no column t_s");
    EXPECT_CONTAINS(no_time, "the header has: tick, x0_m, f0_n");
    EXPECT_CONTAINS(format_error("t_s,x0_m\n0,0\n"), "run.csv:1: column x0_m has no matching f0_n");
    EXPECT_CONTAINS(format_error("t_s,x0_m,f0_n,f1_n\n0,0,0,0\n"),
                    "column f1_n has no matching x1_m");
    EXPECT_CONTAINS(format_error("t_s,x_m,f_n\n0,0,0\n"),
                    "no axis columns: need at least x0_m and f0_n");
    EXPECT_CONTAINS(format_error("t_s,x0_m,f0_n,x0_m\n"),
                    "run.csv:1:4: column x0_m appears twice in the header");
    EXPECT_CONTAINS(format_error("t_s,,f0_n\n"), "run.csv:1:2: empty column name");
    EXPECT_CONTAINS(format_error("t_s,x0_m,f0_n\n0,0,0\n0.001,0\n"),
                    "run.csv:3: 2 fields, but the header (line 1) has 3");
    EXPECT_CONTAINS(format_error("t_s,x0_m,f0_n\n0,0,0\n# note\n0.001,abc,0\n"),
                    "run.csv:4:2 (x0_m): 'abc' is not a finite number");
    EXPECT_CONTAINS(format_error("t_s,x0_m,f0_n\n0,0,nan\n"),
                    "run.csv:2:3 (f0_n): 'nan' is not a finite number");
    EXPECT_CONTAINS(format_error("t_s,x0_m,f0_n\n0,0,1e999\n"), "'1e999' is not a finite number");
    EXPECT_CONTAINS(format_error("t_s,x0_m,f0_n\n0,,1\n"), "run.csv:2:2 (x0_m): '' is not");
    EXPECT_CONTAINS(format_error("t_s,x0_m,f0_n\n0,0x10,1\n"), "'0x10' is not");
    try {
        read_telemetry_log("/nonexistent/run.csv");
        ADD_FAILURE();
    } catch (const LogFormatError& e) {
        EXPECT_CONTAINS(e.what(), "/nonexistent/run.csv: cannot open the log");
    }
}

TEST(IdentificationLog, AcceptsAByteOrderMark) {
    const TelemetryLog log = parse("\xEF\xBB\xBFt_s,x0_m,f0_n\n0,0,0\n");
    EXPECT_EQ(log.columns.front(), "t_s");
}

}  // namespace
}  // namespace hapticd::tune
