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
//   multi-mode      as stiff grasp, plus up to kMaxOperatorModes absorbers, each a mass m_i on
//   grasp           the handle through k_i, b_i: m_i dv_i/dt = k_i (x - x_i) + b_i (v - v_i),
//                   and the handle feels -Σ (k_i (x - x_i) + b_i (v - v_i)) besides
// With a fixed set-point these are exactly the families of hapticd::tune::OperatorModel
// (exact_model.hpp), which put the set-point at 0. Each is a network of masses (the handle
// and the operator's own: the two-mass grasp's hand, the absorbers) joined by springs and
// dampers to each other, to ground or to the set-point; configure() builds the one linear
// system from that list.
//
// Exact discretisation: the state s = (x, v, x_1, v_1, ..., x_M, v_M) (M operator masses,
// 0 to kMaxOperatorModes) and the inputs held over a step — the force f (ZOH), the set-point
// x_s moving at constant velocity v_s — form the augmented linear system dz/dt = M z with
// z = (s, f, x_s, v_s) and df/dt = 0, dx_s/dt = v_s, dv_s/dt = 0. So z(t + dt) = e^{M dt} z(t)
// exactly; configure() precomputes e^{M dt} for dt = T 2^-k, k = 0..kFractionBits, and a step
// of any whole number of units T 2^-20 is a product of those (binary decomposition). Per
// step: an n x (n + 3) matrix times a vector (n = 2 + 2M; 4 x 7 for the two-mass grasp), in
// Eigen matrices of fixed maximum size: no allocation.
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
    /// Mechanical state of one axis.
    struct State {
        double position_m = 0.0;    ///< x, handle
        double velocity_mps = 0.0;  ///< v, handle
        /// The operator's own masses (the two-mass grasp's hand, a multi-mode grasp's
        /// absorbers, in order); the others stay 0.
        std::array<double, kMaxOperatorModes> mass_position_m{};
        std::array<double, kMaxOperatorModes> mass_velocity_mps{};
        double set_point_m = 0.0;  ///< x_s
    };

    /// Outside the tick (computes matrix exponentials). The operator's masses start at the
    /// handle, the set-point at human.push.set_point_m(0); everything at rest.
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

    /// The number of states n = 2 + 2M (handle, then each operator mass: position, velocity).
    int states() const noexcept { return states_; }

    /// e^{M T}: the one-period transition of z = (s, f, x_s, v_s), n rows and n + 3 columns.
    /// For tests (it is the discrete plant the `exact` model samples).
    Eigen::MatrixXd period_transition() const {
        return steps_[0].free.topLeftCorner(states_, states_ + 3);
    }

  private:
    static constexpr int kMaxStates = 2 + 2 * kMaxOperatorModes;
    static constexpr int kMaxAugmented = kMaxStates + 3;
    using Augmented = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor,
                                    kMaxAugmented, kMaxAugmented>;
    using Transition = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor,
                                     kMaxStates, kMaxAugmented>;
    using AugmentedVector =
        Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxAugmented, 1>;
    using StateVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxStates, 1>;
    using AccelerationRow =
        Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMaxAugmented>;

    /// The exact transitions of one step length dt: the n state rows of e^{M dt}.
    struct ExactStep {
        Transition free;          ///< e^{M dt}
        Transition stuck;         ///< the same with the handle clamped
        double duration_s = 0.0;  ///< dt
    };
    /// One piece of a split period: the whole piece and its 32nd (friction substeps).
    struct SplitPiece {
        ExactStep whole;
        ExactStep substep;
    };
    /// A spring and a damper between two nodes: the handle (0), an operator mass (1..M), or
    /// one of kGround and kSetPoint.
    struct Link {
        int from = 0;
        int to = 0;
        double stiffness_n_per_m = 0.0;
        double damping_n_s_per_m = 0.0;
    };
    static constexpr int kGround = -1;
    static constexpr int kSetPoint = -2;
    /// At most: the device's damper, the hand's spring-damper and one per operator mass.
    static constexpr int kMaxLinks = 2 + kMaxOperatorModes;

    /// The operator's masses and links for `human` (the file comment's networks).
    void build_network(double mass_kg, double damping_n_s_per_m, const HumanModel& human);
    /// M of the file comment: dz/dt = M z.
    Augmented continuous_matrix() const;
    ExactStep exact_step(const Augmented& m, double duration_s) const;
    /// z = (s, f, x_s, v_s) from the state, with the handle's velocity `handle_velocity_mps`.
    AugmentedVector augmented(double handle_velocity_mps, double force_n,
                              double set_point_velocity_mps) const noexcept;
    /// The state from the n rows of a step.
    void set_states(const StateVector& next) noexcept;

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
    AccelerationRow acceleration_row_;                  ///< row v of M
    int masses_ = 0;                                    ///< M, the operator's own masses
    int states_ = 2;                                    ///< n = 2 + 2M
    double handle_mass_kg_ = 1.0;                       ///< the handle's, with a hand rigidly on it
    std::array<double, kMaxOperatorModes> mass_kg_{};   ///< the operator's masses
    std::array<Link, kMaxLinks> links_{};
    int link_count_ = 0;
    double coulomb_n_ = 0.0;
    State state_;
};

}  // namespace hapticd::device::sim
