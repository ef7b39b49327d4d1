// The operator classes the tests declare (tune/operator_class.hpp), as tune sees them.
#pragma once

#include "hapticd/tune/operator_class.hpp"

namespace hapticd::testing {

/// config/operators/pen-grip.toml: no member resonates near the aliases of Nyquist.
inline tune::OperatorClass pen_grip_class() {
    tune::OperatorClass c;
    c.hand_mass_kg = {0.1, 2.0};
    c.grip_stiffness_n_per_m = {0.0, 3000.0};
    c.grip_damping_n_s_per_m = {2.0, 30.0};
    c.arm_stiffness_n_per_m = {0.0, 1000.0};
    c.arm_damping_n_s_per_m = {0.0, 20.0};
    return c;
}

/// tests/tune/data/stiff-grips.toml, issue 27's class: stiff, lightly damped grips and arms,
/// whose members put two modes on two aliases at once.
inline tune::OperatorClass stiff_grips_class() {
    tune::OperatorClass c;
    c.hand_mass_kg = {0.05, 0.5};
    c.grip_stiffness_n_per_m = {1e5, 1e7};
    c.grip_damping_n_s_per_m = {0.0, 1.0};
    c.arm_stiffness_n_per_m = {1e5, 1e7};
    c.arm_damping_n_s_per_m = {0.0, 1.0};
    return c;
}

}  // namespace hapticd::testing
