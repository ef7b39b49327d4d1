#include "hapticd/daemon/config.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "embedded_defaults.hpp"
#include "hapticd/input/text_input.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::daemon {
namespace {

/// Reads one table's keys against a fixed list, with errors that name file, key and value.
class TableReader {
  public:
    TableReader(const std::string& source, std::string name, const toml::table* table)
        : source_(source), name_(std::move(name)), table_(table) {}

    /// Unknown keys are errors; `tables` are sub-tables this reader allows.
    void allow_only(const std::set<std::string>& keys,
                    const std::set<std::string>& tables = {}) const {
        if (table_ == nullptr) return;
        for (const auto& [key, node] : *table_) {
            const std::string k(key.str());
            if (keys.count(k) != 0 || (node.is_table() && tables.count(k) != 0)) continue;
            std::string allowed;
            for (const auto& a : keys) allowed += (allowed.empty() ? "" : ", ") + a;
            for (const auto& t : tables)
                allowed += (allowed.empty() ? "[" : ", [") + name_ + "." + t + "]";
            throw ConfigError(source_ + ": unknown key [" + name_ + "] " + k +
                              " (allowed: " + allowed + ")");
        }
    }

    std::optional<double> number(const std::string& key, double lo, double hi, bool lo_open,
                                 const char* unit) const {
        const toml::node* node = find(key);
        if (node == nullptr) return std::nullopt;
        const std::optional<double> v = node->is_boolean() ? std::nullopt : node->value<double>();
        if (!v) throw ConfigError(where(key) + " must be a number (" + unit + ")");
        const bool ok = std::isfinite(*v) && (lo_open ? *v > lo : *v >= lo) && *v <= hi;
        if (!ok) {
            std::ostringstream m;
            m << where(key) << " = " << *v << " is out of range: allowed "
              << (lo_open ? "> " : ">= ") << lo;
            if (std::isfinite(hi)) m << " and <= " << hi;
            m << " (" << unit << ")";
            throw ConfigError(m.str());
        }
        return v;
    }

    std::optional<int> integer(const std::string& key, int lo, int hi) const {
        const toml::node* node = find(key);
        if (node == nullptr) return std::nullopt;
        if (!node->is_integer()) throw ConfigError(where(key) + " must be an integer");
        const std::int64_t v = *node->value<std::int64_t>();
        if (v < lo || v > hi) {
            std::ostringstream m;
            m << where(key) << " = " << v << " is out of range: allowed " << lo << ".." << hi;
            throw ConfigError(m.str());
        }
        return static_cast<int>(v);
    }

    std::optional<bool> boolean(const std::string& key) const {
        const toml::node* node = find(key);
        if (node == nullptr) return std::nullopt;
        if (!node->is_boolean()) throw ConfigError(where(key) + " must be true or false");
        return *node->value<bool>();
    }

    bool has(const std::string& key) const { return find(key) != nullptr; }

    /// A number, or an array [min, max] of two numbers (ranges are checked by the caller).
    std::optional<tune::ParameterRange> range(const std::string& key, const char* unit) const {
        const toml::node* node = find(key);
        if (node == nullptr) return std::nullopt;
        const auto as_number = [](const toml::node* n) -> std::optional<double> {
            if (n == nullptr || n->is_boolean()) return std::nullopt;
            return n->value<double>();
        };
        if (const auto v = as_number(node)) return tune::ParameterRange{*v, *v};
        const toml::array* array = node->as_array();
        if (array != nullptr && array->size() == 2) {
            const auto lo = as_number(array->get(0)), hi = as_number(array->get(1));
            if (lo && hi) return tune::ParameterRange{*lo, *hi};
        }
        throw ConfigError(where(key) + " must be a number or an array [min, max] of two numbers (" +
                          unit + ")");
    }

    std::optional<std::string> text(const std::string& key,
                                    const std::set<std::string>& choices = {}) const {
        const toml::node* node = find(key);
        if (node == nullptr) return std::nullopt;
        if (!node->is_string()) throw ConfigError(where(key) + " must be a string");
        std::string v = *node->value<std::string>();
        if (!choices.empty() && choices.count(v) == 0) {
            std::string allowed;
            for (const auto& c : choices) allowed += (allowed.empty() ? "\"" : ", \"") + c + "\"";
            throw ConfigError(where(key) + " = \"" + v + "\" is not allowed: use one of " +
                              allowed);
        }
        if (choices.empty() && v.empty()) throw ConfigError(where(key) + " must not be empty");
        return v;
    }

