#include "hapticd/daemon/config.hpp"

#include <openssl/evp.h>
#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "embedded_defaults.hpp"
#include "hapticd/input/table_reader.hpp"
#include "hapticd/input/text_input.hpp"

namespace hapticd::daemon {

std::string_view to_string(CheckModel model) noexcept {
    return model ? tune::to_string(*model) : "off";
}

std::string_view to_string(EnvironmentClass environments) noexcept {
    return environments == EnvironmentClass::scene ? "scene" : "every-passive";
}

namespace {

// SHA-256 in hex, with OpenSSL's libcrypto (Debian's libssl-dev): the config's name in a
// recording's preamble, as `sha256sum FILE` prints it.
std::string sha256_hex(std::string_view text) {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned int length = 0;
    if (EVP_Digest(text.data(), text.size(), digest, &length, EVP_sha256(), nullptr) != 1) {
        throw std::runtime_error("SHA-256 of the config failed (OpenSSL EVP_Digest)");
    }
    static constexpr char kHex[] = "0123456789abcdef";
    std::string hex;
    for (unsigned int i = 0; i < length; ++i) {
        hex += kHex[digest[i] >> 4];
        hex += kHex[digest[i] & 0xf];
    }
    return hex;
}

using input::TableReader;

/// The sub-table `key` of `parent` as a reader (an empty table when absent).
class Section {
  public:
    Section(TableReader& parent, std::string_view key)
        : reader_(table_or_empty(parent.subtable(key)), parent.source(), parent.path(key)) {}
    TableReader* operator->() { return &reader_; }
    TableReader& operator*() { return reader_; }

