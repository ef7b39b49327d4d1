// The passive operators and environments the exact model closes the loop with
// (exact_model.hpp's file comment draws each family and gives the default sweep): plain data,
// a factory per family, and a description for reports.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace hapticd::tune {

enum class OperatorFamily { hands_off, heavy_hand, stiff_grasp, two_mass_grasp, multi_mode };

/// "hands-off", "heavy hand", "stiff grasp", "two-mass grasp", "multi-mode grasp".
std::string_view to_string(OperatorFamily family);

/// A multi-mode grasp's absorber: handle --(stiffness, damping)-- mass.
struct OperatorMode {
    double mass_kg = 0.0;            ///< > 0
    double stiffness_n_per_m = 0.0;  ///< > 0
    double damping_n_s_per_m = 0.0;  ///< >= 0
};

/// A passive human operator. Only the fields its family uses may be non-zero
/// (closed_loop_poles rejects the others, so a typo cannot be silently ignored).
struct OperatorModel {
    OperatorFamily family = OperatorFamily::hands_off;
    double hand_mass_kg = 0.0;            ///< heavy hand, stiff grasp, two-mass, multi-mode
    double hand_damping_n_s_per_m = 0.0;  ///< heavy hand, stiff grasp, multi-mode (to ground)
    double hand_stiffness_n_per_m = 0.0;  ///< stiff grasp, multi-mode (to ground)
    double skin_stiffness_n_per_m = 0.0;  ///< two-mass grasp: handle to hand
    double skin_damping_n_s_per_m = 0.0;  ///< two-mass grasp: handle to hand
    double arm_stiffness_n_per_m = 0.0;   ///< two-mass grasp: hand to ground
    double arm_damping_n_s_per_m = 0.0;   ///< two-mass grasp: hand to ground
    std::vector<OperatorMode> modes;      ///< multi-mode grasp: the absorbers
    std::string origin;                   ///< multi-mode grasp: how it was built (for describe)

    static OperatorModel hands_off();
    static OperatorModel heavy_hand(double hand_mass_kg, double hand_damping_n_s_per_m);
    static OperatorModel stiff_grasp(double hand_mass_kg, double hand_stiffness_n_per_m,
                                     double hand_damping_n_s_per_m);
    static OperatorModel two_mass_grasp(double skin_stiffness_n_per_m,
                                        double skin_damping_n_s_per_m, double hand_mass_kg,
                                        double arm_stiffness_n_per_m, double arm_damping_n_s_per_m);
    static OperatorModel multi_mode(double hand_mass_kg, double hand_stiffness_n_per_m,
                                    double hand_damping_n_s_per_m, std::vector<OperatorMode> modes,
                                    std::string origin);

    /// For example "stiff grasp (m_h = 1 kg, k_h = 1000 N/m, b_h = 0 N s/m)".
    std::string describe() const;
};

/// A passive virtual environment, run in the servo tick (update in the file comment).
struct EnvironmentModel {
    enum class Kind { rigid_wall, mass_spring, lossless_mass_spring };
    Kind kind = Kind::rigid_wall;
    double mass_kg = 0.0;            ///< m_e >= 0
    double stiffness_n_per_m = 0.0;  ///< k_e >= 0 (k_e > 0 grounds the loop)
    double damping_n_s_per_m = 0.0;  ///< b_e >= 0

    static EnvironmentModel rigid_wall();
    /// Implicit Euler (the servo's own environments): dissipative.
    static EnvironmentModel mass_spring(double mass_kg, double stiffness_n_per_m,
                                        double damping_n_s_per_m = 0.0);
    /// Trapezoidal rule: lossless when b_e = 0.
    static EnvironmentModel lossless_mass_spring(double mass_kg, double stiffness_n_per_m,
                                                 double damping_n_s_per_m = 0.0);

    /// For example "mass-spring (m_e = 0.1 kg, k_e = 1000 N/m, b_e = 0 N s/m)".
    std::string describe() const;
};

}  // namespace hapticd::tune
