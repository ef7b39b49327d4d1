#include "hapticd/tune/exact_admittance.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "exact_model_detail.hpp"
#include "hapticd/theory/passive_model.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tune {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::RowVectorXd;
using Eigen::VectorXd;
using Kind = AdmittanceEnvironment::Kind;

/// Device + operator, sampled under the shifted hold, and the force sensor's row:
///   s[n+1] = Φ s[n] + Γ_new F_new + Γ_old F_old,   F_h(nT⁻) = C_h s[n] + D_h F_held.
struct SensedPlant {
    MatrixXd phi;
    VectorXd gamma_new;
    VectorXd gamma_old;
    RowVectorXd sensor;      ///< C_h
    double feedthrough = 0;  ///< D_h
    VectorXd translation;    ///< 1 on every position state, or empty when the handle is grounded
};

/// The operator's force on the handle, F_h = C s + D F_d (file comment), and whether the
/// operator grounds the handle.
bool handle_force(const OperatorModel& h, const MatrixXd& a, const VectorXd& b, RowVectorXd& c,
                  double& d) {
    const Index n = a.rows();
    c = RowVectorXd::Zero(n);
    d = 0.0;
    if (h.family == OperatorFamily::two_mass_grasp) {
        c(0) = -h.skin_stiffness_n_per_m;
        c(1) = -h.skin_damping_n_s_per_m;
        c(2) = h.skin_stiffness_n_per_m;
        c(3) = h.skin_damping_n_s_per_m;
        return h.arm_stiffness_n_per_m > 0.0;
    }
    if (h.family == OperatorFamily::hands_off) return false;
    // -m_h a with a = A.row(1) s + B(1) F: the rigid hand's inertia reads the held force.
    c = -h.hand_mass_kg * a.row(1);
    d = -h.hand_mass_kg * b(1);
    c(0) -= h.hand_stiffness_n_per_m;
    c(1) -= h.hand_damping_n_s_per_m;
    for (std::size_t i = 0; i < h.modes.size(); ++i) {
        const OperatorMode& mode = h.modes[i];
        const auto x = static_cast<Index>(2 + 2 * i), v = x + 1;
        c(0) -= mode.stiffness_n_per_m;
        c(1) -= mode.damping_n_s_per_m;
        c(x) += mode.stiffness_n_per_m;
        c(v) += mode.damping_n_s_per_m;
    }
    return h.hand_stiffness_n_per_m > 0.0;
}

SensedPlant sense_plant(const theory::DeviceModel& device, const OperatorModel& h, double period_s,
                        double delay_fraction,
                        const std::optional<theory::ForceSensorFilter>& filter) {
    MatrixXd a;
    VectorXd b;
    detail::operator_plant(device, h, a, b);
    RowVectorXd force_row;
    double force_feedthrough = 0.0;
    const bool grounded = handle_force(h, a, b, force_row, force_feedthrough);
    const Index positions = a.rows();
    if (filter) {
        // Append the filter, driven by the continuous F_h, in a balanced form: the states are
        // x_f1 = F_f/σ and x_f2 = (dF_f/dt)/(ω_a σ), ẋ_f1 = ω_a x_f2,
        // ẋ_f2 = -ω_a x_f1 - 2ζ ω_a x_f2 + ω_a F_h/σ (order 1: ẋ_f1 = -ω_a x_f1 + ω_a F_h/σ).
        // The companion form's ω_a² entries, and a steel grip's k_h ω_a² driving them, would
        // leave the matrix exponential a norm 1e10 times the plant's, and the plant's block
        // inaccurate: σ brings the coupling down to the plant's own scale.
        const double w = 2.0 * std::numbers::pi * filter->cutoff_hz;
        const Index nf = filter->order, n0 = a.rows();
        const double scale = std::max(
            1.0, w * std::max(force_row.cwiseAbs().maxCoeff(), std::abs(force_feedthrough)) /
                     std::max(1.0, a.cwiseAbs().maxCoeff()));
        MatrixXd af = MatrixXd::Zero(nf, nf);
        VectorXd bf = VectorXd::Zero(nf);
        if (nf == 1) {
            af(0, 0) = -w;
            bf(0) = w / scale;
        } else {
            af << 0.0, w, -w, -2.0 * filter->damping_ratio * w;
            bf(1) = w / scale;
        }
        MatrixXd big = MatrixXd::Zero(n0 + nf, n0 + nf);
        big.topLeftCorner(n0, n0) = a;
        big.bottomLeftCorner(nf, n0) = bf * force_row;
        big.bottomRightCorner(nf, nf) = af;
        VectorXd big_b(n0 + nf);
        big_b.head(n0) = b;
        big_b.tail(nf) = bf * force_feedthrough;
        a = big;
        b = big_b;
        force_row = RowVectorXd::Zero(n0 + nf);
        force_row(n0) = scale;
        force_feedthrough = 0.0;
    }
    SensedPlant plant;
    const Index n = a.rows();
    if (delay_fraction == 0.0) {
        auto [phi, gamma] = detail::zoh_sample(a, b, period_s);
        plant.phi = phi;
        plant.gamma_new = gamma;
        plant.gamma_old = VectorXd::Zero(n);
    } else {
        const auto [phi_old, gamma_old] = detail::zoh_sample(a, b, delay_fraction * period_s);
        const auto [phi_new, gamma_new] =
            detail::zoh_sample(a, b, (1.0 - delay_fraction) * period_s);
        plant.phi = phi_new * phi_old;
        plant.gamma_new = gamma_new;
        plant.gamma_old = phi_new * gamma_old;
    }
    plant.sensor = force_row;
    plant.feedthrough = force_feedthrough;
    if (!grounded) {
        // The filter's states are forces: a translation leaves them alone.
        plant.translation = VectorXd::Zero(n);
        for (Index i = 0; i < positions; i += 2) plant.translation(i) = 1.0;
    }
    return plant;
}