  private:
    const toml::table& table_or_empty(const toml::table* table) {
        return table != nullptr ? *table : empty_;
    }
    toml::table empty_;
    TableReader reader_;
};

// [servo]
void read_servo(TableReader& servo, ServoSection& out) {
    input::read_fields(servo, out, kServoFields);
    servo.finish();
}

// [device.model], after [servo] (the delay is bounded in periods of the rate).
void read_model(TableReader& model, double rate_hz, DeviceModel& out) {
    input::read_fields(model, out, kDeviceModelFields);
    out.delay_stated = model.has(schema::kModelDelay.key);
    // In periods, as every model checks it.
    out.delay_s = model.read_periods(schema::kModelDelay.key, tune::kMaxDelayPeriods, rate_hz);
    model.finish();
}

// [device]: the plugin's own table stays where it is, for the plugin to read.
void read_device(TableReader& device, std::string_view text, double rate_hz, DeviceSection& out) {
    input::read_fields(device, out, kDeviceFields);
    Section model(device, "model");
    read_model(*model, rate_hz, out.model);
    const std::string plugin_key = std::filesystem::path(out.plugin).stem().string();
    (void)device.subtable(plugin_key);  // a table, if present; its keys are the plugin's
    out.plugin_table_toml = std::string(text);
    out.plugin_table_path = device.path(plugin_key);
    device.finish();
}

// [coupling] velocity_filter: 0 (none), or the range every model checks
// (tune::check_velocity_filter): 1 Hz and up, below Nyquist.
void check_velocity_filter(TableReader& coupling, double f_c, double rate_hz) {
    if (f_c == 0.0 || (f_c >= tune::kMinVelocityFilterHz && f_c < rate_hz / 2.0)) return;
    coupling.fail("velocity_filter", "is out of range",
                  "0 (no filter) or >= " + input::format_number(tune::kMinVelocityFilterHz) +
                      " and < " + input::format_number(rate_hz / 2.0) +
                      " (Hz, below Nyquist: [servo] rate_hz = " + input::format_number(rate_hz) +
                      ")");
}

// [coupling]
void read_coupling(TableReader& coupling, double rate_hz, CouplingSection& out) {
    input::read_fields(coupling, out, kCouplingFields);
    out.velocity_filter_hz = coupling.read(schema::kVelocityFilter);  // a rule: read here
    check_velocity_filter(coupling, out.velocity_filter_hz, rate_hz);
    if (out.environments == EnvironmentClass::scene &&
        !(out.check && tune::is_guarantee(*out.check))) {
        coupling.fail("environments",
                      "= \"scene\" needs check = \"passive\" or \"exact\" (the models that hold "
                      "for a stated class of environments), but check = \"" +
                          std::string(to_string(out.check)) + "\"");
    }
    if (!out.enabled) {
        // The conventional design, for experiments: the daemon will not pretend to check it.
        for (const char* key : {"stiffness", "damping", "velocity_filter"}) {
            if (coupling.has(key)) {
                coupling.fail(key, "has no effect with enabled = false (no coupling); remove it");
            }
        }
        if (out.check) {
            coupling.fail("check", "= \"" + std::string(to_string(out.check)) +
                                       "\" cannot check enabled = false (no coupling: the scene "
                                       "acts on the device directly); set check = \"off\" to run "
                                       "it deliberately");
        }
    }
    coupling.finish();
}

// [scene]: the file, resolved against the config's folder.
void read_scene(TableReader& scene, const std::string& base_dir, std::string& out) {
    SceneSection section;
    input::read_fields(scene, section, kSceneFields);
    if (section.file) {
        const std::filesystem::path p(*section.file);
        out = p.is_absolute() || base_dir.empty()
                  ? p.string()
                  : (std::filesystem::path(base_dir) / p).lexically_normal().string();
    }
    scene.finish();
}

// [safety]
void read_safety(TableReader& safety, SafetySection& out) {
    input::read_fields(safety, out, kSafetyFields);
    const servo::LinkRecoverySettings& reconnect = out.reconnect;
    if (!reconnect.enabled) {
        for (const char* key : {"reconnect_settle", "reconnect_timeout"}) {
            if (safety.has(key)) {
                safety.fail(key,
                            "has no effect with reconnect = false (every fault ends the run); "
                            "remove it");
            }
        }
    }
    if (reconnect.timeout_s != 0.0 && reconnect.timeout_s <= reconnect.settle_s) {
        safety.fail("reconnect_timeout", "is out of range",
                    "> reconnect_settle = " + input::format_number(reconnect.settle_s) +
                        " (s: the device must be back and settled within it), or 0 to wait "
                        "for ever");
    }
    safety.finish();
}

// [identify], after [servo] and [safety], which bound it.
void read_identify(TableReader& identify, const Config& config, IdentifySection& out) {
    const double rate_hz = config.servo.rate_hz;
    input::read_fields(identify, out, kIdentifyFields);
    out.band_low_hz = identify.read_optional(schema::band_edge(schema::kBandLow, rate_hz));
    out.band_high_hz = identify.read_optional(schema::band_edge(schema::kBandHigh, rate_hz));
    if (out.force_amplitude_n && *out.force_amplitude_n > config.safety.max_force_n) {
        identify.fail("force_amplitude", "is out of range",
                      "<= [safety] max_force = " + input::format_number(config.safety.max_force_n) +
                          " (N: the excitation would only be clipped)");
    }
    if (out.band_low_hz && out.band_high_hz && !(*out.band_high_hz > *out.band_low_hz)) {
        identify.fail("band_high", "is out of range",
                      "> band_low = " + input::format_number(*out.band_low_hz) + " (Hz)");
    }
    identify.finish();
}

/// [operator]: a declared class (tune/operator_class.hpp). Every bound is required.
tune::OperatorClass read_operator_class(TableReader& reader) {
    const auto& keys = tune::OperatorClass::kKeys;
    std::string listed;
    for (const char* key : keys) listed += (listed.empty() ? "" : ", ") + std::string(key);
    if (reader.contents().empty()) {
        reader.fail_table("is empty: declare " + listed +
                          " (each a number or [min, max]), and optionally max_resonance (Hz); "
                          "or remove the table to hold for every passive operator");
    }
    reader.only({keys[0], keys[1], keys[2], keys[3], keys[4], schema::kMaxResonance.key});
    tune::OperatorClass cls;
    tune::ParameterRange* ranges[] = {&cls.hand_mass_kg, &cls.grip_stiffness_n_per_m,
                                      &cls.grip_damping_n_s_per_m, &cls.arm_stiffness_n_per_m,
                                      &cls.arm_damping_n_s_per_m};
    for (int i = 0; i < tune::kClassParameters; ++i) {
        const toml::node* node = reader.get(keys[i]);
        if (node == nullptr) {
            reader.fail(keys[i],
                        "is missing: a class bounds every parameter of the two-mass grasp (" +
                            listed + "); write 0 for a part the hand does not have");
        }
        // A number, or an array [min, max] of two numbers (tune::validate checks the ranges).
        const toml::array* array = node->as_array();
        if (array != nullptr && array->size() == 2 && array->get(0)->is_number() &&
            array->get(1)->is_number()) {
            *ranges[i] = {*array->get(0)->value<double>(), *array->get(1)->value<double>()};
        } else if (node->is_number()) {
            const double v = *node->value<double>();
            *ranges[i] = {v, v};
        } else {
            reader.fail(
                keys[i], "is not a number or an array [min, max] of two numbers",
                "a number or [min, max] (" + std::string(tune::OperatorClass::kUnits[i]) + ")");
        }
    }
    cls.max_resonance_hz = reader.read_optional(schema::kMaxResonance).value_or(0.0);
    reader.finish();
    try {
        tune::validate(cls, reader.source() + ": [operator]");
    } catch (const std::invalid_argument& e) {
        throw ConfigError(e.what());
    }
    return cls;
}

}  // namespace

Config parse_config(std::string_view toml_text, const std::string& source,
                    const std::string& base_dir) {
    const toml::table root = input::parse_document(toml_text, source);
    TableReader file(root, source, "");
    Config config;
    config.source = source;
    config.base_dir = base_dir;
    config.sha256 = sha256_hex(toml_text);
    Section servo(file, "servo");
    read_servo(*servo, config.servo);
    Section device(file, "device");
    read_device(*device, toml_text, config.servo.rate_hz, config.device);
    Section coupling(file, "coupling");
    read_coupling(*coupling, config.servo.rate_hz, config.coupling);
    Section op(file, "operator");
    if (root.contains("operator")) {
        if (config.coupling.check != tune::StabilityModel::exact) {
            op->fail_table(
                "declares an operator class, which only [coupling] check = \"exact\" "
                "can use, but check = \"" +
                std::string(to_string(config.coupling.check)) + "\"" +
                (config.coupling.check == tune::StabilityModel::passive
                     ? " (the passive model holds for every passive operator)"
                     : "") +
                ": set check = \"exact\", or remove [operator]");
        }
        config.operators = read_operator_class(*op);
    }
    Section scene(file, "scene");
    read_scene(*scene, base_dir, config.scene_file);
    Section safety(file, "safety");
    read_safety(*safety, config.safety);
    Section identify(file, "identify");
    read_identify(*identify, config, config.identify);
    file.finish();
    return config;
}

Config load_config(const std::string& path) {
    const std::string text = input::read_text_file(path, "the config file");
    const std::string dir = std::filesystem::path(path).parent_path().string();
    return parse_config(text, path, dir.empty() ? "." : dir);
}

tune::OperatorClass load_operator_class(const std::string& path) {
    const toml::table root =
        input::parse_document(input::read_text_file(path, "the operator class file"), path);
    TableReader file(root, path, "");
    const toml::table* table = file.subtable("operator");
    if (table == nullptr) {
        throw ConfigError(path +
                          ": has no [operator] table: an operator class file declares "
                          "[operator] with hand_mass, grip_stiffness, grip_damping, "
                          "arm_stiffness and arm_damping");
    }
    TableReader reader(*table, path, "operator");
    return read_operator_class(reader);
}

Config default_config() {
    Config config = parse_config(default_config_text(), "<embedded default>", "");
    config.scene_file.clear();  // the demo scene is compiled in as well
    return config;
}

std::string_view default_config_text() { return kEmbeddedDefaultConfig; }
std::string_view default_scene_text() { return kEmbeddedDemoScene; }

}  // namespace hapticd::daemon
