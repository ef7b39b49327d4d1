// One axis of the simulated device with its human operator, integrated exactly under a
// zero-order hold.
//
// The device is (10) with the command taken as the force ON the handle, f = -F_d:
//     m dv/dt + b v = F_h + f
// and the operator's force F_h comes from the passive mechanics of HumanModel:
//   hands-off       F_h = 0
//   heavy hand      a mass m_h rigidly on the handle, damper b_h to ground:
//                   (m + m_h) dv/dt + (b + b_h) v = f
//   stiff grasp     as heavy hand, plus spring k_h and damper b_h to the set-point x_s(t):
//                   (m + m_h) dv/dt + b v + b_h (v - v_s) + k_h (x - x_s) = f
//   two-mass grasp  handle --(skin k_s, b_s)-- hand mass m_h --(arm k_a, b_a)-- x_s(t):
//                   m dv/dt + b v + k_s (x - x_h) + b_s (v - v_h) = f
//                   m_h dv_h/dt = k_s (x - x_h) + b_s (v - v_h) - k_a (x_h - x_s) - b_a (v_h - v_s)
// With a fixed set-point these are exactly the families of hapticd::tune::OperatorModel
// (exact_model.hpp), which put the set-point at 0.
//
// Exact discretisation: the state s = (x, v, x_h, v_h) and the inputs held over a step —
// the force f (ZOH), the set-point x_s moving at constant velocity v_s — form the augmented
// linear system dz/dt = M z with z = (s, f, x_s, v_s) and df/dt = 0, dx_s/dt = v_s,
// dv_s/dt = 0. So z(t + dt) = e^{M dt} z(t) exactly; configure() precomputes e^{M dt} for
// dt = T 2^-k, k = 0..kFractionBits, and a step of any whole number of units T 2^-20 is a
// product of those (binary decomposition). Per step: a 4x7 matrix times a 7-vector, no
// allocation.
//
// Loop delay (command_pipeline.hpp): a fractional delay φT splits each period into [0, φT)
// under the previous command and [φT, T) under the next. configure() also computes e^{M φT}
// and e^{M (1-φ) T} (and their 32nds for Coulomb friction), so step_period_split() is two
// exact ZOH steps, one per piece: the same discretisation with the hold instant moved, not
// rounded to T 2^-20.
//
// Coulomb friction (optional, magnitude F_c on the handle) is not linear. It is integrated
// in 2^kCoulombSubstepBits = 32 substeps per period, each an exact linear step:
//   moving (v != 0):  friction -F_c sign(v) is held over the substep (added to f);
//   at rest (v = 0):  if the other forces on the handle, |F_net| <= F_c, stiction holds it:
//                     the substep integrates the system with the handle clamped (x fixed,
//                     v = 0; the hand of a two-mass grasp keeps moving); else it breaks away
//                     with friction -F_c sign(F_net) held over the substep;
//   a substep in which v would change sign is redone with the handle clamped where the
//   substep began: friction stops the handle, never reverses it.
// Friction then only ever does negative work or none, so a passive operator stays passive
// (the energy test checks this), at the price of first-order accuracy in T/32 of the stop
// and breakaway instants. Between those, the motion is exact: sliding under a constant
// force is (10) under f - F_c sign(v) to rounding.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "hapticd/device/sim/sim_config.hpp"

namespace hapticd::device::sim {

/// Time is counted in units of T / 2^kFractionBits (about 1 ns at 1 kHz).
inline constexpr int kFractionBits = 20;
inline constexpr std::uint64_t kUnitsPerPeriod = std::uint64_t{1} << kFractionBits;
/// Coulomb substeps per period: 2^kCoulombSubstepBits.
inline constexpr int kCoulombSubstepBits = 5;

class AxisPlant {
  public:
    /// Mechanical state of one axis. For the single-mass families the hand moves with the
    /// handle and hand_position_m / hand_velocity_mps stay 0.
    struct State {
        double position_m = 0.0;         ///< x, handle
        double velocity_mps = 0.0;       ///< v, handle
        double hand_position_m = 0.0;    ///< x_h, two-mass grasp only
        double hand_velocity_mps = 0.0;  ///< v_h, two-mass grasp only
        double set_point_m = 0.0;        ///< x_s
    };

