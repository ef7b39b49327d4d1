#include "hapticd/device/sim/axis_plant.hpp"

#include <cmath>
#include <unsupported/Eigen/MatrixFunctions>

namespace hapticd::device::sim {
namespace {

// Indices into the augmented state z = (x, v, x_h, v_h, f, x_s, v_s).
constexpr int kX = 0, kV = 1, kXh = 2, kVh = 3, kF = 4, kXs = 5, kVs = 6;
using Augmented = Eigen::Matrix<double, 7, 7>;

/// M of the file comment of axis_plant.hpp: dz/dt = M z.
Augmented continuous_matrix(double m, double b, const HumanModel& h) {
    Augmented a = Augmented::Zero();
    a(kX, kV) = 1.0;
    a(kXs, kVs) = 1.0;  // the set-point moves at v_s; f and v_s are held
    switch (h.family) {
        case HumanFamily::hands_off:  // (10): m dv/dt = -b v + f
            a(kV, kV) = -b / m;
            a(kV, kF) = 1.0 / m;
            break;
        case HumanFamily::heavy_hand:
        case HumanFamily::stiff_grasp: {
            // (m + m_h) dv/dt = -b v - b_h (v - v_s) - k_h (x - x_s) + f; heavy hand: k_h = 0,
            // and its damper is to ground (v_s enters only through the stiff grasp).
            const double total = m + h.hand_mass_kg;
            const double bh = h.hand_damping_n_s_per_m, kh = h.hand_stiffness_n_per_m;
            const bool grasp = h.family == HumanFamily::stiff_grasp;
            a(kV, kX) = -kh / total;
            a(kV, kV) = -(b + bh) / total;
            a(kV, kF) = 1.0 / total;
            a(kV, kXs) = kh / total;
            a(kV, kVs) = grasp ? bh / total : 0.0;
            break;
        }
        case HumanFamily::two_mass_grasp: {
            const double ks = h.skin_stiffness_n_per_m, bs = h.skin_damping_n_s_per_m;
            const double mh = h.hand_mass_kg;
            const double ka = h.arm_stiffness_n_per_m, ba = h.arm_damping_n_s_per_m;
            // m dv/dt = -b v - k_s (x - x_h) - b_s (v - v_h) + f
            a(kV, kX) = -ks / m;
            a(kV, kV) = -(b + bs) / m;
            a(kV, kXh) = ks / m;
            a(kV, kVh) = bs / m;
            a(kV, kF) = 1.0 / m;
            // m_h dv_h/dt = k_s (x - x_h) + b_s (v - v_h) - k_a (x_h - x_s) - b_a (v_h - v_s)
            a(kXh, kVh) = 1.0;
            a(kVh, kX) = ks / mh;
            a(kVh, kV) = bs / mh;
            a(kVh, kXh) = -(ks + ka) / mh;
            a(kVh, kVh) = -(bs + ba) / mh;
            a(kVh, kXs) = ka / mh;
            a(kVh, kVs) = ba / mh;
            break;
        }
    }
    return a;
}

}  // namespace

AxisPlant::ExactStep AxisPlant::exact_step(const Augmented& a, double duration_s) {
    ExactStep step;
    step.duration_s = duration_s;
    const Augmented scaled = a * duration_s;
    const Augmented e = scaled.exp();
    step.free = e.topRows<4>();
    Augmented held = a;  // the handle clamped by stiction: dx/dt = dv/dt = 0
    held.row(kX).setZero();
    held.row(kV).setZero();
    const Augmented held_scaled = held * duration_s;
    const Augmented held_e = held_scaled.exp();
    step.stuck = held_e.topRows<4>();
    return step;
}

void AxisPlant::configure(double mass_kg, double damping_n_s_per_m, double coulomb_n,
                          const HumanModel& human, double period_s, double initial_position_m,
                          double split_fraction) {
    human_ = human;
    mass_kg_ = mass_kg;
    coulomb_n_ = coulomb_n;
    const bool rigid_hand =
        human.family == HumanFamily::heavy_hand || human.family == HumanFamily::stiff_grasp;
    handle_mass_kg_ = rigid_hand ? mass_kg + human.hand_mass_kg : mass_kg;
    const Augmented a = continuous_matrix(mass_kg, damping_n_s_per_m, human);
    acceleration_row_ = a.row(kV);
    for (int k = 0; k <= kFractionBits; ++k) steps_[k] = exact_step(a, std::ldexp(period_s, -k));
    // A fractional loop delay: the period's two pieces [0, φT) and [φT, T), each with its
    // own exact ZOH transition (and 32 substeps of it for Coulomb friction).
    split_fraction_ = split_fraction;
    const double substeps = static_cast<double>(1 << kCoulombSubstepBits);
    lead_ = {};
    lag_ = {};
    if (split_fraction_ > 0.0) {
        const double lead_s = split_fraction_ * period_s;
        const double lag_s = (1.0 - split_fraction_) * period_s;
        lead_ = {exact_step(a, lead_s), exact_step(a, lead_s / substeps)};
        lag_ = {exact_step(a, lag_s), exact_step(a, lag_s / substeps)};
    }
    state_ = State{};
    state_.position_m = initial_position_m;
    state_.set_point_m = human.push.set_point_m(0.0);
    if (human.family == HumanFamily::two_mass_grasp) state_.hand_position_m = initial_position_m;
}

void AxisPlant::linear_step(const ExactStep& step, double force_n,
                            double set_point_velocity_mps) noexcept {
    Eigen::Matrix<double, 7, 1> z;
    z << state_.position_m, state_.velocity_mps, state_.hand_position_m, state_.hand_velocity_mps,
        force_n, state_.set_point_m, set_point_velocity_mps;
    const Eigen::Matrix<double, 4, 1> next = step.free * z;
    state_.position_m = next(kX);
    state_.velocity_mps = next(kV);
    state_.hand_position_m = next(kXh);
    state_.hand_velocity_mps = next(kVh);
    state_.set_point_m += set_point_velocity_mps * step.duration_s;
}

double AxisPlant::resting_handle_force_n(double force_n,
                                         double set_point_velocity_mps) const noexcept {
    Eigen::Matrix<double, 7, 1> z;
    z << state_.position_m, 0.0, state_.hand_position_m, state_.hand_velocity_mps, force_n,
        state_.set_point_m, set_point_velocity_mps;
    return handle_mass_kg_ * acceleration_row_.dot(z);
}

void AxisPlant::stuck_step(const ExactStep& step, double set_point_velocity_mps) noexcept {
    Eigen::Matrix<double, 7, 1> z;
    z << state_.position_m, 0.0, state_.hand_position_m, state_.hand_velocity_mps, 0.0,
        state_.set_point_m, set_point_velocity_mps;
    const Eigen::Matrix<double, 4, 1> next = step.stuck * z;
    state_.velocity_mps = 0.0;  // the handle is held; x stays as it is
    state_.hand_position_m = next(kXh);
    state_.hand_velocity_mps = next(kVh);
    state_.set_point_m += set_point_velocity_mps * step.duration_s;
}

void AxisPlant::friction_step(int k, double force_n, double set_point_velocity_mps) noexcept {
    if (k < kCoulombSubstepBits) {  // longer than a substep: split
        for (int i = 0; i < (1 << (kCoulombSubstepBits - k)); ++i) {
            friction_substep(steps_[kCoulombSubstepBits], force_n, set_point_velocity_mps);
        }
        return;
    }
    friction_substep(steps_[k], force_n, set_point_velocity_mps);
}

void AxisPlant::friction_substep(const ExactStep& step, double force_n,
                                 double set_point_velocity_mps) noexcept {
    const State start = state_;
    // The direction friction opposes: the motion, or at rest the net force it must hold.
    double direction = start.velocity_mps;
    if (direction == 0.0) {
        const double net_n = resting_handle_force_n(force_n, set_point_velocity_mps);
        if (std::abs(net_n) <= coulomb_n_) {  // stiction holds the handle
            stuck_step(step, set_point_velocity_mps);
            return;
        }
        direction = net_n;  // breakaway
    }
    const double friction_n = direction > 0.0 ? -coulomb_n_ : coulomb_n_;
    linear_step(step, force_n + friction_n, set_point_velocity_mps);
    if ((state_.velocity_mps > 0.0) != (direction > 0.0) || state_.velocity_mps == 0.0) {
        // Friction stopped the handle within the substep (it never reverses it): hold it
        // where the substep began, which only removes the handle's kinetic energy.
        state_ = start;
        stuck_step(step, set_point_velocity_mps);
    }
}

void AxisPlant::advance(std::uint64_t units, double force_n, double set_point_end_m) noexcept {
    if (units == 0) return;
    const double duration_s = static_cast<double>(units) * steps_[kFractionBits].duration_s;
    const double set_point_velocity_mps = (set_point_end_m - state_.set_point_m) / duration_s;
    const std::uint64_t periods = units >> kFractionBits;
    const std::uint64_t fraction = units & (kUnitsPerPeriod - 1);
    const bool friction = coulomb_n_ > 0.0;
    for (std::uint64_t i = 0; i < periods; ++i) {
        friction ? friction_step(0, force_n, set_point_velocity_mps)
                 : linear_step(steps_[0], force_n, set_point_velocity_mps);
    }
    for (int k = 1; k <= kFractionBits; ++k) {
        if ((fraction >> (kFractionBits - k)) & 1u) {
            friction ? friction_step(k, force_n, set_point_velocity_mps)
                     : linear_step(steps_[k], force_n, set_point_velocity_mps);
        }
    }
    state_.set_point_m = set_point_end_m;  // no drift from summing the pieces
}

void AxisPlant::step_period(double force_n, double set_point_end_m) noexcept {
    advance(kUnitsPerPeriod, force_n, set_point_end_m);
}

void AxisPlant::split_piece(const SplitPiece& piece, double force_n,
                            double set_point_velocity_mps) noexcept {
    if (coulomb_n_ > 0.0) {
        for (int i = 0; i < (1 << kCoulombSubstepBits); ++i) {
            friction_substep(piece.substep, force_n, set_point_velocity_mps);
        }
    } else {
        linear_step(piece.whole, force_n, set_point_velocity_mps);
    }
}

void AxisPlant::step_period_split(double lead_force_n, double lag_force_n,
                                  double set_point_end_m) noexcept {
    if (split_fraction_ == 0.0) {  // no fractional delay: the force changes at nT
        step_period(lag_force_n, set_point_end_m);
        return;
    }
    // z((n + φ) T) = e^{M φT} z(nT) under F[n-q-1], then z((n+1) T) = e^{M (1-φ) T} z((n + φ) T)
    // under F[n-q]; the set-point moves at one velocity over the whole period.
    const double set_point_velocity_mps =
        (set_point_end_m - state_.set_point_m) / steps_[0].duration_s;
    split_piece(lead_, lead_force_n, set_point_velocity_mps);
    split_piece(lag_, lag_force_n, set_point_velocity_mps);
    state_.set_point_m = set_point_end_m;
}

double AxisPlant::energy_j() const noexcept {
    const State& s = state_;
    const HumanModel& h = human_;
    const double stretch_m = s.position_m - s.set_point_m;
    switch (h.family) {
        case HumanFamily::hands_off:
            return 0.5 * mass_kg_ * s.velocity_mps * s.velocity_mps;
        case HumanFamily::heavy_hand:
        case HumanFamily::stiff_grasp:
            return 0.5 * handle_mass_kg_ * s.velocity_mps * s.velocity_mps +
                   0.5 * h.hand_stiffness_n_per_m * stretch_m * stretch_m;
        case HumanFamily::two_mass_grasp: {
            const double skin_m = s.position_m - s.hand_position_m;
            const double arm_m = s.hand_position_m - s.set_point_m;
            return 0.5 * mass_kg_ * s.velocity_mps * s.velocity_mps +
                   0.5 * h.hand_mass_kg * s.hand_velocity_mps * s.hand_velocity_mps +
                   0.5 * h.skin_stiffness_n_per_m * skin_m * skin_m +
                   0.5 * h.arm_stiffness_n_per_m * arm_m * arm_m;
        }
    }
    return 0.0;
}

}  // namespace hapticd::device::sim
