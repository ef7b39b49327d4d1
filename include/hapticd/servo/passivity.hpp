// Time-domain passivity observer and controller (Hannaford & Ryu, "Time-domain passivity
// control of haptic interfaces", IEEE T-RA 18(1), 2002), at the device port.
//
// The observer integrates the energy that the virtual side (coupling + environment, as the
// controller renders it) has absorbed from the human through the handle:
//
//   E[n] = E[n-1] - F_h[n] . v_d[n] T                     (joules)
//
// where F_h is the force commanded on the handle and v_d the handle velocity. A passive
// virtual side keeps E >= 0; E < 0 means it has delivered net energy into the human's
// hand. The controller then adds a damping force -alpha v_d with
//
//   alpha = -E' / (|v_d|^2 T),  E' = E[n-1] - F_h . v_d T  (the energy before correction)
//
// which dissipates exactly the deficit, so that the corrected E[n] is 0 (alpha is capped
// at max_damping_n_s_per_m). record() then books the force that was really commanded.
#pragma once

#include <string_view>

#include "hapticd/servo/environment_port.hpp"

namespace hapticd::servo {

enum class PassivityMode {
    off,      ///< no observation
    observe,  ///< observe the energy only (telemetry, summary)
    control,  ///< observe and add damping when the energy goes negative
};
/// "off", "observe", "control" ([safety] passivity, an [external] scene's passivity). Inline:
/// the env layer, which uses servo's headers only, reads the names too.
constexpr std::string_view to_string(PassivityMode mode) noexcept {
    switch (mode) {
        case PassivityMode::off:
            return "off";
        case PassivityMode::observe:
            return "observe";
        case PassivityMode::control:
            return "control";
    }
    return "off";
}

struct PassivitySettings {
    PassivityMode mode = PassivityMode::observe;
    double max_damping_n_s_per_m = 200.0;  ///< cap on the controller's alpha
    double min_speed_mps = 1e-6;           ///< below this the controller does not act
};

class PassivityObserver {
  public:
    PassivityObserver() = default;
    explicit PassivityObserver(const PassivitySettings& settings) : settings_(settings) {}

    void reset() noexcept {
        energy_j_ = 0.0;
        damping_n_s_per_m_ = 0.0;
    }

    /// Controller: the handle force with the damping that keeps the energy non-negative.
    /// Does not change the observed energy; call record() with the force finally commanded.
    Vec3 control(const Vec3& handle_force_n, const Vec3& handle_velocity_mps,
                 double period_s) noexcept;

    /// Observer: books the energy of the force actually commanded this tick.
    void record(const Vec3& commanded_handle_force_n, const Vec3& handle_velocity_mps,
                double period_s) noexcept;

    /// Energy absorbed by the virtual side since reset, J; negative = it was active.
    double energy_j() const noexcept { return energy_j_; }
    /// The damping the controller added this tick, N s/m (0 when it did not act).
    double damping_n_s_per_m() const noexcept { return damping_n_s_per_m_; }
    PassivityMode mode() const noexcept { return settings_.mode; }

  private:
    PassivitySettings settings_{};
    double energy_j_ = 0.0;
    double damping_n_s_per_m_ = 0.0;
};

}  // namespace hapticd::servo
