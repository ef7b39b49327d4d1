#include "hapticd/env/plugin_environment.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "c_vectors.hpp"
#include "hapticd/install/plugin_files.hpp"

namespace hapticd::env {
namespace {

using detail::to_array;

// Appends to a fixed buffer, cut at its end: the failure's text, written on the servo thread.
class FixedText {
  public:
    explicit FixedText(std::array<char, 256>& buffer) : buffer_(buffer) { buffer_[0] = '\0'; }
    FixedText& operator<<(std::string_view text) noexcept {
        const std::size_t room = buffer_.size() - 1 - used_;
        const std::size_t n = std::min(room, text.size());
        if (n == 0) return *this;  // an empty view may hold no pointer at all
        std::memcpy(buffer_.data() + used_, text.data(), n);
        used_ += n;
        buffer_[used_] = '\0';
        return *this;
    }
    FixedText& operator<<(double value) noexcept {
        char* const begin = buffer_.data() + used_;
        char* const last = buffer_.data() + buffer_.size() - 1;  // room for the terminator
        const auto [end, error] = std::to_chars(begin, last, value, std::chars_format::general, 6);
        if (error == std::errc{}) used_ = static_cast<std::size_t>(end - buffer_.data());
        buffer_[used_] = '\0';
        return *this;
    }

