// libFuzzer target for hapticd's config reader (daemon::parse_config, docs/daemon.md
// "Config"): any text is either a config whose values are in their documented ranges, or a
// ConfigError. Anything else (another exception, a crash, a hang, a stack overflow inside
// toml++) is a finding. The same entry point replays the seed corpus (fuzz/corpus/config) in
// ctest under GCC (tests/fuzz_replay).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_check.hpp"
#include "hapticd/daemon/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const hapticd::daemon::Config c = hapticd::daemon::parse_config(text, "fuzz.toml", "/fuzz");
        FUZZ_CHECK(c.servo.rate_hz >= 100.0 && c.servo.rate_hz <= 20000.0);
        FUZZ_CHECK(c.device.axes >= 1 && c.device.axes <= 3);
        FUZZ_CHECK(c.safety.max_force_n > 0.0 && c.safety.max_force_n <= 1e4);
        FUZZ_CHECK(c.safety.max_speed_mps > 0.0 && c.safety.max_speed_mps <= 100.0);
        FUZZ_CHECK(std::isfinite(c.coupling.stiffness_n_per_m) &&
                   c.coupling.stiffness_n_per_m >= 0.0);
        FUZZ_CHECK(std::isfinite(c.coupling.damping_n_s_per_m) &&
                   c.coupling.damping_n_s_per_m >= 0.0);
        FUZZ_CHECK(c.safety.overrun.max_missed_periods >= 0 &&
                   c.safety.overrun.max_consecutive_overruns >= 0);
    } catch (const hapticd::daemon::ConfigError&) {
        // refused, with a message: what bad input must get
    }
    return 0;
}
