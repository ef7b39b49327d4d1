// A test environment plugin that does, after a number of ticks, what a plugin must not: its
// scene's [plugin.settings] say `mode = "error" | "nan" | "throw" | "slow" | "none"` and
// `after = N` (commits, or steps for the admittance build). Built as an impedance plugin and,
// with HAPTICD_TEST_ADMITTANCE, as an admittance one; with HAPTICD_TEST_ABI_VERSION as a
// plugin of another ABI version. A free-space world until it misbehaves.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>

#include "hapticd/env/plugin_abi.h"

namespace {

enum class Mode { none, error, nan, throws, slow };

struct World {
    Mode mode = Mode::none;
    long after = 0;
    long ticks = 0;
    bool misbehaving() const { return mode != Mode::none && ticks >= after; }
};

void spin_for_ms(int ms) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    while (std::chrono::steady_clock::now() < until) {
    }
}

// The tick's misbehaviour; 0 when it behaves.
std::int32_t misbehave(const World& w, double* value) {
    if (!w.misbehaving()) return 0;
    switch (w.mode) {
        case Mode::error:
            return 7;
        case Mode::nan:
            *value = std::nan("");
            return 0;
        case Mode::throws:
            throw std::runtime_error("the test world's own exception");
        case Mode::slow:
            spin_for_ms(20);
            return 0;
        case Mode::none:
            break;
    }
    return 0;
}

void* create(const hapticd_env_setup* setup, char* message, std::size_t capacity) {
    auto* w = new (std::nothrow) World;
    if (w == nullptr) return nullptr;
    const std::string settings = setup->settings;
    char mode[32] = "none";
    // toml++ writes a string either way: "error" or 'error'.
    if (const auto at = settings.find("mode = "); at != std::string::npos) {
        std::sscanf(settings.c_str() + at, "mode = %*1[\"']%31[a-z]", mode);
    }
    if (const auto at = settings.find("after = "); at != std::string::npos) {
        std::sscanf(settings.c_str() + at, "after = %ld", &w->after);
    }
    const std::string m = mode;
    if (m == "none")
        w->mode = Mode::none;
    else if (m == "error")
        w->mode = Mode::error;
    else if (m == "nan")
        w->mode = Mode::nan;
    else if (m == "throw")
        w->mode = Mode::throws;
    else if (m == "slow")
        w->mode = Mode::slow;
    else {
        std::snprintf(message, capacity,
                      "%s: [plugin.settings] mode = \"%s\": allowed none, "
                      "error, nan, throw or slow",
                      setup->scene_file, mode);
        delete w;
        return nullptr;
    }
    return w;
}

void destroy(void* world) { delete static_cast<World*>(world); }

std::int32_t reset(void* world, const double* /*position_m*/) {
    static_cast<World*>(world)->ticks = 0;
    return 0;
}

[[maybe_unused]] std::int32_t evaluate(const void* world, const double* /*x*/, const double* /*v*/,
                                       hapticd_env_penalty* out) {
    std::memset(out, 0, sizeof *out);
    return misbehave(*static_cast<const World*>(world), &out->force_n[0]);
}

[[maybe_unused]] std::int32_t commit(void* world, const double* /*x*/, const double* /*v*/) {
    ++static_cast<World*>(world)->ticks;
    return 0;
}

[[maybe_unused]] std::int32_t step(void* world, const double* x_d, const double* /*v_d*/,
                                   const hapticd_env_coupling* /*coupling*/, double* x_e) {
    auto* w = static_cast<World*>(world);
    for (int i = 0; i < 3; ++i) x_e[i] = x_d[i];
    const std::int32_t status = misbehave(*w, &x_e[0]);
    ++w->ticks;
    return status;
}

}  // namespace

#ifndef HAPTICD_TEST_ABI_VERSION
#define HAPTICD_TEST_ABI_VERSION HAPTICD_ENVIRONMENT_ABI_VERSION
#endif

extern "C" __attribute__((visibility("default"))) const hapticd_environment_plugin*
hapticd_environment_plugin_entry(void) {
#ifdef HAPTICD_TEST_ADMITTANCE
    static const hapticd_environment_plugin plugin = {HAPTICD_TEST_ABI_VERSION,
                                                      HAPTICD_ENV_ADMITTANCE,
                                                      "misbehaving-admittance",
                                                      "a test world that misbehaves after a while",
                                                      create,
                                                      destroy,
                                                      reset,
                                                      nullptr,
                                                      nullptr,
                                                      step};
#else
    static const hapticd_environment_plugin plugin = {HAPTICD_TEST_ABI_VERSION,
                                                      HAPTICD_ENV_IMPEDANCE,
                                                      "misbehaving",
                                                      "a test world that misbehaves after a while",
                                                      create,
                                                      destroy,
                                                      reset,
                                                      evaluate,
                                                      commit,
                                                      nullptr};
#endif
    return &plugin;
}