/// Where each piece of the closed-loop state sits (-1: not part of this loop).
struct Layout {
    Index plant = 0;  ///< size of s
    Index x_prev = -1, integral = -1, coupling_velocity = -1;
    Index env_velocity = -1, env_spring_force = -1, env_position = -1;
    Index delay_line = -1;  ///< F[n-1] .. F[n-q-1]
    Index lag = 0;          ///< q + 1
    Index size = 0;
};

Layout layout_of(const AdmittanceDesign& d, const AdmittanceEnvironment& env, Index plant_size,
                 const theory::LoopDelay& delay) {
    Layout l;
    l.plant = plant_size;
    Index next = plant_size;
    l.x_prev = next++;
    if (d.loop.integral_gain_n_per_m > 0.0) l.integral = next++;
    if (env.kind != Kind::rigid_wall) {
        if (std::isfinite(d.coupling.mass_kg)) l.coupling_velocity = next++;
        const bool mass = env.mass_kg > 0.0, spring = env.stiffness_n_per_m > 0.0;
        if (env.kind == Kind::mass_spring) {
            if (mass) l.env_velocity = next++;
            if (spring) l.env_position = next++;
        } else if (env.kind == Kind::lossless_mass_spring) {
            if (mass || spring) l.env_velocity = next++;
            if (mass) l.env_spring_force = next++;  // F_m, the mass's force
            if (spring) l.env_position = next++;
        }
    }
    l.lag = delay.whole_periods + 1;
    l.delay_line = next;
    next += l.lag;
    l.size = next;
    return l;
}

RowVectorXd unit_row(Index size, Index at) {
    RowVectorXd r = RowVectorXd::Zero(size);
    if (at >= 0) r(at) = 1.0;
    return r;
}

