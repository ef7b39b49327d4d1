// Reads and validates the [device.sim] table (schema: docs/sim-device.md).
#include "hapticd/device/sim/sim_config.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include "hapticd/device/sim/command_pipeline.hpp"
#include "hapticd/device/table_reader.hpp"
#include "hapticd/input/text_input.hpp"

namespace hapticd::device::sim {
namespace {

using device::kInf;
using device::Range;
using device::TableReader;

constexpr Range kMass{0.0, 1e3, true, "kg"};
constexpr Range kDamping{0.0, 1e6, false, "N s/m"};
constexpr Range kStiffness{0.0, 1e9, false, "N/m"};
constexpr Range kPosition{-10.0, 10.0, false, "m"};
constexpr Range kDuration{0.0, 1e6, false, "s"};

std::optional<HumanFamily> family_named(std::string_view name) {
    if (name == "hands-off") return HumanFamily::hands_off;
    if (name == "heavy-hand") return HumanFamily::heavy_hand;
    if (name == "stiff-grasp") return HumanFamily::stiff_grasp;
    if (name == "two-mass-grasp") return HumanFamily::two_mass_grasp;
    return std::nullopt;
}

/// A key that the chosen model does not use is an error, so a typo in the model name or a
/// parameter meant for another model is never silently ignored.
void require_unused(TableReader& r, std::string_view key, std::string_view model) {
    if (r.has(key)) {
        r.get(key);
        r.fail(key, "is not used by model = \"" + std::string(model) + "\"; remove it");
    }
}

HumanModel read_human(const toml::table& table, std::string prefix, const std::string& source,
                      double initial_position_m) {
    TableReader r(table, std::move(prefix), source, "docs/sim-device.md");
    const std::string model = r.choice(
        "model", "hands-off", {"hands-off", "heavy-hand", "stiff-grasp", "two-mass-grasp"});
    HumanModel h;
    h.family = *family_named(model);
    const bool rigid_hand =
        h.family == HumanFamily::heavy_hand || h.family == HumanFamily::stiff_grasp;
    const bool two_mass = h.family == HumanFamily::two_mass_grasp;
    const bool set_point = h.family == HumanFamily::stiff_grasp || two_mass;

    auto param = [&](std::string_view key, bool used, double fallback, const Range& range) {
        if (!used) {
            require_unused(r, key, model);
            return 0.0;
        }
        return r.number(key, fallback, range);
    };
    h.hand_mass_kg = two_mass ? r.number("hand_mass", 0.5, kMass)
                              : param("hand_mass", rigid_hand, 0.5, Range{0.0, 1e3, false, "kg"});
    h.hand_damping_n_s_per_m = param("hand_damping", rigid_hand, 0.0, kDamping);
    h.hand_stiffness_n_per_m =
        param("hand_stiffness", h.family == HumanFamily::stiff_grasp, 1000.0, kStiffness);
    h.skin_stiffness_n_per_m = param("skin_stiffness", two_mass, 1000.0, kStiffness);
    h.skin_damping_n_s_per_m = param("skin_damping", two_mass, 1.0, kDamping);
    h.arm_stiffness_n_per_m = param("arm_stiffness", two_mass, 100.0, kStiffness);
    h.arm_damping_n_s_per_m = param("arm_damping", two_mass, 10.0, kDamping);

    h.push.from_m = initial_position_m;
    h.push.to_m = initial_position_m;
    if (!set_point) {
        require_unused(r, "set_point", model);
        require_unused(r, "push", model);
    } else {
        h.push.from_m = h.push.to_m = r.number("set_point", initial_position_m, kPosition);
        if (const toml::table* push = r.subtable("push")) {
            TableReader p(*push, r.prefix() + "push.", source, "docs/sim-device.md");
            h.push.to_m = p.number("to", h.push.from_m, kPosition);
            h.push.start_s = p.number("start", 0.0, kDuration);
            h.push.ramp_s = p.number("ramp", 0.0, kDuration);
            h.push.hold_s = p.number("hold", 0.0, kDuration);
            p.finish();
        }
    }
    r.finish();
    return h;
}

FaultConfig read_faults(const toml::table& table, const std::string& source, int axes) {
    TableReader r(table, "device.sim.faults.", source, "docs/sim-device.md");
    FaultConfig f;
    const Range time{0.0, 1e9, false, "s"};
    f.disconnect_at_s = r.number("disconnect_at", -1.0, time);
    f.stale_at_s = r.number("stale_at", -1.0, time);
    f.stale_for_s = r.number("stale_for", -1.0, Range{0.0, 1e9, true, "s"});
    f.jump_at_s = r.number("jump_at", -1.0, time);
    f.jump_counts = r.integer("jump_counts", 0, -(std::int64_t{1} << 40), std::int64_t{1} << 40);
    f.jump_axis = static_cast<int>(r.integer("jump_axis", 0, 0, axes - 1));
    f.drop_at_s = r.times("drop_at");
    f.drop_probability = r.number("drop_probability", 0.0, Range{0.0, 1.0, false, ""});
    f.late_at_s = r.times("late_at");
    f.late_probability = r.number("late_probability", 0.0, Range{0.0, 1.0, false, ""});
    f.late_by_s = r.number("late_by", 0.0, Range{0.0, 1.0, false, "s"});
    f.seed = static_cast<std::uint64_t>(
        r.integer("seed", 1, 0, std::numeric_limits<std::int64_t>::max()));
    r.finish();
    return f;
}

/// [device.sim] delay: finite, >= 0 and below kMaxDelayPeriods periods of the servo rate.
double read_delay(TableReader& r, double rate_hz) {
    const toml::node* node = r.get("delay");
    if (node == nullptr) return 0.0;
    std::optional<double> value;
    if (const auto* f = node->as_floating_point()) value = f->get();
    if (const auto* i = node->as_integer()) value = static_cast<double>(i->get());
    const double max_s = kMaxDelayPeriods / rate_hz;
    if (!value || !std::isfinite(*value) || *value < 0.0 ||
        !(*value * rate_hz < kMaxDelayPeriods)) {
        std::ostringstream allowed;
        allowed << "a number >= 0 and < " << max_s << " (s: " << kMaxDelayPeriods
                << " periods at servo.rate_hz = " << rate_hz << " Hz)";
        r.fail_value("delay", *node, allowed.str());
    }
    return *value;
}

}  // namespace

SimConfig parse_sim_config(const DeviceConfig& config) {
    const std::string& source = config.source;
    SimConfig c;
    if (config.axes < 1 || config.axes > kMaxAxes) {
        throw std::runtime_error(source + ": device.axes = " + std::to_string(config.axes) +
                                 " is not allowed: the sim device has 1 to " +
                                 std::to_string(kMaxAxes) + " axes");
    }
    if (!std::isfinite(config.rate_hz) || config.rate_hz <= 0.0 || config.rate_hz > 1e6) {
        std::ostringstream s;
        s << source << ": servo.rate_hz = " << config.rate_hz
          << " is not allowed: the sim device needs a rate > 0 and <= 1e6 Hz";
        throw std::runtime_error(s.str());
    }
    c.axes = config.axes;
    c.rate_hz = config.rate_hz;

    if (const std::string e = input::toml_shape_error(config.plugin_table_toml, source);
        !e.empty()) {
        throw std::runtime_error(e);
    }
    toml::table table;
    try {
        table = toml::parse(config.plugin_table_toml, source);
    } catch (const toml::parse_error& e) {
        std::ostringstream s;
        s << source << ": [device.sim] is not valid TOML: " << e.description();
        throw std::runtime_error(s.str());
    }
    TableReader r(table, "device.sim.", source, "docs/sim-device.md");
    c.mass_kg = r.number("mass", c.mass_kg, kMass);
    c.damping_n_s_per_m = r.number("damping", c.damping_n_s_per_m, kDamping);
    c.counts_per_meter =
        r.number("counts_per_meter", c.counts_per_meter, Range{0.0, 1e10, true, "counts/m"});
    c.force_limit_n = r.number("force_limit", c.force_limit_n, Range{0.0, 1e4, true, "N"});
    c.coulomb_n = r.number("coulomb", c.coulomb_n, Range{0.0, 1e3, false, "N"});
    c.clock = r.choice("clock", "realtime", {"lockstep", "realtime"}) == "lockstep"
                  ? SimClock::lockstep
                  : SimClock::realtime;
    if (config.lockstep) c.clock = SimClock::lockstep;
    c.delay_s = read_delay(r, c.rate_hz);

    if (const toml::node* node = r.get("initial_position")) {
        const std::string allowed = "a position or an array of " + std::to_string(c.axes) +
                                    " positions, each " + kPosition.describe();
        if (const auto* array = node->as_array()) {
            if (static_cast<int>(array->size()) != c.axes) {
                r.fail_value("initial_position", *node, allowed);
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
                c.human[i] = read_human(*one, "device.sim.human.", source, c.initial_position_m[i]);
            }
        } else if (const auto* each = node->as_array(); each != nullptr &&
                                                        each->is_array_of_tables() &&
                                                        static_cast<int>(each->size()) == c.axes) {
            for (int i = 0; i < c.axes; ++i) {
                c.human[i] = read_human(*each->get(i)->as_table(),
                                        "device.sim.human[" + std::to_string(i) + "].", source,
                                        c.initial_position_m[i]);
            }
        } else {
            r.fail_value("human", *node,
                         "a table [device.sim.human] (every axis) or " + std::to_string(c.axes) +
                             " tables [[device.sim.human]] (one per axis)");
        }
    }
    if (const toml::table* faults = r.subtable("faults"))
        c.faults = read_faults(*faults, source, c.axes);
    r.finish();
    return c;
}

}  // namespace hapticd::device::sim
