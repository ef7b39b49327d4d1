#include "hapticd/device/sim/axis_plant.hpp"

#include <cmath>
#include <unsupported/Eigen/MatrixFunctions>

namespace hapticd::device::sim {

void AxisPlant::build_network(double mass_kg, double damping_n_s_per_m, const HumanModel& h) {
    masses_ = 0;
    link_count_ = 0;
    mass_kg_.fill(0.0);
    // Every hand but the two-mass grasp's is rigidly on the handle (hands-off: m_h = 0).
    handle_mass_kg_ = mass_kg + (h.family == HumanFamily::two_mass_grasp ? 0.0 : h.hand_mass_kg);
    const auto link = [&](int from, int to, double k, double b) {
        links_[static_cast<std::size_t>(link_count_++)] = {from, to, k, b};
    };
    const auto mass = [&](double kg) {
        mass_kg_[static_cast<std::size_t>(masses_++)] = kg;
        return masses_;  // its node
    };
    link(0, kGround, 0.0, damping_n_s_per_m);  // (10)'s b
    switch (h.family) {
        case HumanFamily::hands_off:
            break;
        case HumanFamily::heavy_hand:
            link(0, kGround, 0.0, h.hand_damping_n_s_per_m);
            break;
        case HumanFamily::stiff_grasp:
            link(0, kSetPoint, h.hand_stiffness_n_per_m, h.hand_damping_n_s_per_m);
            break;
        case HumanFamily::two_mass_grasp: {
            const int hand = mass(h.hand_mass_kg);
            link(0, hand, h.skin_stiffness_n_per_m, h.skin_damping_n_s_per_m);
            link(hand, kSetPoint, h.arm_stiffness_n_per_m, h.arm_damping_n_s_per_m);
            break;
        }
        case HumanFamily::multi_mode_grasp:
            link(0, kSetPoint, h.hand_stiffness_n_per_m, h.hand_damping_n_s_per_m);
            for (int i = 0; i < h.mode_count; ++i) {
                const OperatorMode& mode = h.modes[static_cast<std::size_t>(i)];
                link(0, mass(mode.mass_kg), mode.stiffness_n_per_m, mode.damping_n_s_per_m);
            }
            break;
    }
    states_ = 2 + 2 * masses_;
}

AxisPlant::Augmented AxisPlant::continuous_matrix() const {
    // z = (x, v, x_1, v_1, ..., x_M, v_M, f, x_s, v_s); node 0 is the handle, node i the
    // operator mass at rows 2i, 2i + 1.
    const int n = states_, f = n, xs = n + 1, vs = n + 2;
    Augmented a = Augmented::Zero(n + 3, n + 3);
    const auto node_mass = [&](int node) {
        return node == 0 ? handle_mass_kg_ : mass_kg_[static_cast<std::size_t>(node - 1)];
    };
    for (Eigen::Index node = 0; node <= masses_; ++node)
        a(2 * node, 2 * node + 1) = 1.0;  // dx/dt = v
    a(xs, vs) = 1.0;                      // the set-point moves at v_s; f and v_s are held
    a(1, f) = 1.0 / node_mass(0);
    // A link's force on `from` is -k (x_from - x_to) - b (v_from - v_to), and the opposite
    // on `to`; ground stays at 0, the set-point is (x_s, v_s).
    const auto add = [&](int on, int sign, const Link& l, int x_column, int v_column) {
        const double m = node_mass(on);
        a(2 * on + 1, x_column) += sign * l.stiffness_n_per_m / m;
        a(2 * on + 1, v_column) += sign * l.damping_n_s_per_m / m;
    };
    for (int i = 0; i < link_count_; ++i) {
        const Link& l = links_[static_cast<std::size_t>(i)];
        add(l.from, -1, l, 2 * l.from, 2 * l.from + 1);
        if (l.to >= 0) {
            add(l.from, +1, l, 2 * l.to, 2 * l.to + 1);
            add(l.to, -1, l, 2 * l.to, 2 * l.to + 1);
            add(l.to, +1, l, 2 * l.from, 2 * l.from + 1);
        } else if (l.to == kSetPoint) {
            add(l.from, +1, l, xs, vs);
        }
    }
    return a;
}

AxisPlant::ExactStep AxisPlant::exact_step(const Augmented& a, double duration_s) const {
    ExactStep step;
    step.duration_s = duration_s;
    const Augmented scaled = a * duration_s;
    const Augmented e = scaled.exp();
    step.free = e.topRows(states_);
    Augmented held = a;  // the handle clamped by stiction: dx/dt = dv/dt = 0
    held.row(0).setZero();
    held.row(1).setZero();
    const Augmented held_scaled = held * duration_s;
    const Augmented held_e = held_scaled.exp();
    step.stuck = held_e.topRows(states_);
    return step;
}

void AxisPlant::configure(double mass_kg, double damping_n_s_per_m, double coulomb_n,
                          const HumanModel& human, double period_s, double initial_position_m,
                          double split_fraction) {
    coulomb_n_ = coulomb_n;
    build_network(mass_kg, damping_n_s_per_m, human);
    const Augmented a = continuous_matrix();
    acceleration_row_ = a.row(1);
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
    for (int i = 0; i < masses_; ++i)
        state_.mass_position_m[static_cast<std::size_t>(i)] = initial_position_m;
}

AxisPlant::AugmentedVector AxisPlant::augmented(double handle_velocity_mps, double force_n,
                                                double set_point_velocity_mps) const noexcept {
    AugmentedVector z(states_ + 3);
    z(0) = state_.position_m;
    z(1) = handle_velocity_mps;
    for (int i = 0; i < masses_; ++i) {
        z(2 + 2 * i) = state_.mass_position_m[static_cast<std::size_t>(i)];
        z(3 + 2 * i) = state_.mass_velocity_mps[static_cast<std::size_t>(i)];
    }
    z(states_) = force_n;
    z(states_ + 1) = state_.set_point_m;
    z(states_ + 2) = set_point_velocity_mps;
    return z;
}

void AxisPlant::set_states(const StateVector& next) noexcept {
    state_.position_m = next(0);
    state_.velocity_mps = next(1);
    for (int i = 0; i < masses_; ++i) {
        state_.mass_position_m[static_cast<std::size_t>(i)] = next(2 + 2 * i);
        state_.mass_velocity_mps[static_cast<std::size_t>(i)] = next(3 + 2 * i);
    }
}

void AxisPlant::linear_step(const ExactStep& step, double force_n,
                            double set_point_velocity_mps) noexcept {
    const AugmentedVector z = augmented(state_.velocity_mps, force_n, set_point_velocity_mps);
    StateVector next(states_);
    next.noalias() = step.free * z;
    set_states(next);
    state_.set_point_m += set_point_velocity_mps * step.duration_s;
}

double AxisPlant::resting_handle_force_n(double force_n,
                                         double set_point_velocity_mps) const noexcept {
    return handle_mass_kg_ * acceleration_row_.dot(augmented(0.0, force_n, set_point_velocity_mps));
}

void AxisPlant::stuck_step(const ExactStep& step, double set_point_velocity_mps) noexcept {
    const double x = state_.position_m;
    const AugmentedVector z = augmented(0.0, 0.0, set_point_velocity_mps);
    StateVector next(states_);
    next.noalias() = step.stuck * z;
    set_states(next);
    state_.position_m = x;  // the handle is held; x stays as it is
    state_.velocity_mps = 0.0;
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
    const auto position = [&](int node) {
        if (node == kGround) return 0.0;
        if (node == kSetPoint) return s.set_point_m;
        return node == 0 ? s.position_m : s.mass_position_m[static_cast<std::size_t>(node - 1)];
    };
    double energy = 0.5 * handle_mass_kg_ * s.velocity_mps * s.velocity_mps;
    for (int i = 0; i < masses_; ++i) {
        const auto k = static_cast<std::size_t>(i);
        energy += 0.5 * mass_kg_[k] * s.mass_velocity_mps[k] * s.mass_velocity_mps[k];
    }
    for (int i = 0; i < link_count_; ++i) {
        const Link& l = links_[static_cast<std::size_t>(i)];
        const double stretch_m = position(l.from) - position(l.to);
        energy += 0.5 * l.stiffness_n_per_m * stretch_m * stretch_m;
    }
    return energy;
}

}  // namespace hapticd::device::sim