  private:
    std::array<char, 256>& buffer_;
    std::size_t used_ = 0;
};

Mat3 to_mat3(const double (&rows)[9]) noexcept {
    Mat3 m(0.0);  // glm is column-major: m[column][row]
    for (int row = 0; row < 3; ++row) {
        for (int column = 0; column < 3; ++column) m[column][row] = rows[row * 3 + column];
    }
    return m;
}

}  // namespace

PluginWorld::PluginWorld(std::shared_ptr<void> library, const hapticd_environment_plugin* plugin,
                         void* world, double max_call_us)
    : library_(std::move(library)),
      plugin_(plugin),
      world_(world),
      max_call_ns_(static_cast<std::int64_t>(std::llround(max_call_us * 1e3))) {}

PluginWorld::~PluginWorld() {
    try {
        plugin_->destroy(world_);
    } catch (...) {  // NOLINT(bugprone-empty-catch): a destroy() that throws leaks its world
    }
}

void PluginWorld::fail(const char* what, std::string_view why,
                       std::string_view detail) const noexcept {
    if (failed_) return;
    failed_ = true;
    FixedText(failure_) << what << " " << why << detail;
}

void PluginWorld::fail_number(const char* what, std::string_view why, double value,
                              std::string_view unit) const noexcept {
    if (failed_) return;
    failed_ = true;
    FixedText(failure_) << what << " " << why << value << unit;
}

bool PluginWorld::finite(const char* what, const double* values, int count) const noexcept {
    for (int i = 0; i < count; ++i) {
        if (!std::isfinite(values[i])) {
            fail(what, "gave a value that is not finite");
            return false;
        }
    }
    return true;
}

void PluginWorld::end_tick() const noexcept {
    if (!failed_ && tick_ns_ > max_call_ns_) {
        if (++slow_ticks_ >= 2) {
            failed_ = true;
            FixedText(failure_) << "took " << static_cast<double>(tick_ns_) / 1e3
                                << " us in a tick, the second tick in a row over its max_call_us "
                                << static_cast<double>(max_call_ns_) / 1e3;
        }
    } else {
        slow_ticks_ = 0;
    }
    tick_ns_ = 0;
}

void PluginWorld::clear() noexcept {
    failed_ = false;
    failure_[0] = '\0';
    tick_ns_ = 0;
    slow_ticks_ = 0;
}

PenaltyForce PluginImpedanceEnvironment::evaluate(const Vec3& tool_position_m,
                                                  const Vec3& tool_velocity_mps) const noexcept {
    double x[3];
    double v[3];
    to_array(tool_position_m, x);
    to_array(tool_velocity_mps, v);
    hapticd_env_penalty out{};
    const PluginWorld& w = *world_;
    if (!w.guarded("evaluate()", [&] { return w.plugin().evaluate(w.world(), x, v, &out); }) ||
        !w.finite("evaluate()", out.force_n, 3) ||
        !w.finite("evaluate()", out.stiffness_n_per_m, 9) ||
        !w.finite("evaluate()", out.damping_n_s_per_m, 9)) {
        return PenaltyForce{};  // the servo sees failed() and zeroes the force
    }
    return PenaltyForce{.force_n = Vec3(out.force_n[0], out.force_n[1], out.force_n[2]),
                        .stiffness_n_per_m = to_mat3(out.stiffness_n_per_m),
                        .damping_n_s_per_m = to_mat3(out.damping_n_s_per_m)};
}

void PluginImpedanceEnvironment::commit(const Vec3& tool_position_m,
                                        const Vec3& tool_velocity_mps) noexcept {
    double x[3];
    double v[3];
    to_array(tool_position_m, x);
    to_array(tool_velocity_mps, v);
    PluginWorld& w = *world_;
    w.guarded("commit()", [&] { return w.plugin().commit(w.world(), x, v); });
    w.end_tick();
}

void PluginImpedanceEnvironment::reset(const Vec3& tool_position_m) noexcept {
    double x[3];
    to_array(tool_position_m, x);
    PluginWorld& w = *world_;
    w.clear();
    w.guarded("reset()", [&] { return w.plugin().reset(w.world(), x); });
}

Vec3 PluginAdmittanceEnvironment::step(const Vec3& device_position_m,
                                       const Vec3& device_velocity_mps, const CouplingGains& gains,
                                       double period_s) noexcept {
    double x[3];
    double v[3];
    to_array(device_position_m, x);
    to_array(device_velocity_mps, v);
    const hapticd_env_coupling coupling{.stiffness_n_per_m = gains.stiffness_n_per_m,
                                        .damping_n_s_per_m = gains.damping_n_s_per_m,
                                        .period_s = period_s};
    double tool[3] = {last_tool_position_m_.x, last_tool_position_m_.y, last_tool_position_m_.z};
    PluginWorld& w = *world_;
    const bool ok = w.guarded("step()", [&] {
        return w.plugin().step(w.world(), x, v, &coupling, tool);
    }) && w.finite("step()", tool, 3);
    w.end_tick();
    if (!ok) return device_position_m;  // no stretch, no force; the servo zeroes it anyway
    last_tool_position_m_ = Vec3(tool[0], tool[1], tool[2]);
    return last_tool_position_m_;
}

void PluginAdmittanceEnvironment::reset(const Vec3& position_m) noexcept {
    double x[3];
    to_array(position_m, x);
    PluginWorld& w = *world_;
    w.clear();
    last_tool_position_m_ = position_m;
    w.guarded("reset()", [&] { return w.plugin().reset(w.world(), x); });
}

LoadedPlugin load_environment_plugin(const PluginSpec& spec, int axes, double rate_hz,
                                     const std::string& scene_file) {
    const auto refuse = [&](const std::string& path, const std::string& why) {
        return std::runtime_error(scene_file + ": [plugin] name = \"" + spec.name + "\" (" + path +
                                  ") cannot be used: " + why);
    };
    std::string path;
    try {
        path = install::find_plugin_file("env", spec.name);
    } catch (const std::runtime_error& e) {
        throw std::runtime_error(scene_file + ": [plugin] name: " + e.what());
    }
    std::string error;
    std::shared_ptr<void> library = install::open_plugin_library(path, error);
    if (!library) throw refuse(path, "dlopen failed: " + error);
    dlerror();
    void* symbol = dlsym(library.get(), HAPTICD_ENVIRONMENT_PLUGIN_ENTRY_SYMBOL);
    if (symbol == nullptr) {
        throw refuse(path, std::string("it does not export the entry symbol '") +
                               HAPTICD_ENVIRONMENT_PLUGIN_ENTRY_SYMBOL + "'");
    }
    using Entry = const hapticd_environment_plugin* (*)();
    const hapticd_environment_plugin* plugin = reinterpret_cast<Entry>(symbol)();
    if (plugin == nullptr) throw refuse(path, "its entry returned a null descriptor");
    // abi_version is the first member in every version: read before anything else.
    if (plugin->abi_version != HAPTICD_ENVIRONMENT_ABI_VERSION) {
        throw refuse(path, "it was built for environment plugin ABI version " +
                               std::to_string(plugin->abi_version) +
                               ", but this hapticd speaks version " +
                               std::to_string(HAPTICD_ENVIRONMENT_ABI_VERSION) +
                               "; rebuild the plugin against this hapticd");
    }
    const bool admittance = plugin->causality == HAPTICD_ENV_ADMITTANCE;
    if (!admittance && plugin->causality != HAPTICD_ENV_IMPEDANCE) {
        throw refuse(path, "its causality is " + std::to_string(plugin->causality) +
                               ": allowed HAPTICD_ENV_IMPEDANCE (0) or HAPTICD_ENV_ADMITTANCE (1)");
    }
    if (plugin->create == nullptr || plugin->destroy == nullptr || plugin->reset == nullptr ||
        (admittance ? plugin->step == nullptr
                    : plugin->evaluate == nullptr || plugin->commit == nullptr)) {
        throw refuse(path, admittance ? "its descriptor has a null create, destroy, reset or step"
                                      : "its descriptor has a null create, destroy, reset, "
                                        "evaluate or commit");
    }
    const hapticd_env_setup setup{.axes = static_cast<std::uint32_t>(axes),
                                  .rate_hz = rate_hz,
                                  .settings = spec.settings_toml.c_str(),
                                  .scene_file = scene_file.c_str()};
    std::string message(4096, '\0');
    void* world = nullptr;
    try {
        world = plugin->create(&setup, message.data(), message.size());
    } catch (const std::exception& e) {
        throw refuse(path, std::string("create() threw: ") + e.what());
    } catch (...) {
        throw refuse(path, "create() threw an exception that is no std::exception");
    }
    if (world == nullptr) {
        message.back() = '\0';
        message.resize(std::strlen(message.c_str()));
        throw refuse(path, message.empty() ? std::string("create() refused, saying nothing")
                                           : "create() refused: " + message);
    }
    auto guarded =
        std::make_unique<PluginWorld>(std::move(library), plugin, world, spec.max_call_us);
    LoadedPlugin loaded{.name = plugin->name != nullptr ? plugin->name : spec.name,
                        .description = plugin->description != nullptr ? plugin->description : "",
                        .path = path,
                        .admittance = admittance,
                        .impedance = nullptr,
                        .admittance_environment = nullptr};
    if (admittance) {
        loaded.admittance_environment =
            std::make_unique<PluginAdmittanceEnvironment>(std::move(guarded));
    } else {
        loaded.impedance = std::make_unique<PluginImpedanceEnvironment>(std::move(guarded));
    }
    return loaded;
}

}  // namespace hapticd::env
