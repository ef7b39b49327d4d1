// The coupling gains haptic-tune sizes for the pen display, from the real executable:
// `haptic-tune size --mass 0.1 --damping 2 --rate 1000 --model MODEL --json`.
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "hapticd_run.hpp"
#include "pen_display.hpp"
#include "run_command.hpp"

namespace hapticd::testing {

/// Sizes (k_c, b_c) with the `model` ("passive", "encoder" or "paper") at b_c = 0 (the
/// default), without the exact cross-check (which rejects the paper's gains, exit 1: the
/// HIL tests show the same in closed loop). Fails the calling test (and returns zeros) if
/// haptic-tune fails.
inline CouplingGains run_haptic_tune_size(std::string_view model) {
    const std::string command = shell_quote(HAPTIC_TUNE_BIN) + " size --mass " +
                                toml_number(kPenMassKg) + " --damping " +
                                toml_number(kPenDampingNsPerM) + " --rate " + toml_number(kRateHz) +
                                " --model " + std::string(model) + " --json --no-exact-check";
    const CommandResult result = run_command(command);
    EXPECT_EQ(result.exit_code, 0) << command << "\n" << result.err;
    if (result.exit_code != 0) return {};
    const nlohmann::json sized = nlohmann::json::parse(result.out);
    return {.stiffness_n_per_m = sized.at("stiffness").get<double>(),
            .damping_n_s_per_m = sized.at("damping").get<double>()};
}

/// The same, sized once per test program and model.
inline CouplingGains size_coupling(std::string_view model) {
    static std::map<std::string, CouplingGains, std::less<>> sized;
    const auto found = sized.find(model);
    if (found != sized.end()) return found->second;
    const CouplingGains gains = run_haptic_tune_size(model);
    if (gains.stiffness_n_per_m > 0.0) sized.emplace(std::string(model), gains);
    return gains;
}

}  // namespace hapticd::testing
