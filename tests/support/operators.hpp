// The passive human operators the sim plugin offers (docs/sim-device.md), with the
// parameters the HIL tests hold the pen display with. They are the families of the exact
// model's sweep (docs/stability-models.md): hands-off, heavy hand, stiff grasp, two-mass grasp.
#pragma once

#include <string>

#include "pen_display.hpp"

namespace hapticd::testing {

/// Nothing on the handle.
inline std::string hands_off() { return "model = \"hands-off\"\n"; }

/// A hand of `hand_mass_kg` riding on the handle, with `hand_damping_n_s_per_m` to ground.
inline std::string heavy_hand(double hand_mass_kg = 0.3, double hand_damping_n_s_per_m = 0.5) {
    return "model = \"heavy-hand\"\nhand_mass = " + toml_number(hand_mass_kg) +
           "\nhand_damping = " + toml_number(hand_damping_n_s_per_m) + "\n";
}

/// A heavy hand with a spring-damper to its set-point, which follows `push` (push_toml());
/// empty `push`: the set-point stays at the initial position.
inline std::string stiff_grasp(const std::string& push, double hand_stiffness_n_per_m = 500.0,
                               double hand_damping_n_s_per_m = 5.0, double hand_mass_kg = 0.3) {
    return "model = \"stiff-grasp\"\nhand_mass = " + toml_number(hand_mass_kg) +
           "\nhand_stiffness = " + toml_number(hand_stiffness_n_per_m) +
           "\nhand_damping = " + toml_number(hand_damping_n_s_per_m) + "\n" + push;
}

/// Handle --(skin)-- hand mass --(arm)-- set-point following `push`; the sim's defaults.
inline std::string two_mass_grasp(const std::string& push) {
    return "model = \"two-mass-grasp\"\nhand_mass = 0.5\nskin_stiffness = 1000.0\n"
           "skin_damping = 1.0\narm_stiffness = 100.0\narm_damping = 10.0\n" +
           push;
}

}  // namespace hapticd::testing