MatrixXd closed_loop(const AdmittanceDesign& d, const AdmittanceEnvironment& env,
                     const SensedPlant& plant, const theory::LoopDelay& delay, double t,
                     Layout* out_layout) {
    const Layout l = layout_of(d, env, plant.phi.rows(), delay);
    const Index s = l.size;
    const auto e = [&](Index at) { return unit_row(s, at); };
    // The delay line holds F[n-j] at delay_line + j - 1, j = 1..q+1.
    const Index held = l.delay_line + l.lag - 1;  // F[n-q-1]: held at nT⁻
    RowVectorXd x_d = e(0);
    RowVectorXd f_h = RowVectorXd::Zero(s);
    f_h.head(l.plant) = plant.sensor;
    f_h(held) += plant.feedthrough;
    const RowVectorXd v_d = (x_d - e(l.x_prev)) / t;

    // The virtual side: v_com, and the force the environment takes, F_e = z_e v_com + r.
    RowVectorXd v_com = RowVectorXd::Zero(s);
    RowVectorXd r = RowVectorXd::Zero(s);
    double z_e = 0.0;
    const double me = env.mass_kg, ke = env.stiffness_n_per_m, be = env.damping_n_s_per_m;
    if (env.kind == Kind::mass_spring) {
        z_e = me / t + be + ke * t;
        if (l.env_velocity >= 0) r -= (me / t) * e(l.env_velocity);
        if (l.env_position >= 0) r += ke * e(l.env_position);
    } else if (env.kind == Kind::lossless_mass_spring) {
        z_e = 2.0 * me / t + be + ke * t / 2.0;
        if (l.env_spring_force >= 0) r -= e(l.env_spring_force);
        if (l.env_velocity >= 0) r += (ke * t / 2.0 - 2.0 * me / t) * e(l.env_velocity);
        if (l.env_position >= 0) r += ke * e(l.env_position);
    }
    const double inv_bc =
        std::isfinite(d.coupling.damping_n_s_per_m) ? 1.0 / d.coupling.damping_n_s_per_m : 0.0;
    const double per_mass =
        std::isfinite(d.coupling.mass_kg) ? t / d.coupling.mass_kg : 0.0;  // T/m_c
    const double g = inv_bc + per_mass;
    if (env.kind != Kind::rigid_wall) {
        v_com = (g * f_h - g * r + e(l.coupling_velocity)) / (1.0 + g * z_e);
    }
    const RowVectorXd f_e = z_e * v_com + r;

    // (27) on the backward-difference velocity.
    const RowVectorXd error = v_d - v_com;
    const double kp = d.loop.proportional_gain_n_s_per_m, ki = d.loop.integral_gain_n_per_m;
    RowVectorXd integral = RowVectorXd::Zero(s);
    if (l.integral >= 0) integral = e(l.integral) + t * error;
    const RowVectorXd force = kp * error + ki * integral;

    MatrixXd loop = MatrixXd::Zero(s, s);
    loop.topLeftCorner(l.plant, l.plant) = plant.phi;
    // Over the rest of the period the plant sees F[n-q]; over its first φT, F[n-q-1].
    if (delay.whole_periods == 0) {
        loop.topRows(l.plant) += plant.gamma_new * force;
    } else {
        loop.block(0, l.delay_line + delay.whole_periods - 1, l.plant, 1) += plant.gamma_new;
    }
    if (delay.fraction > 0.0) loop.block(0, held, l.plant, 1) += plant.gamma_old;
    loop.row(l.x_prev) = x_d;
    if (l.integral >= 0) loop.row(l.integral) = integral;
    if (l.coupling_velocity >= 0) {
        loop.row(l.coupling_velocity) = e(l.coupling_velocity) + per_mass * (f_h - f_e);
    }
    if (env.kind == Kind::mass_spring) {
        if (l.env_velocity >= 0) loop.row(l.env_velocity) = v_com;
        if (l.env_position >= 0) loop.row(l.env_position) = e(l.env_position) + t * v_com;
    } else if (env.kind == Kind::lossless_mass_spring) {
        const RowVectorXd previous = e(l.env_velocity);
        if (l.env_velocity >= 0) loop.row(l.env_velocity) = v_com;
        if (l.env_spring_force >= 0) {
            loop.row(l.env_spring_force) =
                -e(l.env_spring_force) + (2.0 * me / t) * (v_com - previous);
        }
        if (l.env_position >= 0) {
            loop.row(l.env_position) = e(l.env_position) + (t / 2.0) * (v_com + previous);
        }
    }
    loop.row(l.delay_line) = force;
    for (Index j = 1; j < l.lag; ++j) loop(l.delay_line + j, l.delay_line + j - 1) = 1.0;
    *out_layout = l;
    return loop;
}