    /// Outside the tick (computes matrix exponentials). The hand of a two-mass grasp starts
    /// at the handle, the set-point at human.push.set_point_m(0); everything at rest.
    /// `split_fraction` (φ in [0, 1)): where step_period_split() changes the force.
    void configure(double mass_kg, double damping_n_s_per_m, double coulomb_n,
                   const HumanModel& human, double period_s, double initial_position_m,
                   double split_fraction = 0.0);

    /// Advances by `units` of T 2^-20 (any number, whole periods included) with the force
    /// `force_n` on the handle held and the set-point moving linearly to set_point_end_m.
    void advance(std::uint64_t units, double force_n, double set_point_end_m) noexcept;

    /// One whole period: advance(kUnitsPerPeriod, ...).
    void step_period(double force_n, double set_point_end_m) noexcept;

    /// One whole period with `lead_force_n` held over its first φT and `lag_force_n` over
    /// the rest (φ = configure()'s split_fraction), the set-point moving linearly to
    /// set_point_end_m over the whole period. Exact for any φ; φ = 0 is
    /// step_period(lag_force_n), bit for bit.
    void step_period_split(double lead_force_n, double lag_force_n,
                           double set_point_end_m) noexcept;

    const State& state() const noexcept { return state_; }
    void set_state(const State& state) noexcept { state_ = state; }

    /// Kinetic energy of the moving masses plus the potential energy of the operator's
    /// springs (measured from the set-point), J. Never increases with zero force and a
    /// fixed set-point: every element is passive.
    double energy_j() const noexcept;

    /// e^{M T}, rows x, v, x_h, v_h: the one-period transition of z = (x, v, x_h, v_h, f,
    /// x_s, v_s). For tests (it is the discrete plant the `exact` model samples).
    Eigen::Matrix<double, 4, 7> period_transition() const { return steps_[0].free; }

  private:
    using Transition = Eigen::Matrix<double, 4, 7>;

    /// The exact transitions of one step length dt, rows x, v, x_h, v_h.
    struct ExactStep {
        Transition free = Transition::Zero();   ///< e^{M dt}
        Transition stuck = Transition::Zero();  ///< the same with the handle clamped
        double duration_s = 0.0;                ///< dt
    };
    /// One piece of a split period: the whole piece and its 32nd (friction substeps).
    struct SplitPiece {
        ExactStep whole;
        ExactStep substep;
    };

    static ExactStep exact_step(const Eigen::Matrix<double, 7, 7>& m, double duration_s);

    /// One exact linear step with total handle force f and set-point velocity v_s; no
    /// friction.
    void linear_step(const ExactStep& step, double force_n, double set_point_velocity_mps) noexcept;
    /// A step of length T 2^-k including Coulomb friction (substeps when longer than one).
    void friction_step(int k, double force_n, double set_point_velocity_mps) noexcept;
    /// One Coulomb substep (the rules of the file comment) of `step`.
    void friction_substep(const ExactStep& step, double force_n,
                          double set_point_velocity_mps) noexcept;
    /// A step with the handle held still by stiction.
    void stuck_step(const ExactStep& step, double set_point_velocity_mps) noexcept;
    /// One piece of a split period, with friction in 32 substeps if there is any.
    void split_piece(const SplitPiece& piece, double force_n,
                     double set_point_velocity_mps) noexcept;
    /// The net force on the handle other than friction, at the current state with v = 0.
    double resting_handle_force_n(double force_n, double set_point_velocity_mps) const noexcept;

    std::array<ExactStep, kFractionBits + 1> steps_{};  ///< dt = T 2^-k
    SplitPiece lead_;                                   ///< dt = φT
    SplitPiece lag_;                                    ///< dt = (1 - φ) T
    double split_fraction_ = 0.0;                       ///< φ
    Eigen::Matrix<double, 1, 7> acceleration_row_ =
        Eigen::Matrix<double, 1, 7>::Zero();  ///< row v of M
    double handle_mass_kg_ = 1.0;             ///< the mass the handle's equation divides by
    double coulomb_n_ = 0.0;
    HumanModel human_;
    double mass_kg_ = 1.0;
    State state_;
};

}  // namespace hapticd::device::sim