  private:
    const toml::node* find(const std::string& key) const {
        return table_ == nullptr ? nullptr : table_->get(key);
    }

  public:
    std::string where(const std::string& key) const { return source_ + ": [" + name_ + "] " + key; }

  private:
    const std::string& source_;
    std::string name_;
    const toml::table* table_;
};

const toml::table* sub_table(const toml::table& parent, const std::string& source,
                             const std::string& name) {
    const toml::node* node = parent.get(name);
    if (node == nullptr) return nullptr;
    if (!node->is_table())
        throw ConfigError(source + ": " + name + " must be a table ([" + name + "])");
    return node->as_table();
}

constexpr double kInf = std::numeric_limits<double>::infinity();

// [coupling] velocity_filter: 0 (none), or the range every model checks
// (tune::check_velocity_filter): 1 Hz and up, below Nyquist.
double velocity_filter(const TableReader& coupling, const std::string& source, double rate_hz) {
    std::ostringstream range;
    range << "Hz; 0: no filter, or >= " << tune::kMinVelocityFilterHz << " and < " << rate_hz / 2.0
          << ", below Nyquist";
    const std::string unit = range.str();
    const double f_c =
        coupling.number("velocity_filter", 0.0, kInf, false, unit.c_str()).value_or(0.0);
    if (f_c != 0.0 && !(f_c >= tune::kMinVelocityFilterHz && f_c < rate_hz / 2.0)) {
        std::ostringstream m;
        m << source << ": [coupling] velocity_filter = " << f_c
          << " is out of range: allowed 0 (no filter) or >= " << tune::kMinVelocityFilterHz
          << " and < " << rate_hz / 2.0 << " (Hz, below Nyquist: [servo] rate_hz = " << rate_hz
          << ")";
        throw ConfigError(m.str());
    }
    return f_c;
}

// [identify], after [servo] and [safety], which bound it.
void parse_identify(const toml::table& root, const std::string& source, Config& config) {
    const TableReader identify(source, "identify", sub_table(root, source, "identify"));
    identify.allow_only({"force_amplitude", "workspace", "band_low", "band_high",
                         "lines_per_decade", "period", "periods", "fade"});
    IdentifySection& out = config.identify;
    // The band stays well below Nyquist: at least ten samples a cycle.
    const double band_limit_hz = config.servo.rate_hz / 10.0;
    out.force_amplitude_n = identify.number("force_amplitude", 0.0, 1e4, true, "N");
    out.workspace_m = identify.number("workspace", 0.0, 1.0, true, "m").value_or(0.03);
    out.band_low_hz =
        identify.number("band_low", 0.0, band_limit_hz, true, "Hz, rate_hz/10 at most");
    out.band_high_hz =
        identify.number("band_high", 0.0, band_limit_hz, true, "Hz, rate_hz/10 at most");
    out.lines_per_decade =
        identify.number("lines_per_decade", 1.0, 50.0, false, "lines per decade per axis")
            .value_or(10.0);
    out.period_s = identify.number("period", 0.0, 60.0, true, "s");
    out.periods = identify.integer("periods", 1, 1000);
    out.fade_s = identify.number("fade", 0.0, 60.0, false, "s");
    if (out.force_amplitude_n && *out.force_amplitude_n > config.safety.max_force_n) {
        std::ostringstream m;
        m << source << ": [identify] force_amplitude = " << *out.force_amplitude_n
          << " is out of range: allowed <= [safety] max_force = " << config.safety.max_force_n
          << " (N: the excitation would only be clipped)";
        throw ConfigError(m.str());
    }
    if (out.band_low_hz && out.band_high_hz && !(*out.band_high_hz > *out.band_low_hz)) {
        std::ostringstream m;
        m << source << ": [identify] band_high = " << *out.band_high_hz
          << " is out of range: allowed > band_low = " << *out.band_low_hz << " (Hz)";
        throw ConfigError(m.str());
    }
}

/// [operator]: a declared class (tune/operator_class.hpp). Every bound is required: a class
/// is a claim about the lab's hands, and a default would make it silently.
std::optional<tune::OperatorClass> parse_operator_class(const toml::table& root,
                                                        const std::string& source) {
    const toml::table* table = sub_table(root, source, "operator");
    if (table == nullptr) return std::nullopt;
    const TableReader reader(source, "operator", table);
    const auto& keys = tune::OperatorClass::kKeys;
    std::string listed;
    for (const char* key : keys) listed += (listed.empty() ? "" : ", ") + std::string(key);
    std::set<std::string> allowed(keys.begin(), keys.end());
    allowed.insert("max_resonance");
    reader.allow_only(allowed);
    if (table->empty()) {
        throw ConfigError(source + ": [operator] is empty: declare " + listed +
                          " (each a number or [min, max]), and optionally max_resonance (Hz); "
                          "or remove the table to hold for every passive operator");
    }
    tune::OperatorClass cls;
    tune::ParameterRange* ranges[] = {&cls.hand_mass_kg, &cls.grip_stiffness_n_per_m,
                                      &cls.grip_damping_n_s_per_m, &cls.arm_stiffness_n_per_m,
                                      &cls.arm_damping_n_s_per_m};
    for (int i = 0; i < tune::kClassParameters; ++i) {
        const auto r = reader.range(keys[i], tune::OperatorClass::kUnits[i]);
        if (!r) {
            throw ConfigError(reader.where(keys[i]) +
                              " is missing: a class bounds every parameter of the two-mass "
                              "grasp (" +
                              listed + "); write 0 for a part the hand does not have");
        }
        *ranges[i] = *r;
    }
    cls.max_resonance_hz =
        reader.number("max_resonance", 0.0, tune::OperatorClass::kMaxResonanceLimitHz, true, "Hz")
            .value_or(0.0);
    try {
        tune::validate(cls, source + ": [operator]");
    } catch (const std::invalid_argument& e) {
        throw ConfigError(e.what());
    }
    return cls;
}

}  // namespace

