// The one TOML field reader: declared fields, their defaults and ranges, and the one
// message form "FILE:LINE: TABLE KEY = VALUE PROBLEM: allowed ALLOWED".
#include "hapticd/input/table_reader.hpp"

#include <gtest/gtest.h>

#include <string>

namespace hapticd::input {
namespace {

enum class Mode { fast, slow };
std::string_view name_of(Mode mode) { return mode == Mode::fast ? "fast" : "slow"; }
constexpr Mode kModes[] = {Mode::fast, Mode::slow};

constexpr Number kRate{"rate_hz", {.lo = 100.0, .hi = 20000.0, .unit = "Hz"}, 1000.0};
constexpr Number kMass{"mass", {.lo = 0.0, .hi = 1e3, .lo_open = true, .unit = "kg"}};
constexpr Integer kAxes{"axes", 1, 3, 1};
constexpr Flag kOn{"on", true};
constexpr Text kName{"name", std::nullopt, false, "a non-empty name"};
constexpr Choice<Mode> kMode{"mode", kModes, &name_of, Mode::slow};

/// The message reading `text`'s [t] with `read` throws ("no error" if none).
template <typename Read>
std::string error_of(const std::string& text, Read read) {
    try {
        const toml::table document = parse_document(text, "lab.toml");
        TableReader file(document, "lab.toml", "");
        TableReader t = file.nested(*file.subtable("t"), "t");
        read(t);
        t.finish();
        file.finish();
    } catch (const ConfigError& e) {
        return e.what();
    }
    return "no error";
}

TEST(InputTableReader, ReadsDeclaredFieldsWithTheirDefaults) {
    const toml::table document =
        parse_document("[t]\nrate_hz = 2000\non = false\nmode = \"fast\"\nname = \"x\"\n", "f");
    TableReader t(*document["t"].as_table(), "f", "t");
    EXPECT_EQ(t.read(kRate), 2000.0);
    EXPECT_FALSE(t.read(kOn));
    EXPECT_EQ(t.read(kMode), Mode::fast);
    EXPECT_EQ(t.read(kName), "x");
    EXPECT_EQ(t.read(kAxes), 1);                      // absent: the default
    EXPECT_EQ(t.read_optional(kMass), std::nullopt);  // absent, no default
    EXPECT_NO_THROW(t.finish());

    const toml::table empty;
    TableReader e(empty, "f", "t");
    EXPECT_EQ(e.read(kRate), 1000.0);
    EXPECT_TRUE(e.read(kOn));
    EXPECT_EQ(e.read(kMode), Mode::slow);
}

TEST(InputTableReader, EveryMessageNamesTheFileLineTableKeyValueAndRange) {
    EXPECT_EQ(error_of("[t]\n\nrate_hz = 50\n", [](TableReader& t) { (void)t.read(kRate); }),
              "lab.toml:3: [t] rate_hz = 50 is out of range: allowed >= 100 and <= 20000 (Hz)");
    EXPECT_EQ(error_of("[t]\nrate_hz = \"fast\"\n", [](TableReader& t) { (void)t.read(kRate); }),
              "lab.toml:2: [t] rate_hz = \"fast\" is not a number: allowed >= 100 and <= 20000 "
              "(Hz)");
    EXPECT_EQ(error_of("[t]\nrate_hz = nan\n", [](TableReader& t) { (void)t.read(kRate); }),
              "lab.toml:2: [t] rate_hz = nan is out of range: allowed >= 100 and <= 20000 (Hz)");
    EXPECT_EQ(error_of("[t]\n", [](TableReader& t) { (void)t.read(kMass); }),
              "lab.toml:1: [t] mass is missing: required, allowed > 0 and <= 1000 (kg)");
    EXPECT_EQ(error_of("[t]\naxes = 4\n", [](TableReader& t) { (void)t.read(kAxes); }),
              "lab.toml:2: [t] axes = 4 is out of range: allowed 1..3");
    EXPECT_EQ(error_of("[t]\naxes = 2.0\n", [](TableReader& t) { (void)t.read(kAxes); }),
              "lab.toml:2: [t] axes = 2.0 is not an integer: allowed 1..3");
    EXPECT_EQ(error_of("[t]\non = 1\n", [](TableReader& t) { (void)t.read(kOn); }),
              "lab.toml:2: [t] on = 1 is not a boolean: allowed true or false");
    EXPECT_EQ(error_of("[t]\nmode = \"medium\"\n", [](TableReader& t) { (void)t.read(kMode); }),
              "lab.toml:2: [t] mode = \"medium\" is not allowed: allowed \"fast\" or \"slow\"");
    EXPECT_EQ(error_of("[t]\nname = \"\"\n", [](TableReader& t) { (void)t.read(kName); }),
              "lab.toml:2: [t] name = \"\" is empty: allowed a non-empty name");
}

// A string with a control character is refused (a scene's name goes to the journal and to
// other operators' terminals: an escape sequence there cleared their screens), and no
// message carries one: the value and the key are shown written out.
TEST(InputTableReader, ControlCharactersAreRefusedAndNeverEchoed) {
    EXPECT_EQ(error_of("[t]\nname = \"wall\\u001b[2Jstate disabled\"\n",
                       [](TableReader& t) { (void)t.read(kName); }),
              "lab.toml:2: [t] name = \"wall\\x1b[2Jstate disabled\" holds a control character at "
              "byte 5: allowed a non-empty name without control characters");
    EXPECT_EQ(error_of("[t]\nname = \"a\\n<0>b\"\n", [](TableReader& t) { (void)t.read(kName); }),
              "lab.toml:2: [t] name = \"a\\x0a<0>b\" holds a control character at byte 2: allowed "
              "a non-empty name without control characters");
    // A key of the file's own with one, unknown: written out too.
    EXPECT_EQ(error_of("[t]\n\"k\\u001b]0;x\\u0007\" = 1\n", [](TableReader&) {}).substr(0, 33),
              "lab.toml:2: [t] k\\x1b]0;x\\x07 = 1");
}

TEST(InputTableReader, UnknownKeysAndTablesAreRefusedListingTheKnownOnes) {
    EXPECT_EQ(error_of("[t]\nrate_hz = 1000\nrate = 1000\n",
                       [](TableReader& t) {
                           (void)t.read(kRate);
                           (void)t.read(kAxes);
                       }),
              "lab.toml:3: [t] rate = 1000 is not a known key: allowed rate_hz, axes");
    EXPECT_EQ(error_of("[t]\n[t.sub]\nx = 1\n", [](TableReader& t) { (void)t.read(kRate); }),
              "lab.toml:2: [t.sub] is not a known table: allowed rate_hz");
    EXPECT_EQ(error_of("[t]\n[u]\n", [](TableReader&) {}),
              "lab.toml:2: [u] is not a known table: allowed [t]");
    // only(): a misspelt required key is named as unknown before anything is read.
    EXPECT_EQ(error_of("[t]\nmas = 1\n",
                       [](TableReader& t) {
                           t.only({"mass"});
                           (void)t.read(kMass);
                       }),
              "lab.toml:2: [t] mas = 1 is not a known key: allowed mass");
    const toml::table document = parse_document("x = 1\n", "p.toml");
    TableReader documented(document, "p.toml", "device.p", 0, "docs/p.md");
    EXPECT_THROW(documented.finish(), ConfigError);
    try {
        documented.finish();
    } catch (const ConfigError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "p.toml:1: [device.p] x = 1 is not a known key: allowed no keys (docs/p.md)");
    }
}

TEST(InputTableReader, AnArrayOfTablesIsNamedByItsPlace) {
    const toml::table document = parse_document("[[w]]\nk = 1\n[[w]]\nk = -1\n", "s.toml");
    TableReader file(document, "s.toml", "");
    const toml::array* walls = file.array_of_tables("w");
    ASSERT_NE(walls, nullptr);
    TableReader second = file.nested(*walls->get(1)->as_table(), "w", 2);
    try {
        (void)second.read(Number{"k", {.lo = 0.0, .lo_open = true, .unit = "N/m"}});
        FAIL() << "accepted k = -1";
    } catch (const ConfigError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "s.toml:4: [[w]] #2 k = -1 is out of range: allowed > 0 (N/m)");
    }
}

