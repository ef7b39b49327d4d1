#include "cli_common.hpp"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/device_open.hpp"
#include "hapticd/servo/rate.hpp"
#include "hapticd/tune/input_checks.hpp"
#include "hapticd/tune/result_json.hpp"

namespace hapticd::tools {
namespace {

CLI::Validator numeric_range(const std::string& allowed, const std::function<bool(double)>& ok,
                             const std::string& unit) {
    return CLI::Validator(
        [allowed, ok, unit](std::string& text) -> std::string {
            double value = 0.0;
            try {
                std::size_t used = 0;
                value = std::stod(text, &used);
                if (used != text.size()) throw std::invalid_argument(text);
            } catch (const std::exception&) {
                return "value '" + text + "' is not a number (" + unit + ")";
            }
            if (!ok(value))
                return "value " + text + " is out of range: allowed " + allowed + " (" + unit + ")";
            return {};
        },
        allowed + " " + unit);
}

/// The help of an option that stands for a config key, from the key's own declaration and
/// its table's field list: "as [TABLE] KEY[ ABSENT]: HELP; ALLOWED".
template <typename Fields>
std::string key_option_help(const Fields& list, const input::Number& key,
                            std::string_view absent = "") {
    return "as [" + std::string(list.table) + "] " + std::string(key.key) + std::string(absent) +
           ": " + std::string(key.help) + "; " + key.describe();
}

}  // namespace

CLI::Validator positive_finite(const std::string& unit) {
    return numeric_range(
        "finite and > 0", [](double v) { return std::isfinite(v) && v > 0.0; }, unit);
}

CLI::Validator non_negative_finite(const std::string& unit) {
    return numeric_range(
        "finite and >= 0", [](double v) { return std::isfinite(v) && v >= 0.0; }, unit);
}

CLI::Validator in_range(const input::Range& range) {
    input::Range bounds = range;
    bounds.unit = "";
    return numeric_range(
        bounds.describe(), [range](double v) { return range.contains(v); },
        std::string(range.unit));
}

void add_device_options(CLI::App& command, DeviceOptions& options) {
    command
        .add_option("--config", options.config_path,
                    "hapticd config file to take [device.model], [servo] rate_hz and "
                    "[coupling] from; flags override it")
        ->check(CLI::ExistingFile);
    command.add_option("--mass", options.mass_kg, "device mass m (kg)")
        ->check(positive_finite("kg"));
    command.add_option("--damping", options.damping_n_s_per_m, "device damping b (N s/m)")
        ->check(positive_finite("N s/m"));
    const input::Number& rate = daemon::schema::kRate;
    command.add_option("--rate", options.rate_hz, key_option_help(daemon::kServoFields, rate))
        ->check(in_range(rate.range));
}

void add_delay_option(CLI::App& command, DeviceOptions& options) {
    command
        .add_option("--delay", options.delay_s,
                    key_option_help(daemon::kDeviceModelFields, daemon::schema::kModelDelay,
                                    " (the default, else 0)"))
        ->check(non_negative_finite("s"));
}

void add_velocity_filter_option(CLI::App& command, DeviceOptions& options) {
    command
        .add_option("--velocity-filter", options.velocity_filter_hz,
                    key_option_help(daemon::kCouplingFields, daemon::schema::kVelocityFilter,
                                    " (the default, else 0)"))
        ->check(non_negative_finite("Hz"));
}

CLI::Option* add_model_option(CLI::App& command, std::string& model,
                              const std::vector<std::string>& allowed) {
    std::string list;
    for (const std::string& name : allowed) list += (list.empty() ? "" : ", ") + name;
    model = allowed.front();
    return command
        .add_option("--model", model,
                    "stability model: " + list + " (default " + allowed.front() +
                        ": holds for every passive operator and environment; paper and "
                        "encoder reproduce the paper and compare models, they are no guarantee)")
        ->check(CLI::IsMember(allowed));
}

theory::PiVelocityLoop DisplayOptions::pi_loop() const {
    if (!kp || !ki) {
        throw UsageError("--display admittance needs the PI velocity-loop gains --kp and --ki");
    }
    return {*kp, *ki};
}

void add_display_options(CLI::App& command, DisplayOptions& options) {
    command.add_option("--display", options.display, "display causality (default impedance)")
        ->check(CLI::IsMember({"impedance", "admittance"}));
    command.add_option("--kp", options.kp, "admittance display: PI proportional gain (N s/m)")
        ->check(non_negative_finite("N s/m"));
    command.add_option("--ki", options.ki, "admittance display: PI integral gain (N/m)")
        ->check(non_negative_finite("N/m"));
}

daemon::Config load_config_as_hapticd(const std::string& path) {
    daemon::Config config = daemon::load_config(path);
    // hapticd refuses a plugin it cannot load when it opens the device; haptic-tune opens
    // none, so it refuses it here, with the same message: a verdict on a config that hapticd
    // will not run is no verdict.
    daemon::check_device_config(config, daemon::UnloadablePlugin::refuse);
    return config;
}

DesignInput resolve_design_input(const DeviceOptions& options) {
    DesignInput input;
    if (!options.config_path.empty()) input.config = load_config_as_hapticd(options.config_path);
    const daemon::Config* config = input.config ? &*input.config : nullptr;
    if (config && !((options.mass_kg || config->device.model.mass_kg) &&
                    (options.damping_n_s_per_m || config->device.model.damping_n_s_per_m))) {
        daemon::require_device_model(*config);  // what the config lacks, in hapticd's words
    }
    const auto pick = [](const std::optional<double>& flag, const std::optional<double>& cfg,
                         const char* what) {
        if (flag) return *flag;
        if (cfg) return *cfg;
        throw UsageError(std::string("missing ") + what);
    };
    input.device.mass_kg =
        pick(options.mass_kg, config ? config->device.model.mass_kg : std::nullopt,
             "--mass (or [device.model] mass in --config)");
    input.device.damping_n_s_per_m = pick(
        options.damping_n_s_per_m, config ? config->device.model.damping_n_s_per_m : std::nullopt,
        "--damping (or [device.model] damping in --config)");
    input.rate_hz =
        pick(options.rate_hz, config ? std::optional<double>(config->servo.rate_hz) : std::nullopt,
             "--rate (or [servo] rate_hz in --config)");
    if (config) {
        if (config->coupling.stiffness_n_per_m > 0.0) {
            input.coupling_stiffness_n_per_m = config->coupling.stiffness_n_per_m;
        }
        input.coupling_damping_n_s_per_m = config->coupling.damping_n_s_per_m;
    }
    input.delay_s = options.delay_s.value_or(config ? config->device.model.delay_s : 0.0);
    input.velocity_filter_hz =
        options.velocity_filter_hz.value_or(config ? config->coupling.velocity_filter_hz : 0.0);
    try {
        tune::check_device(input.device);
        tune::check_rate(input.rate_hz);
        tune::check_velocity_filter(input.velocity_filter_hz, input.rate_hz);
    } catch (const std::invalid_argument& error) {
        throw UsageError(error.what());
    }
    if (!(input.delay_s >= 0.0 && input.delay_periods() < tune::kMaxDelayPeriods)) {
        std::ostringstream message;
        message << "--delay " << input.delay_s << " s is out of range: allowed >= 0 and < "
                << tune::kMaxDelayPeriods << " periods (" << tune::kMaxDelayPeriods / input.rate_hz
                << " s at " << input.rate_hz << " Hz)";
        throw UsageError(message.str());
    }
    return input;
}

namespace {

// Flattens nested objects into dotted keys ("device.mass") for the text output.
void flatten(const nlohmann::ordered_json& node, const std::string& prefix,
             std::vector<std::pair<std::string, std::string>>& rows) {
    for (const auto& [key, value] : node.items()) {
        const std::string name = prefix.empty() ? key : prefix + "." + key;
        if (value.is_object()) {
            flatten(value, name, rows);
        } else if (value.is_string()) {
            rows.emplace_back(name, value.get<std::string>());
        } else if (value.is_number_float()) {
            std::ostringstream number;
            number << std::setprecision(10) << value.get<double>();
            rows.emplace_back(name, number.str());
        } else {
            rows.emplace_back(name, value.dump());
        }
    }
}

}  // namespace

std::string trimmed(const std::string& text) {
    const auto first = text.find_first_not_of(" \t\r\n");
    if (first == std::string::npos) return {};
    const auto last = text.find_last_not_of(" \t\r\n");
    return text.substr(first, last - first + 1);
}

std::string number_text(double value, int digits) {
    std::ostringstream text;
    text << std::setprecision(digits) << value;
    return text.str();
}

void add_input_fields(const DesignInput& input, nlohmann::ordered_json& out) {
    out["delay_s"] = input.delay_s;
    out["delay_periods"] = input.delay_periods();
    out["device"] = input.device;
    out["rate_hz"] = input.rate_hz;
}

void print_result(const nlohmann::ordered_json& fields, bool json) {
    if (json) {
        std::cout << fields.dump(2) << '\n';
        return;
    }
    std::vector<std::pair<std::string, std::string>> rows;
    flatten(fields, "", rows);
    std::size_t width = 0;
    for (const auto& row : rows) width = std::max(width, row.first.size());
    for (const auto& [key, value] : rows) {
        std::cout << std::left << std::setw(static_cast<int>(width) + 2) << key << value << '\n';
    }
}

}  // namespace hapticd::tools