Config parse_config(std::string_view toml_text, const std::string& source,
                    const std::string& base_dir) {
    if (const std::string e = input::toml_shape_error(toml_text, source); !e.empty()) {
        throw ConfigError(e);
    }
    toml::table root;
    try {
        root = toml::parse(toml_text, source);
    } catch (const toml::parse_error& e) {
        std::ostringstream m;
        m << source << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
          << e.description();
        throw ConfigError(m.str());
    }
    Config config;
    config.source = source;
    config.base_dir = base_dir;
    const std::set<std::string> tables = {"servo",  "device",   "coupling", "scene",
                                          "safety", "identify", "operator"};
    for (const auto& [key, node] : root) {
        const std::string k(key.str());
        if (!node.is_table()) {
            throw ConfigError(source + ": top-level key " + k +
                              " must be inside one of the tables [servo], [device], [coupling], "
                              "[scene], [safety], [identify], [operator]");
        }
        if (tables.count(k) == 0) {
            throw ConfigError(source + ": unknown table [" + k +
                              "] (allowed: [servo], [device], [coupling], [scene], [safety], "
                              "[identify], [operator])");
        }
    }

    const TableReader servo(source, "servo", sub_table(root, source, "servo"));
    servo.allow_only({"rate_hz", "realtime", "priority", "cpu"});
    config.servo.rate_hz = servo.number("rate_hz", 100.0, 20000.0, false, "Hz").value_or(1000.0);
    config.servo.realtime = servo.text("realtime", {"enforce", "warn", "off"}).value_or("warn");
    config.servo.priority = servo.integer("priority", 1, 99).value_or(80);
    config.servo.cpu = servo.integer("cpu", 0, 4095);

    const toml::table* device_table = sub_table(root, source, "device");
    const TableReader device(source, "device", device_table);
    config.device.plugin = device.text("plugin").value_or("sim");
    config.device.axes = device.integer("axes", 1, 3).value_or(1);
    const std::string plugin_key = std::filesystem::path(config.device.plugin).stem().string();
    device.allow_only({"plugin", "axes"}, {"model", plugin_key});
    if (device_table != nullptr) {
        const TableReader model(source, "device.model", sub_table(*device_table, source, "model"));
        model.allow_only({"mass", "damping", "delay"});
        // The physical ranges of hapticd::tune (input_checks.hpp), which every model obeys.
        config.device.model_mass_kg =
            model.number("mass", tune::kMinDeviceMassKg, tune::kMaxDeviceMassKg, false, "kg");
        config.device.model_damping_n_s_per_m = model.number(
            "damping", tune::kMinDeviceDamping, tune::kMaxDeviceDamping, false, "N s/m");
        const double period_s = 1.0 / config.servo.rate_hz;
        config.device.model_delay_s = model.number("delay", 0.0, kInf, false, "s").value_or(0.0);
        // In periods, as every model checks it (rounding of delay / period must not pass here
        // and fail there).
        if (!(config.device.model_delay_s * config.servo.rate_hz < tune::kMaxDelayPeriods)) {
            std::ostringstream m;
            m << source << ": [device.model] delay = " << config.device.model_delay_s
              << " s is out of range: allowed >= 0 and < " << tune::kMaxDelayPeriods << " periods ("
              << tune::kMaxDelayPeriods * period_s
              << " s at [servo] rate_hz = " << config.servo.rate_hz << ")";
            throw ConfigError(m.str());
        }
        if (const toml::table* own = sub_table(*device_table, source, plugin_key)) {
            std::ostringstream text;
            text << *own;
            config.device.plugin_table_toml = text.str();
        }
    }

    const TableReader coupling(source, "coupling", sub_table(root, source, "coupling"));
    coupling.allow_only(
        {"enabled", "stiffness", "damping", "velocity_filter", "check", "environments"});
    config.coupling.enabled = coupling.boolean("enabled").value_or(true);
    config.coupling.stiffness_n_per_m =
        coupling.number("stiffness", 0.0, tune::kMaxCouplingStiffness, false, "N/m").value_or(0.0);
    config.coupling.damping_n_s_per_m =
        coupling.number("damping", 0.0, tune::kMaxCouplingDamping, false, "N s/m").value_or(0.0);
    config.coupling.velocity_filter_hz = velocity_filter(coupling, source, config.servo.rate_hz);
    config.coupling.check =
        coupling.text("check", {"passive", "exact", "paper", "encoder", "off"}).value_or("passive");
    config.coupling.environments =
        coupling.text("environments", {"every-passive", "scene"}).value_or("every-passive");
    const std::string& check = config.coupling.check;
    if (root.contains("operator") && check != "exact") {
        throw ConfigError(
            source +
            ": [operator] declares an operator class, which only [coupling] "
            "check = \"exact\" can use, but check = \"" +
            check + "\"" +
            (check == "passive" ? " (the passive model holds for every passive operator)" : "") +
            ": set check = \"exact\", or remove [operator]");
    }
    config.operators = parse_operator_class(root, source);
    if (config.coupling.environments == "scene" && check != "passive" && check != "exact") {
        throw ConfigError(source +
                          ": [coupling] environments = \"scene\" needs check = "
                          "\"passive\" or \"exact\" (the models that hold for a stated "
                          "class of environments), but check = \"" +
                          check + "\"");
    }
    if (!config.coupling.enabled) {
        // The conventional design, for experiments: the daemon will not pretend to check it.
        for (const char* key : {"stiffness", "damping", "velocity_filter"}) {
            if (coupling.has(key)) {
                throw ConfigError(source + ": [coupling] " + key +
                                  " has no effect with enabled = false (no coupling); remove it");
            }
        }
        if (config.coupling.check != "off") {
            throw ConfigError(source + ": [coupling] check = \"" + config.coupling.check +
                              "\" cannot check enabled = false (no coupling: the scene acts on "
                              "the device directly); set check = \"off\" to run it deliberately");
        }
    }

    const TableReader scene(source, "scene", sub_table(root, source, "scene"));
    scene.allow_only({"file"});
    if (const auto file = scene.text("file")) {
        const std::filesystem::path p(*file);
        config.scene_file = p.is_absolute() || base_dir.empty()
                                ? p.string()
                                : (std::filesystem::path(base_dir) / p).lexically_normal().string();
    }

    const TableReader safety(source, "safety", sub_table(root, source, "safety"));
    safety.allow_only({"max_force", "max_speed", "soft_start_ramp", "passivity", "reconnect",
                       "reconnect_settle", "reconnect_timeout", "max_missed_periods",
                       "max_consecutive_overruns"});
    // Physical ranges: no haptic device pushes 10 kN or moves its handle at 100 m/s (and
    // max_speed sets the encoder-jump threshold, 10 max_speed T, which must stay finite).
    config.safety.max_force_n = safety.number("max_force", 0.0, 1e4, true, "N").value_or(10.0);
    config.safety.max_speed_mps = safety.number("max_speed", 0.0, 100.0, true, "m/s").value_or(1.0);
    config.safety.soft_start_ramp_s =
        safety.number("soft_start_ramp", 0.0, 10.0, false, "s").value_or(0.5);
    config.safety.passivity = safety.text("passivity", {"observe", "control"}).value_or("observe");
    config.safety.reconnect = safety.boolean("reconnect").value_or(true);
    config.safety.reconnect_settle_s =
        safety.number("reconnect_settle", 0.0, 60.0, true, "s").value_or(0.5);
    config.safety.reconnect_timeout_s =
        safety.number("reconnect_timeout", 0.0, 3600.0, false, "s; 0: wait for ever").value_or(5.0);
    // The overrun budget: a stall of up to max_missed_periods periods (20 ms at 1 kHz by
    // default) or max_consecutive_overruns late ticks in a row is ridden out.
    config.safety.max_missed_periods =
        safety.integer("max_missed_periods", 0, 1'000'000).value_or(20);
    config.safety.max_consecutive_overruns =
        safety.integer("max_consecutive_overruns", 0, 1'000'000).value_or(5);
    if (!config.safety.reconnect) {
        for (const char* key : {"reconnect_settle", "reconnect_timeout"}) {
            if (safety.has(key)) {
                throw ConfigError(source + ": [safety] " + key +
                                  " has no effect with reconnect = false (every fault ends the "
                                  "run); remove it");
            }
        }
    }
    if (config.safety.reconnect_timeout_s != 0.0 &&
        config.safety.reconnect_timeout_s <= config.safety.reconnect_settle_s) {
        std::ostringstream m;
        m << source << ": [safety] reconnect_timeout = " << config.safety.reconnect_timeout_s
          << " is out of range: allowed > reconnect_settle = " << config.safety.reconnect_settle_s
          << " (s: the device must be back and settled within it), or 0 to wait for ever";
        throw ConfigError(m.str());
    }
    parse_identify(root, source, config);
    return config;
}