ClosedLoopPoles poles_of(MatrixXd loop, const SensedPlant& plant, const Layout& l,
                         double period_s) {
    if (!loop.allFinite()) {
        throw std::invalid_argument(
            "exact admittance model: the sampled loop is not finite (a mass, gain or rate far "
            "outside the physical range)");
    }
    if (plant.translation.size() > 0) {
        // L t = t for t = 1 on every position (the plant's and x_d[n-1]): in the basis
        // (t, e_1, e_2, ...) L is block triangular, and the rest of its spectrum is that of
        // (L - t L_0)[1:, 1:] (row 0 is x_d's).
        VectorXd t = VectorXd::Zero(loop.rows());
        t.head(l.plant) = plant.translation;
        t(l.x_prev) = 1.0;
        const RowVectorXd first = loop.row(0);
        for (Index i = 1; i < loop.rows(); ++i) {
            if (t(i) != 0.0) loop.row(i) -= t(i) * first;
        }
        const Index n = loop.rows() - 1;
        loop = MatrixXd(loop.bottomRightCorner(n, n));
    }
    detail::balance_loop(loop);
    Eigen::EigenSolver<MatrixXd> solver(loop, /*computeEigenvectors=*/false);
    if (solver.info() != Eigen::Success) {
        throw std::runtime_error(
            "exact admittance model: the closed-loop eigenvalue solver did not converge");
    }
    return detail::poles_from_eigenvalues(solver.eigenvalues(), period_s);
}

void check_design(const AdmittanceDesign& d) {
    check_device(d.device);
    check_rate(d.rate_hz);
    check_delay_periods(d.delay_periods);
    check_in_range("proportional gain k_p", d.loop.proportional_gain_n_s_per_m, 0.0, 1e7, "N s/m");
    check_in_range("integral gain k_i", d.loop.integral_gain_n_per_m, 0.0, 1e9, "N/m");
    check_positive_or_infinite("coupling mass m_c", d.coupling.mass_kg, "kg");
    check_positive_or_infinite("coupling damping b_c", d.coupling.damping_n_s_per_m, "N s/m");
    if (d.force_filter) theory::check_force_sensor_filter(*d.force_filter, d.rate_hz);
    if (std::isinf(d.coupling.mass_kg) && std::isinf(d.coupling.damping_n_s_per_m)) {
        throw std::invalid_argument(
            "coupling (32) with m_c = inf and b_c = inf is no coupling (Y_cA = 0): give one");
    }
}

void check_environment(const AdmittanceEnvironment& env) {
    if (env.kind == Kind::free_space || env.kind == Kind::rigid_wall) {
        if (env.mass_kg != 0.0 || env.stiffness_n_per_m != 0.0 || env.damping_n_s_per_m != 0.0) {
            throw std::invalid_argument(
                "free space and the rigid wall take no mass, stiffness "
                "or damping: leave them 0");
        }
        return;
    }
    check_non_negative("environment mass m_e", env.mass_kg, "kg");
    check_non_negative("environment stiffness k_e", env.stiffness_n_per_m, "N/m");
    check_non_negative("environment damping b_e", env.damping_n_s_per_m, "N s/m");
}

}  // namespace

AdmittanceEnvironment AdmittanceEnvironment::free_space() { return {}; }

AdmittanceEnvironment AdmittanceEnvironment::rigid_wall() { return {Kind::rigid_wall}; }

AdmittanceEnvironment AdmittanceEnvironment::mass_spring(double mass_kg, double stiffness_n_per_m,
                                                         double damping_n_s_per_m) {
    return {Kind::mass_spring, mass_kg, stiffness_n_per_m, damping_n_s_per_m};
}

AdmittanceEnvironment AdmittanceEnvironment::lossless_mass_spring(double mass_kg,
                                                                  double stiffness_n_per_m,
                                                                  double damping_n_s_per_m) {
    return {Kind::lossless_mass_spring, mass_kg, stiffness_n_per_m, damping_n_s_per_m};
}

AdmittanceEnvironment AdmittanceEnvironment::from(const EnvironmentModel& environment) {
    switch (environment.kind) {
        case EnvironmentModel::Kind::rigid_wall:
            return rigid_wall();
        case EnvironmentModel::Kind::mass_spring:
            return mass_spring(environment.mass_kg, environment.stiffness_n_per_m,
                               environment.damping_n_s_per_m);
        case EnvironmentModel::Kind::lossless_mass_spring:
            break;
    }
    return lossless_mass_spring(environment.mass_kg, environment.stiffness_n_per_m,
                                environment.damping_n_s_per_m);
}