TEST(InputTableReader, ValuesArePrintedAsWritten) {
    const toml::table document =
        parse_document("h = 0x1209\nf = 115200.0\ne = 2e9\na = [1, \"x\"]\n", "v.toml");
    EXPECT_EQ(format_value(*document.get("h")), "0x1209");
    EXPECT_EQ(format_value(*document.get("f")), "115200.0");
    EXPECT_EQ(format_value(*document.get("e")), "2e+09");
    EXPECT_EQ(format_value(*document.get("a")), "[1, \"x\"]");
}

TEST(InputTableReader, APeriodBoundIsCheckedInPeriods) {
    const auto error = [](const std::string& value) {
        return error_of("[t]\ndelay = " + value + "\n",
                        [](TableReader& t) { (void)t.read_periods("delay", 10.0, 1000.0); });
    };
    EXPECT_EQ(error("0.0099"), "no error");
    for (const char* bad : {"0.01", "-0.001", "inf", "\"1 ms\""}) {
        EXPECT_NE(
            error(bad).find(": allowed >= 0 and < 0.01 (s: 10 periods at [servo] rate_hz = 1000)"),
            std::string::npos)
            << error(bad);
    }
}

TEST(InputTableReader, SyntaxErrorsAndMissingTablesNameTheFile) {
    try {
        (void)parse_document("[t\n", "bad.toml");
        FAIL() << "parsed";
    } catch (const ConfigError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("bad.toml:1:", 0), 0u) << e.what();
        EXPECT_NE(std::string(e.what()).find("TOML syntax error"), std::string::npos);
    }
    const toml::table document = parse_document("[device]\nsim = 3\n", "c.toml");
    EXPECT_EQ(table_at(document, "device.usb", "c.toml"), nullptr);
    EXPECT_NE(table_at(document, "device", "c.toml"), nullptr);
    EXPECT_THROW((void)table_at(document, "device.sim", "c.toml"), ConfigError);
}

TEST(InputRange, TheOneOutOfRangeMessage) {
    EXPECT_EQ(out_of_range("servo config: rate_hz", 50.0,
                           (Range{.lo = 100.0, .hi = 20000.0, .unit = "Hz"})),
              "servo config: rate_hz = 50 is out of range: allowed >= 100 and <= 20000 (Hz)");
    EXPECT_EQ((Range{.lo = 0.0, .lo_open = true}.describe()), "> 0");
    EXPECT_EQ((Range{.hi = 0.5, .unit = "at most static_coefficient"}.describe()),
              "<= 0.5 (at most static_coefficient)");
    EXPECT_FALSE((Range{}.contains(std::numeric_limits<double>::infinity())));
    EXPECT_THROW(reject_out_of_range("x", 1.0, "2..3"), std::invalid_argument);
    std::string error;
    EXPECT_FALSE(invalid(&error, "why"));
    EXPECT_EQ(error, "why");
    EXPECT_FALSE(invalid(nullptr, "why"));
}

}  // namespace
}  // namespace hapticd::input