Config load_config(const std::string& path) {
    std::string text;
    try {
        text = input::read_text_file(path, "the config file");
    } catch (const input::InputError& e) {
        throw ConfigError(e.what());
    }
    const std::string dir = std::filesystem::path(path).parent_path().string();
    return parse_config(text, path, dir.empty() ? "." : dir);
}

tune::OperatorClass load_operator_class(const std::string& path) {
    std::string text;
    try {
        text = input::read_text_file(path, "the operator class file");
    } catch (const input::InputError& e) {
        throw ConfigError(e.what());
    }
    if (const std::string e = input::toml_shape_error(text, path); !e.empty()) {
        throw ConfigError(e);
    }
    toml::table root;
    try {
        root = toml::parse(text, path);
    } catch (const toml::parse_error& e) {
        std::ostringstream m;
        m << path << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
          << e.description();
        throw ConfigError(m.str());
    }
    const auto cls = parse_operator_class(root, path);
    if (!cls) {
        throw ConfigError(path +
                          ": has no [operator] table: an operator class file declares "
                          "[operator] with hand_mass, grip_stiffness, grip_damping, "
                          "arm_stiffness and arm_damping");
    }
    return *cls;
}

Config default_config() {
    Config config = parse_config(default_config_text(), "<embedded default>", "");
    config.scene_file.clear();  // the demo scene is compiled in as well
    return config;
}

std::string_view default_config_text() { return kEmbeddedDefaultConfig; }
std::string_view default_scene_text() { return kEmbeddedDemoScene; }

}  // namespace hapticd::daemon
