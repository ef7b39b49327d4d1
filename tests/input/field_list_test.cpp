// Field lists (field_list.hpp): a struct filled from its list, through nested settings
// structs, with a rule's field left to its section; and the reference rows.
#include "hapticd/input/field_list.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "hapticd/input/table_reader.hpp"

namespace hapticd::input {
namespace {

enum class Mode { fast, slow };
std::string_view name_of(Mode mode) { return mode == Mode::fast ? "fast" : "slow"; }
constexpr Mode kModes[] = {Mode::fast, Mode::slow};

struct Inner {
    double settle_s = 0.5;
    bool enabled = true;
};

constexpr Number kRate{"rate_hz", {.lo = 100.0, .hi = 20000.0, .unit = "Hz"}, 1000.0, "rate"};
constexpr Number kMass{
    "mass", {.lo = 0.0, .hi = 1e3, .lo_open = true, .unit = "kg"}, std::nullopt, "mass"};
constexpr Integer kAxes{"axes", 1, 3, std::nullopt, "", "axes"};
constexpr Text kLabel{"label", "", true, "free text", "a label", 8};
constexpr Choice<Mode> kMode{"mode", kModes, &name_of, Mode::slow, "speed"};
constexpr Number kSettle{
    "settle", {.lo = 0.0, .hi = 60.0, .lo_open = true, .unit = "s"}, Inner{}.settle_s, "settle"};
constexpr Flag kEnabled{"enabled", Inner{}.enabled, "on"};
constexpr Number kFilter{"filter", {.unit = "Hz"}, 0.0, "cutoff", "0 or < rate_hz/2 (Hz)"};

struct Settings {
    double rate_hz = *kRate.default_value;
    std::optional<double> mass_kg;
    int axes = 1;
    std::string label;
    Mode mode = kMode.default_value;
    Inner inner;
    double filter_hz = -1.0;  // the section reads it
};
constexpr auto kSettingsFields = fields<Settings>(
    "t", bind(kRate, &Settings::rate_hz), bind(kMass, &Settings::mass_kg),
    bind(kAxes, &Settings::axes), bind(kLabel, &Settings::label), bind(kMode, &Settings::mode),
    bind(kSettle, &Settings::inner, &Inner::settle_s),
    bind(kEnabled, &Settings::inner, &Inner::enabled), bind(kFilter, &Settings::filter_hz));

Settings read(const std::string& text) {
    const toml::table document = parse_document(text, "lab.toml");
    TableReader file(document, "lab.toml", "");
    TableReader t = file.nested(*file.subtable("t"), "t");
    Settings settings;
    read_fields(t, settings, kSettingsFields);
    return settings;
}

TEST(InputFieldList, FillsEveryBoundMemberThroughNestedStructs) {
    const Settings s = read(
        "[t]\nrate_hz = 2000\nmass = 0.25\naxes = 3\nlabel = \"rig 2\"\nmode = \"fast\"\n"
        "settle = 1.5\nenabled = false\nfilter = 30\n");
    EXPECT_EQ(s.rate_hz, 2000.0);
    EXPECT_EQ(s.mass_kg, 0.25);
    EXPECT_EQ(s.axes, 3);
    EXPECT_EQ(s.label, "rig 2");
    EXPECT_EQ(s.mode, Mode::fast);
    EXPECT_EQ(s.inner.settle_s, 1.5);
    EXPECT_FALSE(s.inner.enabled);
    EXPECT_EQ(s.filter_hz, -1.0) << "a field with a rule is its section's to read";
}

TEST(InputFieldList, AnAbsentKeyTakesItsDefaultOrStaysNone) {
    const Settings s = read("[t]\naxes = 2\n");
    EXPECT_EQ(s.rate_hz, 1000.0);
    EXPECT_FALSE(s.mass_kg.has_value());
    EXPECT_EQ(s.mode, Mode::slow);
    EXPECT_EQ(s.inner.settle_s, 0.5);
    EXPECT_TRUE(s.inner.enabled);
}

TEST(InputFieldList, RefusesAsTheReaderDoes) {
    const auto error = [](const std::string& text) -> std::string {
        try {
            (void)read(text);
        } catch (const ConfigError& e) {
            return e.what();
        }
        return "no error";
    };
    EXPECT_EQ(error("[t]\n"), "lab.toml:1: [t] axes is missing: required, allowed 1..3");
    EXPECT_EQ(error("[t]\naxes = 1\nsettle = 0\n"),
              "lab.toml:3: [t] settle = 0 is out of range: allowed > 0 and <= 60 (s)");
    EXPECT_EQ(error("[t]\naxes = 1\nlabel = \"123456789\"\n"),
              "lab.toml:3: [t] label = \"123456789\" is too long (9 bytes): allowed free text, "
              "at most 8 bytes");
}

TEST(InputFieldList, RowsSayKeyAllowedDefaultAndHelp) {
    const std::vector<FieldRow> r = rows(kSettingsFields);
    ASSERT_EQ(r.size(), 8u);
    EXPECT_EQ(r[0].table, "t");
    EXPECT_EQ(r[0].key, "rate_hz");
    EXPECT_EQ(r[0].allowed, ">= 100 and <= 20000 (Hz)");
    EXPECT_EQ(r[0].default_value, "1000");
    EXPECT_EQ(r[0].help, "rate");
    EXPECT_EQ(r[1].default_value, "none");      // an optional member without a default
    EXPECT_EQ(r[2].default_value, "required");  // a plain member without a default
    EXPECT_EQ(r[3].allowed, "free text, at most 8 bytes, without control characters");
    EXPECT_EQ(r[3].default_value, "\"\"");
    EXPECT_EQ(r[4].allowed, "\"fast\" or \"slow\"");
    EXPECT_EQ(r[4].default_value, "\"slow\"");
    EXPECT_EQ(r[5].key, "settle");
    EXPECT_EQ(r[5].default_value, "0.5");
    EXPECT_EQ(r[6].allowed, "true, false");
    EXPECT_EQ(r[6].default_value, "true");
    EXPECT_EQ(r[7].allowed, "0 or < rate_hz/2 (Hz)");
}

}  // namespace
}  // namespace hapticd::input
