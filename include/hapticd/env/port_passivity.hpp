// The passivity observer and controller on the environment port of an admittance world whose
// passivity hapticd cannot assume (an external world: external_environment.hpp). Hannaford &
// Ryu's observer ("Time-domain passivity control of haptic interfaces", IEEE T-RA 18(1),
// 2002) books the energy the coupling (22) puts into the world through the tool,
//
//   E[n] = E[n-1] + f_c[n] . (x_e[n] - x_e[n-1]),          (joules, from the last reset)
//
// with f_c[n] = k_c (x_d - x_e[n]) + b_c (v_d - (x_e[n] - x_e[n-1])/T) the coupling's force on
// the tool in the tick: the paper's passivity (5) at the environment port, in discrete time
// (F_e* v_e* T summed). A world is passive at the port when E[n] >= 0 for every n.
//
// The controller keeps it so, exactly. f_c[n] is affine in the tool's step d = x_e[n] - x_e[n-1]:
//   f_c = f0 - kappa d,  f0 = k_c (x_d - x_e[n-1]) + b_c v_d,  kappa = k_c + b_c/T,
// so E[n] >= 0 holds for the steps d in the ball
//   | d - f0/(2 kappa) |^2 <= (E[n-1] + |f0|^2/(4 kappa)) / kappa,
// which holds d = 0 (the tool stays: no energy) whenever E[n-1] >= 0. The controller takes the
// world's step when it is in the ball and the point of the ball nearest it otherwise: the tool
// yields (or lags) just enough that the world delivers no net energy. It is Hannaford & Ryu's
// controller in admittance form (a series element on the tool's motion), solved in closed form
// rather than through a damping alpha. The coupling then sees a passive environment, and the
// certified gains' guarantee (inequality (21)) holds for the world whatever it does.
#pragma once

#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/passivity.hpp"

namespace hapticd::env {

using servo::CouplingGains;
using servo::PassivityMode;
using servo::Vec3;

class PortPassivity {
  public:
    PortPassivity() = default;
    explicit PortPassivity(PassivityMode mode) : mode_(mode) {}

    /// Energy back to 0: the world starts again, its tool at `tool_position_m` (what was
    /// removed is kept).
    void reset(const Vec3& tool_position_m) noexcept {
        energy_j_ = 0.0;
        previous_wanted_m_ = tool_position_m;
    }

    /// The tool's position this tick: `wanted_m` (the world's), or the nearest that keeps the
    /// port passive (control); `previous_m` is the tool's last position, x_d and v_d the
    /// handle's, `gains` the coupling's (as step() gets them) and `period_s` this tick's T.
    /// Books the energy of the step taken.
    Vec3 limit(const Vec3& wanted_m, const Vec3& previous_m, const Vec3& device_position_m,
               const Vec3& device_velocity_mps, const CouplingGains& gains,
               double period_s) noexcept;

    /// E[n], J: the energy the world has absorbed at the port since the reset (>= 0 under
    /// control).
    double energy_j() const noexcept { return energy_j_; }
    /// What the controller has removed, J, over every reset: at each tick it acted, what the
    /// world's own motion in the tick (w[n] - w[n-1], applied to the tool) would have taken
    /// out of the port beyond the energy the port held, max(0, -(E[n-1] + g(w[n] - w[n-1])))
    /// with g(d) = f_c . d; summed. A world at rest adds nothing, however far from its wish
    /// the tool is held; a world whose motion is active adds what each tick of it would take.
    double removed_j() const noexcept { return removed_j_; }
    /// Whether the controller changed this tick's step.
    bool acted() const noexcept { return acted_; }
    PassivityMode mode() const noexcept { return mode_; }

  private:
    PassivityMode mode_ = PassivityMode::control;
    double energy_j_ = 0.0;  ///< E[n] of the tool rendered
    double removed_j_ = 0.0;
    Vec3 previous_wanted_m_{0.0};  ///< w[n-1]
    bool acted_ = false;
};

}  // namespace hapticd::env
