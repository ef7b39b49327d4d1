// The virtual coupling's gains (16): the one type for them, from the theory's models to the
// servo's tick (servo::CouplingGains names it there) and the daemon's config.
#pragma once

namespace hapticd::theory {

/// F = k_c (x_d - x_e) + b_c (v_d - v_e), the same on every axis.
struct SpringDamperCoupling {
    double stiffness_n_per_m = 0.0;  ///< k_c
    double damping_n_s_per_m = 0.0;  ///< b_c
    /// f_c of the first-order low-pass on the damper's velocity (velocity_filter.hpp), Hz,
    /// 0 <= f_c < rate/2; 0: none, the damper acts on v_d - v_e itself.
    double velocity_filter_hz = 0.0;

    /// k_c = b_c = 0: the coupling carries no force, whatever the tool and the device do.
    bool renders_nothing() const noexcept {
        return stiffness_n_per_m == 0.0 && damping_n_s_per_m == 0.0;
    }
};

}  // namespace hapticd::theory
