// The operator and environment models of the exact model (operator_model.hpp): their
// factories and their descriptions.
#include "hapticd/tune/operator_model.hpp"

#include <sstream>
#include <utility>

namespace hapticd::tune {

std::string_view to_string(OperatorFamily family) {
    switch (family) {
        case OperatorFamily::hands_off:
            return "hands-off";
        case OperatorFamily::heavy_hand:
            return "heavy hand";
        case OperatorFamily::stiff_grasp:
            return "stiff grasp";
        case OperatorFamily::two_mass_grasp:
            return "two-mass grasp";
        case OperatorFamily::multi_mode:
            return "multi-mode grasp";
    }
    return "unknown";
}

OperatorModel OperatorModel::hands_off() { return {}; }

OperatorModel OperatorModel::heavy_hand(double hand_mass_kg, double hand_damping_n_s_per_m) {
    OperatorModel h;
    h.family = OperatorFamily::heavy_hand;
    h.hand_mass_kg = hand_mass_kg;
    h.hand_damping_n_s_per_m = hand_damping_n_s_per_m;
    return h;
}

OperatorModel OperatorModel::stiff_grasp(double hand_mass_kg, double hand_stiffness_n_per_m,
                                         double hand_damping_n_s_per_m) {
    OperatorModel h = heavy_hand(hand_mass_kg, hand_damping_n_s_per_m);
    h.family = OperatorFamily::stiff_grasp;
    h.hand_stiffness_n_per_m = hand_stiffness_n_per_m;
    return h;
}

OperatorModel OperatorModel::two_mass_grasp(double skin_stiffness_n_per_m,
                                            double skin_damping_n_s_per_m, double hand_mass_kg,
                                            double arm_stiffness_n_per_m,
                                            double arm_damping_n_s_per_m) {
    OperatorModel h;
    h.family = OperatorFamily::two_mass_grasp;
    h.skin_stiffness_n_per_m = skin_stiffness_n_per_m;
    h.skin_damping_n_s_per_m = skin_damping_n_s_per_m;
    h.hand_mass_kg = hand_mass_kg;
    h.arm_stiffness_n_per_m = arm_stiffness_n_per_m;
    h.arm_damping_n_s_per_m = arm_damping_n_s_per_m;
    return h;
}

OperatorModel OperatorModel::multi_mode(double hand_mass_kg, double hand_stiffness_n_per_m,
                                        double hand_damping_n_s_per_m,
                                        std::vector<OperatorMode> modes, std::string origin) {
    OperatorModel h = stiff_grasp(hand_mass_kg, hand_stiffness_n_per_m, hand_damping_n_s_per_m);
    h.family = OperatorFamily::multi_mode;
    h.modes = std::move(modes);
    h.origin = std::move(origin);
    return h;
}

std::string OperatorModel::describe() const {
    std::ostringstream s;
    s << to_string(family);
    switch (family) {
        case OperatorFamily::hands_off:
            break;
        case OperatorFamily::heavy_hand:
            s << " (m_h = " << hand_mass_kg << " kg, b_h = " << hand_damping_n_s_per_m << " N s/m)";
            break;
        case OperatorFamily::stiff_grasp:
            s << " (m_h = " << hand_mass_kg << " kg, k_h = " << hand_stiffness_n_per_m
              << " N/m, b_h = " << hand_damping_n_s_per_m << " N s/m)";
            break;
        case OperatorFamily::two_mass_grasp:
            s << " (k_s = " << skin_stiffness_n_per_m << " N/m, b_s = " << skin_damping_n_s_per_m
              << " N s/m, m_h = " << hand_mass_kg << " kg, k_a = " << arm_stiffness_n_per_m
              << " N/m, b_a = " << arm_damping_n_s_per_m << " N s/m)";
            break;
        case OperatorFamily::multi_mode:
            s << " (" << modes.size() << " modes" << (origin.empty() ? "" : ", ") << origin
              << "; m_h = " << hand_mass_kg << " kg, k_h = " << hand_stiffness_n_per_m
              << " N/m, b_h = " << hand_damping_n_s_per_m << " N s/m; modes (m_i kg, k_i N/m):";
            for (const OperatorMode& mode : modes) {
                s << " (" << mode.mass_kg << ", " << mode.stiffness_n_per_m << ")";
            }
            s << ")";
            break;
    }
    return s.str();
}

EnvironmentModel EnvironmentModel::rigid_wall() { return {}; }

EnvironmentModel EnvironmentModel::mass_spring(double mass_kg, double stiffness_n_per_m,
                                               double damping_n_s_per_m) {
    return {Kind::mass_spring, mass_kg, stiffness_n_per_m, damping_n_s_per_m};
}

EnvironmentModel EnvironmentModel::lossless_mass_spring(double mass_kg, double stiffness_n_per_m,
                                                        double damping_n_s_per_m) {
    return {Kind::lossless_mass_spring, mass_kg, stiffness_n_per_m, damping_n_s_per_m};
}

std::string EnvironmentModel::describe() const {
    if (kind == Kind::rigid_wall) return "rigid wall";
    std::ostringstream s;
    s << (kind == Kind::mass_spring ? "mass-spring" : "lossless mass-spring (trapezoidal)")
      << " (m_e = " << mass_kg << " kg, k_e = " << stiffness_n_per_m
      << " N/m, b_e = " << damping_n_s_per_m << " N s/m)";
    return s.str();
}

}  // namespace hapticd::tune