std::string AdmittanceEnvironment::describe() const {
    std::ostringstream s;
    switch (kind) {
        case Kind::free_space:
            return "free space";
        case Kind::rigid_wall:
            return "rigid wall";
        case Kind::mass_spring:
            if (stiffness_n_per_m == 0.0) {
                s << "virtual mass (m_e = " << mass_kg << " kg, b_e = " << damping_n_s_per_m
                  << " N s/m)";
                return s.str();
            }
            s << "mass-spring";
            break;
        case Kind::lossless_mass_spring:
            s << "lossless mass-spring (trapezoidal)";
            break;
    }
    s << " (m_e = " << mass_kg << " kg, k_e = " << stiffness_n_per_m
      << " N/m, b_e = " << damping_n_s_per_m << " N s/m)";
    return s.str();
}

ClosedLoopPoles admittance_closed_loop_poles(const AdmittanceDesign& design,
                                             const OperatorModel& human,
                                             const AdmittanceEnvironment& environment) {
    check_design(design);
    detail::validate_operator(human);
    check_environment(environment);
    const double period_s = 1.0 / design.rate_hz;
    const theory::LoopDelay delay = theory::split_delay(design.delay_periods);
    const SensedPlant plant =
        sense_plant(design.device, human, period_s, delay.fraction, design.force_filter);
    Layout layout;
    const MatrixXd loop = closed_loop(design, environment, plant, delay, period_s, &layout);
    return poles_of(loop, plant, layout, period_s);
}

std::vector<AdmittanceEnvironment> default_admittance_environment_sweep(
    const theory::DeviceModel& device) {
    check_device(device);
    std::vector<AdmittanceEnvironment> sweep{AdmittanceEnvironment::free_space(),
                                             AdmittanceEnvironment::rigid_wall()};
    for (double mass_ratio : detail::log_grid(0.01, 100.0, 5)) {
        for (double be : {0.0, 1.0, 30.0}) {
            sweep.push_back(
                AdmittanceEnvironment::mass_spring(mass_ratio * device.mass_kg, 0.0, be));
        }
        for (double ke : detail::log_grid(1.0, 1e6, 7)) {
            for (double be : {0.0, 30.0}) {
                sweep.push_back(
                    AdmittanceEnvironment::mass_spring(mass_ratio * device.mass_kg, ke, be));
            }
        }
    }
    return sweep;
}

AdmittanceExactCheck check_exact_admittance(
    const AdmittanceDesign& design, const std::vector<OperatorModel>& operators,
    const std::vector<AdmittanceEnvironment>& environments) {
    check_design(design);
    for (const OperatorModel& h : operators) detail::validate_operator(h);
    for (const AdmittanceEnvironment& e : environments) check_environment(e);
    const double period_s = 1.0 / design.rate_hz;
    const theory::LoopDelay delay = theory::split_delay(design.delay_periods);
    AdmittanceExactCheck check;
    check.worst_spectral_radius = -1.0;
    check.delay_periods = design.delay_periods;
    for (const OperatorModel& h : operators) {
        const SensedPlant plant =
            sense_plant(design.device, h, period_s, delay.fraction, design.force_filter);
        for (const AdmittanceEnvironment& env : environments) {
            Layout layout;
            const MatrixXd loop = closed_loop(design, env, plant, delay, period_s, &layout);
            const ClosedLoopPoles poles = poles_of(loop, plant, layout, period_s);
            ++check.cases_checked;
            if (poles.spectral_radius > check.worst_spectral_radius) {
                check.worst_spectral_radius = poles.spectral_radius;
                check.worst_frequency_hz = poles.dominant_frequency_hz;
                check.worst_operator = h;
                check.worst_environment = env;
            }
        }
    }
    if (check.cases_checked == 0) {
        throw std::invalid_argument(
            "check_exact_admittance: the operator or environment sweep is empty");
    }
    check.worst_margin = 1.0 - check.worst_spectral_radius;
    check.stable = check.worst_margin >= -kMarginalTolerance;
    return check;
}

AdmittanceExactCheck check_exact_admittance(const AdmittanceDesign& design) {
    check_design(design);
    return check_exact_admittance(design, default_operator_sweep(design.device, design.rate_hz),
                                  default_admittance_environment_sweep(design.device));
}

}  // namespace hapticd::tune
