// Reads and validates the [device.sim] table (schema: docs/sim-device.md).
#include "hapticd/device/sim/sim_config.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "hapticd/device/plugin_table.hpp"
#include "hapticd/device/sim/command_pipeline.hpp"

namespace hapticd::device::sim {
namespace {

using input::Integer;
using input::Number;
using input::Range;

constexpr Range kMass{.lo = 0.0, .hi = 1e3, .lo_open = true, .unit = "kg"};
constexpr Range kDamping{.lo = 0.0, .hi = 1e6, .unit = "N s/m"};
constexpr Range kStiffness{.lo = 0.0, .hi = 1e9, .unit = "N/m"};
constexpr Range kPosition{.lo = -10.0, .hi = 10.0, .unit = "m"};
constexpr Range kDuration{.lo = 0.0, .hi = 1e6, .unit = "s"};
constexpr Range kFaultTime{.lo = 0.0, .hi = 1e9, .unit = "s"};
constexpr Range kProbability{.lo = 0.0, .hi = 1.0};

std::string_view to_string(HumanFamily family) noexcept {
    switch (family) {
        case HumanFamily::hands_off:
            return "hands-off";
        case HumanFamily::heavy_hand:
            return "heavy-hand";
        case HumanFamily::stiff_grasp:
            return "stiff-grasp";
        case HumanFamily::two_mass_grasp:
            return "two-mass-grasp";
        case HumanFamily::multi_mode_grasp:
            return "multi-mode-grasp";
    }
    return "hands-off";
}
constexpr HumanFamily kFamilies[] = {HumanFamily::hands_off, HumanFamily::heavy_hand,
                                     HumanFamily::stiff_grasp, HumanFamily::two_mass_grasp,
                                     HumanFamily::multi_mode_grasp};
constexpr input::Choice<HumanFamily> kModel{"model", kFamilies, &to_string, HumanFamily::hands_off};

std::string_view to_string(SimClock clock) noexcept {
    return clock == SimClock::lockstep ? "lockstep" : "realtime";
}
constexpr SimClock kClocks[] = {SimClock::lockstep, SimClock::realtime};
constexpr input::Choice<SimClock> kClock{"clock", kClocks, &to_string, SimConfig{}.clock};

/// A key that the chosen model does not use is an error, so a typo in the model name or a
/// parameter meant for another model is never silently ignored.
void require_unused(TableReader& r, std::string_view key, HumanFamily model) {
    if (r.has(key)) {
        r.get(key);
        r.fail(key, "is not used by model = \"" + std::string(to_string(model)) + "\": remove it");
    }
}

/// A multi-mode grasp's [[modes]]: 1 to kMaxOperatorModes absorbers.
void read_modes(TableReader& r, HumanModel& h) {
    const toml::array* modes = r.array_of_tables("modes");
    const std::size_t count = modes == nullptr ? 0 : modes->size();
    if (count < 1 || count > static_cast<std::size_t>(kMaxOperatorModes)) {
        r.fail("modes", "has " + std::to_string(count) + " absorbers",
               "1 to " + std::to_string(kMaxOperatorModes) + " tables [[" + r.path("modes") +
                   "]], each { mass, stiffness, damping }");
    }
    h.mode_count = static_cast<int>(count);
    for (std::size_t i = 0; i < count; ++i) {
        TableReader m = r.nested(*modes->get(i)->as_table(), "modes", static_cast<int>(i) + 1);
        m.only({"mass", "stiffness", "damping"});
        h.modes[i] = {m.read(Number{"mass", kMass}),
                      m.read(Number{"stiffness",
                                    Range{.lo = 0.0, .hi = 1e9, .lo_open = true, .unit = "N/m"}}),
                      m.read(Number{"damping", kDamping, 0.0})};
        m.finish();
    }
}

HumanModel read_human(TableReader& r, double initial_position_m) {
    HumanModel h;
    h.family = r.read(kModel);
    const bool multi_mode = h.family == HumanFamily::multi_mode_grasp;
    const bool rigid_hand =
        h.family == HumanFamily::heavy_hand || h.family == HumanFamily::stiff_grasp || multi_mode;
    const bool two_mass = h.family == HumanFamily::two_mass_grasp;
    const bool set_point = h.family == HumanFamily::stiff_grasp || two_mass || multi_mode;

    auto param = [&](std::string_view key, bool used, double fallback, const Range& range) {
        if (!used) {
            require_unused(r, key, h.family);
            return 0.0;
        }
        return r.read(Number{key, range, fallback});
    };
    // A multi-mode grasp's absorbers are the grasp: no hand mass or spring unless given.
    h.hand_mass_kg = two_mass ? r.read(Number{"hand_mass", kMass, 0.5})
                              : param("hand_mass", rigid_hand, multi_mode ? 0.0 : 0.5,
                                      Range{.lo = 0.0, .hi = 1e3, .unit = "kg"});
    h.hand_damping_n_s_per_m = param("hand_damping", rigid_hand, 0.0, kDamping);
    h.hand_stiffness_n_per_m =
        param("hand_stiffness", h.family == HumanFamily::stiff_grasp || multi_mode,
              multi_mode ? 0.0 : 1000.0, kStiffness);
    if (multi_mode) {
        read_modes(r, h);
    } else {
        require_unused(r, "modes", h.family);
    }
    h.skin_stiffness_n_per_m = param("skin_stiffness", two_mass, 1000.0, kStiffness);
    h.skin_damping_n_s_per_m = param("skin_damping", two_mass, 1.0, kDamping);
    h.arm_stiffness_n_per_m = param("arm_stiffness", two_mass, 100.0, kStiffness);
    h.arm_damping_n_s_per_m = param("arm_damping", two_mass, 10.0, kDamping);

    h.push.from_m = initial_position_m;
    h.push.to_m = initial_position_m;
    if (!set_point) {
        require_unused(r, "set_point", h.family);
        require_unused(r, "push", h.family);
    } else {
        h.push.from_m = h.push.to_m = r.read(Number{"set_point", kPosition, initial_position_m});
        if (const toml::table* push = r.subtable("push")) {
            TableReader p = r.nested(*push, "push");
            h.push.to_m = p.read(Number{"to", kPosition, h.push.from_m});
            h.push.start_s = p.read(Number{"start", kDuration, 0.0});
            h.push.ramp_s = p.read(Number{"ramp", kDuration, 0.0});
            h.push.hold_s = p.read(Number{"hold", kDuration, 0.0});
            p.finish();
        }
    }
    r.finish();
    return h;
}

/// A list of times, s, each >= 0 (none when absent).
std::vector<double> read_times(TableReader& r, std::string_view key) {
    const toml::node* node = r.get(key);
    std::vector<double> values;
    if (node == nullptr) return values;
    const auto* array = node->as_array();
    if (array == nullptr) r.fail(key, "is not an array", "an array of times >= 0 (s)");
    for (const toml::node& element : *array) {
        values.push_back(r.number(element, key, Range{.lo = 0.0, .unit = "s"}));
    }
    return values;
}

FaultConfig read_faults(TableReader& r, int axes) {
    FaultConfig f;
    f.disconnect_at_s = r.read(Number{"disconnect_at", kFaultTime, -1.0});
    f.stale_at_s = r.read(Number{"stale_at", kFaultTime, -1.0});
    f.stale_for_s = r.read(
        Number{"stale_for", Range{.lo = 0.0, .hi = 1e9, .lo_open = true, .unit = "s"}, -1.0});
    f.jump_at_s = r.read(Number{"jump_at", kFaultTime, -1.0});
    f.jump_counts =
        r.read(Integer{"jump_counts", -(std::int64_t{1} << 40), std::int64_t{1} << 40, 0});
    f.jump_axis = static_cast<int>(r.read(Integer{"jump_axis", 0, axes - 1, 0}));
    f.drop_at_s = read_times(r, "drop_at");
    f.drop_probability = r.read(Number{"drop_probability", kProbability, 0.0});
    f.late_at_s = read_times(r, "late_at");
    f.late_probability = r.read(Number{"late_probability", kProbability, 0.0});
    f.late_by_s = r.read(Number{"late_by", Range{.lo = 0.0, .hi = 1.0, .unit = "s"}, 0.0});
    f.seed = static_cast<std::uint64_t>(
        r.read(Integer{"seed", 0, std::numeric_limits<std::int64_t>::max(), 1}));
    r.finish();
    return f;
}

}  // namespace

SimConfig parse_sim_config(const DeviceConfig& config) {
    const std::string& source = config.source;
    SimConfig c;
    if (config.axes < 1 || config.axes > kMaxAxes) {
        throw input::ConfigError(
            source + ": " +
            input::out_of_range("device.axes", config.axes,
                                "1.." + std::to_string(kMaxAxes) + " (the sim device's axes)"));
    }
    if (!std::isfinite(config.rate_hz) || config.rate_hz <= 0.0 || config.rate_hz > 1e6) {
        throw input::ConfigError(source + ": " +
                                 input::out_of_range("servo.rate_hz", config.rate_hz,
                                                     "> 0 and <= 1e+06 (Hz, the sim device)"));
    }
    c.axes = config.axes;
    c.rate_hz = config.rate_hz;

    PluginTable table(config, "sim", "docs/sim-device.md");
    TableReader& r = table.reader();
    c.mass_kg = r.read(Number{"mass", kMass, c.mass_kg});
    c.damping_n_s_per_m = r.read(Number{"damping", kDamping, c.damping_n_s_per_m});
    c.counts_per_meter = r.read(Number{
        "counts_per_meter", Range{.lo = 0.0, .hi = 1e10, .lo_open = true, .unit = "counts/m"},
        c.counts_per_meter});
    c.force_limit_n = r.read(Number{
        "force_limit", Range{.lo = 0.0, .hi = 1e4, .lo_open = true, .unit = "N"}, c.force_limit_n});
    c.coulomb_n = r.read(Number{"coulomb", Range{.lo = 0.0, .hi = 1e3, .unit = "N"}, c.coulomb_n});
    c.clock = r.read(kClock);
    if (config.lockstep) c.clock = SimClock::lockstep;
    c.delay_s = r.read_periods("delay", kMaxDelayPeriods, c.rate_hz);

    if (const toml::node* node = r.get("initial_position")) {
        if (const auto* array = node->as_array()) {
            if (static_cast<int>(array->size()) != c.axes) {
                r.fail("initial_position", "has " + std::to_string(array->size()) + " components",
                       "a position or an array of " + std::to_string(c.axes) + " positions, each " +
                           kPosition.describe());
            }
            for (int i = 0; i < c.axes; ++i) {
                c.initial_position_m[i] = r.number(*array->get(i), "initial_position", kPosition);
            }
        } else {
            const double x = r.number(*node, "initial_position", kPosition);
            c.initial_position_m.fill(x);
        }
    }

    for (int i = 0; i < c.axes; ++i)
        c.human[i].push.from_m = c.human[i].push.to_m = c.initial_position_m[i];
    if (const toml::node* node = r.get("human")) {
        if (const auto* one = node->as_table()) {
            for (int i = 0; i < c.axes; ++i) {
                TableReader human = r.nested(*one, "human");
                c.human[i] = read_human(human, c.initial_position_m[i]);
            }
        } else if (const auto* each = node->as_array(); each != nullptr &&
                                                        each->is_array_of_tables() &&
                                                        static_cast<int>(each->size()) == c.axes) {
            for (int i = 0; i < c.axes; ++i) {
                TableReader human = r.nested(*each->get(i)->as_table(), "human", i + 1);
                c.human[i] = read_human(human, c.initial_position_m[i]);
            }
        } else {
            r.fail("human", "is not allowed",
                   "a table [" + r.path("human") + "] (every axis) or " + std::to_string(c.axes) +
                       " tables [[" + r.path("human") + "]] (one per axis)");
        }
    }
    if (const toml::table* faults = r.subtable("faults")) {
        TableReader f = r.nested(*faults, "faults");
        c.faults = read_faults(f, c.axes);
    }
    r.finish();
    return c;
}

}  // namespace hapticd::device::sim
