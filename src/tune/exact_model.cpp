#include "hapticd/tune/exact_model.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <future>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <unsupported/Eigen/MatrixFunctions>

#include "exact_model_detail.hpp"
#include "hapticd/theory/passive_model.hpp"
#include "hapticd/tune/input_checks.hpp"
#include "hapticd/tune/operator_synthesis.hpp"

namespace hapticd::tune {
namespace {

/// Fewer cases than this are checked on the calling thread alone (a thread costs about 50 us,
/// a case 5-40 us).
constexpr std::size_t kCasesWorthAThread = 2000;

using detail::log_grid;

using Eigen::MatrixXd;
using Eigen::RowVectorXd;
using Eigen::VectorXd;
using theory::DeviceModel;
using theory::SpringDamperCoupling;

/// Device + operator sampled with the ZOH shifted by the loop delay's fraction φ of a period:
///   s[n+1] = Φ s[n] + Γ_new F_new + Γ_old F_old,
/// F_old acting for the first φT of the period and F_new for the rest (Γ_old = 0 at φ = 0).
/// The encoder reads x_d = s(0).
struct SampledPlant {
    MatrixXd phi;
    VectorXd gamma_new;
    VectorXd gamma_old;
};

/// Continuous state space ds/dt = A s + B F_d of the device (10) with the operator attached.
/// States: [x_d, v_d], then [x_i, v_i] for every mass hung off the handle (the two-mass
/// grasp's hand, the multi-mode grasp's absorbers).
void continuous_plant(const DeviceModel& device, const OperatorModel& human, MatrixXd& a,
                      VectorXd& b) {
    const double m = device.mass_kg;
    const double c = device.damping_n_s_per_m;
    if (human.family == OperatorFamily::two_mass_grasp) {
        const double ks = human.skin_stiffness_n_per_m, bs = human.skin_damping_n_s_per_m;
        const double mh = human.hand_mass_kg;
        const double ka = human.arm_stiffness_n_per_m, ba = human.arm_damping_n_s_per_m;
        a.setZero(4, 4);
        b.setZero(4);
        // m dv_d/dt = -b v_d - k_s (x_d - x_h) - b_s (v_d - v_h) - F_d       (10) + skin
        a(0, 1) = 1.0;
        a(1, 0) = -ks / m;
        a(1, 1) = -(c + bs) / m;
        a(1, 2) = ks / m;
        a(1, 3) = bs / m;
        // m_h dv_h/dt = k_s (x_d - x_h) + b_s (v_d - v_h) - k_a x_h - b_a v_h
        a(2, 3) = 1.0;
        a(3, 0) = ks / mh;
        a(3, 1) = bs / mh;
        a(3, 2) = -(ks + ka) / mh;
        a(3, 3) = -(bs + ba) / mh;
        b(1) = -1.0 / m;
        return;
    }
    // The rigid part adds a mass, a damper and a spring to ground to (10):
    // (m + m_h) dv/dt + (b + b_h) v + k_h x = -F_d - Σ_i [k_i (x - x_i) + b_i (v - v_i)].
    const double total_mass = m + human.hand_mass_kg;
    const auto n = static_cast<Eigen::Index>(2 + 2 * human.modes.size());
    a.setZero(n, n);
    b.setZero(n);
    a(0, 1) = 1.0;
    a(1, 0) = -human.hand_stiffness_n_per_m / total_mass;
    a(1, 1) = -(c + human.hand_damping_n_s_per_m) / total_mass;
    b(1) = -1.0 / total_mass;
    for (std::size_t i = 0; i < human.modes.size(); ++i) {
        const OperatorMode& mode = human.modes[i];
        const auto x = static_cast<Eigen::Index>(2 + 2 * i), v = x + 1;
        const double k = mode.stiffness_n_per_m, d = mode.damping_n_s_per_m;
        a(1, 0) -= k / total_mass;
        a(1, 1) -= d / total_mass;
        a(1, x) += k / total_mass;
        a(1, v) += d / total_mass;
        // m_i dv_i/dt = k_i (x - x_i) + b_i (v - v_i)
        a(x, v) = 1.0;
        a(v, 0) = k / mode.mass_kg;
        a(v, 1) = d / mode.mass_kg;
        a(v, x) = -k / mode.mass_kg;
        a(v, v) = -d / mode.mass_kg;
    }
}

/// e^{A t} and ∫_0^t e^{Aτ} dτ B, both read off exp([[A, B], [0, 0]] t).
std::pair<MatrixXd, VectorXd> sample_over(const MatrixXd& a, const VectorXd& b, double t) {
    const Eigen::Index n = a.rows();
    MatrixXd augmented = MatrixXd::Zero(n + 1, n + 1);
    augmented.topLeftCorner(n, n) = a * t;
    augmented.topRightCorner(n, 1) = b * t;
    const MatrixXd e = augmented.exp();
    return {e.topLeftCorner(n, n), e.topRightCorner(n, 1)};
}

SampledPlant sample_plant(const DeviceModel& device, const OperatorModel& human, double period_s,
                          double delay_fraction) {
    MatrixXd a;
    VectorXd b;
    continuous_plant(device, human, a, b);
    if (delay_fraction == 0.0) {
        auto [phi, gamma] = sample_over(a, b, period_s);
        return {phi, gamma, VectorXd::Zero(gamma.size())};
    }
    // [0, φT): the previous command; [φT, T): the new one.
    const auto [phi_old, gamma_old] = sample_over(a, b, delay_fraction * period_s);
    const auto [phi_new, gamma_new] = sample_over(a, b, (1.0 - delay_fraction) * period_s);
    return {phi_new * phi_old, gamma_new, phi_new * gamma_old};
}

/// The controller of one tick as linear maps of w = (x_d[n], memory[n]):
///   F[n] = force · w,   memory[n+1] = next · w.
struct Controller {
    RowVectorXd force;
    MatrixXd next;
};

/// An environment as a difference equation from the tool position to the coupling force:
///   F[n] + a1 F[n-1] = c0 x_e[n] + c1 x_e[n-1] + c2 x_e[n-2].
struct EnvironmentRecurrence {
    double a1 = 0.0;
    double c0 = 0.0, c1 = 0.0, c2 = 0.0;
};

EnvironmentRecurrence recurrence_of(const EnvironmentModel& env, double t) {
    const double me = env.mass_kg, ke = env.stiffness_n_per_m, be = env.damping_n_s_per_m;
    if (env.kind == EnvironmentModel::Kind::mass_spring) {
        // Implicit Euler: m_e (x_e[n] - 2x_e[n-1] + x_e[n-2])/T² = F - k_e x_e[n] - b_e v_e[n].
        return {0.0, me / (t * t) + be / t + ke, -2.0 * me / (t * t) - be / t, me / (t * t)};
    }
    // Trapezoidal: (1 + z⁻¹) F = [m_e (2/T²)(1 - z⁻¹)² + (b_e/T)(1 - z⁻²) + (k_e/2)(1 + z⁻¹)²] x_e.
    return {1.0, 2.0 * me / (t * t) + be / t + ke / 2.0, -4.0 * me / (t * t) + ke,
            2.0 * me / (t * t) - be / t + ke / 2.0};
}

Controller make_controller(const SpringDamperCoupling& coupling, const EnvironmentModel& env,
                           double period_s) {
    const double kc = coupling.stiffness_n_per_m;
    const double bc = coupling.damping_n_s_per_m;
    const double t = period_s;
    // The velocity filter (velocity_filter.hpp): u[n] = a u[n-1] + (1 - a)(v_d - v_e), and the
    // damper's force b_c u[n] = (1 - a) b_c (v_d - v_e) + a b_c u[n-1]. Without it (a = 0) the
    // loop has no u state and bw = b_c: the unfiltered controller, to the bit.
    const double a = theory::velocity_filter_pole(coupling.velocity_filter_hz, t);
    const bool filtered = a > 0.0;
    const double bw = (1.0 - a) * bc;  // the damper's weight on this tick's v_d - v_e
    Controller ctl;
    if (env.kind == EnvironmentModel::Kind::rigid_wall) {
        // w = (x_d[n], x_d[n-1]); (16) with x_e = v_e = 0: F = k_c x_d + b_c (x_d[n] - x_d[n-1])/T.
        if (!filtered) {
            ctl.force.resize(2);
            ctl.force << kc + bc / t, -bc / t;
            ctl.next.resize(1, 2);
            ctl.next << 1.0, 0.0;
            return ctl;
        }
        // w = (x_d[n], x_d[n-1], u[n-1]): F = k_c x_d + b_c u[n],
        // u[n] = a u[n-1] + (1 - a)(x_d[n] - x_d[n-1])/T.
        ctl.force.resize(3);
        ctl.force << kc + bw / t, -bw / t, a * bc;
        ctl.next.resize(2, 3);
        ctl.next << 1.0, 0.0, 0.0,  //
            (1.0 - a) / t, -(1.0 - a) / t, a;
        return ctl;
    }
    // w = (x_d[n], x_d[n-1], x_e[n-1], x_e[n-2]), then F[n-1] when the environment remembers
    // its force (a1 != 0), then u[n-1] with the velocity filter. The coupling (16),
    //   F = P - g x_e[n],  g = k_c + b_w/T,  b_w = (1 - a) b_c,
    //   P = k_c x_d + b_w (x_d - x_d[n-1])/T + (b_w/T) x_e[n-1] + a b_c u[n-1],
    // solved together with the environment's recurrence for x_e[n] and F[n].
    const EnvironmentRecurrence r = recurrence_of(env, t);
    const Eigen::Index force_memory = r.a1 != 0.0 ? 1 : 0;
    const Eigen::Index w = 4 + force_memory + (filtered ? 1 : 0);
    const Eigen::Index u_index = 4 + force_memory;  // only when filtered
    RowVectorXd p = RowVectorXd::Zero(w), rhs = RowVectorXd::Zero(w);
    p.head(3) << kc + bw / t, -bw / t, bw / t;
    if (filtered) p(u_index) = a * bc;
    rhs.segment(2, 2) << r.c1, r.c2;  // c1 x_e[n-1] + c2 x_e[n-2] - a1 F[n-1]
    if (force_memory != 0) rhs(4) = -r.a1;
    const double g = kc + bw / t;
    const RowVectorXd x_e = (p - rhs) / (g + r.c0);
    const RowVectorXd f = p - g * x_e;
    ctl.force = f;
    RowVectorXd x_d = RowVectorXd::Zero(w), x_e1 = RowVectorXd::Zero(w);
    x_d(0) = 1.0;
    x_e1(2) = 1.0;
    ctl.next.resize(w - 1, w);
    ctl.next.row(0) = x_d;
    ctl.next.row(1) = x_e;
    ctl.next.row(2) = x_e1;
    if (force_memory != 0) ctl.next.row(3) = f;
    if (filtered) {
        // u[n] = a u[n-1] + ((1 - a)/T)(x_d[n] - x_d[n-1] - x_e[n] + x_e[n-1]).
        RowVectorXd u = -((1.0 - a) / t) * x_e;
        u(0) += (1.0 - a) / t;
        u(1) -= (1.0 - a) / t;
        u(2) += (1.0 - a) / t;
        u(u_index) += a;
        ctl.next.row(w - 2) = u;
    }
    return ctl;
}

/// Closed-loop state (s[n], memory[n], F[n-1], ..., F[n-L]) one tick on, with x_d[n] = s(0)
/// and the delay line as long as the delay needs: L = q, or q + 1 when φ > 0.
template <typename Loop>
Loop closed_loop_matrix(const SampledPlant& plant, const Controller& ctl,
                        const theory::LoopDelay& delay) {
    const Eigen::Index n = plant.phi.rows();
    const Eigen::Index q = ctl.next.rows();
    const Eigen::Index lag = delay.whole_periods + (delay.fraction > 0.0 ? 1 : 0);
    const Eigen::Index size = n + q + lag;
    // F[n] as a row over the whole state.
    RowVectorXd force = RowVectorXd::Zero(size);
    force(0) = ctl.force(0);
    force.segment(n, q) = ctl.force.tail(q);
    Loop loop = Loop::Zero(size, size);
    loop.topLeftCorner(n, n) = plant.phi;
    // The force acting over the rest of the period: F[n-q]; over its first φT: F[n-q-1].
    if (delay.whole_periods == 0) {
        loop.topRows(n) += plant.gamma_new * force;
    } else {
        loop.block(0, n + q + delay.whole_periods - 1, n, 1) += plant.gamma_new;
    }
    if (delay.fraction > 0.0) loop.block(0, n + q + lag - 1, n, 1) += plant.gamma_old;
    loop.block(n, 0, q, 1) = ctl.next.col(0);
    loop.block(n, n, q, q) = ctl.next.rightCols(q);
    if (lag > 0) {
        loop.row(n + q) = force;
        for (Eigen::Index i = 1; i < lag; ++i) loop(n + q + i, n + q + i - 1) = 1.0;
    }
    return loop;
}

/// Parlett-Reinsch balancing: a diagonal similarity, by powers of two, that evens the row
/// and column norms. The loop matrix mixes metres, metres per second and newtons, and
/// Eigen's real Schur iteration can fail to converge on it unbalanced (a two-mass grasp
/// with a 0.1 g hand on a 1e6 N/m arm did).
template <typename Loop>
void balance(Loop& a) {
    const Eigen::Index n = a.rows();
    for (bool changed = true; changed;) {
        changed = false;
        for (Eigen::Index i = 0; i < n; ++i) {
            const double column = a.col(i).cwiseAbs().sum() - std::abs(a(i, i));
            const double row = a.row(i).cwiseAbs().sum() - std::abs(a(i, i));
            if (column == 0.0 || row == 0.0) continue;
            double c = column, r = row, f = 1.0;
            while (c < r / 2.0) c *= 2.0, r /= 2.0, f *= 2.0;
            while (c >= r * 2.0) c /= 2.0, r *= 2.0, f /= 2.0;
            if (c + r < 0.95 * (column + row)) {
                a.row(i) /= f;
                a.col(i) *= f;
                changed = true;
            }
        }
    }
}

template <typename Loop>
ClosedLoopPoles poles_of(Loop loop, double period_s) {
    if (!loop.allFinite()) {
        throw std::invalid_argument(
            "exact model: the sampled loop is not finite (a mass, stiffness or rate far outside "
            "the physical range)");
    }
    balance(loop);
    Eigen::EigenSolver<Loop> solver(loop, /*computeEigenvectors=*/false);
    if (solver.info() != Eigen::Success) {
        throw std::runtime_error("exact model: the closed-loop eigenvalue solver did not converge");
    }
    return detail::poles_from_eigenvalues(solver.eigenvalues(), period_s);
}

// Loops of up to 12 states (every default case) stay on the stack: the sweep's 67,522
// eigenvalue problems are 30% faster without a heap allocation each.
constexpr int kSmallLoop = 12;
using SmallLoop = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kSmallLoop, kSmallLoop>;

Eigen::Index loop_size(const SampledPlant& plant, const Controller& ctl,
                       const theory::LoopDelay& delay) {
    return plant.phi.rows() + ctl.next.rows() + delay.whole_periods +
           (delay.fraction > 0.0 ? 1 : 0);
}

ClosedLoopPoles loop_poles(const SampledPlant& plant, const Controller& ctl,
                           const theory::LoopDelay& delay, double period_s) {
    if (loop_size(plant, ctl, delay) <= kSmallLoop) {
        return poles_of(closed_loop_matrix<SmallLoop>(plant, ctl, delay), period_s);
    }
    return poles_of(closed_loop_matrix<MatrixXd>(plant, ctl, delay), period_s);
}

void require_unused(const char* name, double value, OperatorFamily family) {
    if (value != 0.0) {
        std::ostringstream message;
        message << name << " = " << value << " is not used by the '" << to_string(family)
                << "' operator: leave it 0";
        throw std::invalid_argument(message.str());
    }
}

void check_operator(const OperatorModel& h) {
    const OperatorFamily f = h.family;
    const bool hand = f != OperatorFamily::hands_off;
    const bool multi = f == OperatorFamily::multi_mode;
    const bool grounded_hand =
        f == OperatorFamily::heavy_hand || f == OperatorFamily::stiff_grasp || multi;
    const bool two_mass = f == OperatorFamily::two_mass_grasp;
    if (two_mass) {
        check_positive("operator hand mass m_h", h.hand_mass_kg, "kg");
    } else if (hand) {
        check_non_negative("operator hand mass m_h", h.hand_mass_kg, "kg");
    } else {
        require_unused("hand_mass_kg", h.hand_mass_kg, f);
    }
    if (grounded_hand) {
        check_non_negative("operator hand damping b_h", h.hand_damping_n_s_per_m, "N s/m");
    } else {
        require_unused("hand_damping_n_s_per_m", h.hand_damping_n_s_per_m, f);
    }
    if (f == OperatorFamily::stiff_grasp || multi) {
        check_non_negative("operator hand stiffness k_h", h.hand_stiffness_n_per_m, "N/m");
    } else {
        require_unused("hand_stiffness_n_per_m", h.hand_stiffness_n_per_m, f);
    }
    if (two_mass) {
        check_non_negative("operator skin stiffness k_s", h.skin_stiffness_n_per_m, "N/m");
        check_non_negative("operator skin damping b_s", h.skin_damping_n_s_per_m, "N s/m");
        check_non_negative("operator arm stiffness k_a", h.arm_stiffness_n_per_m, "N/m");
        check_non_negative("operator arm damping b_a", h.arm_damping_n_s_per_m, "N s/m");
    } else {
        require_unused("skin_stiffness_n_per_m", h.skin_stiffness_n_per_m, f);
        require_unused("skin_damping_n_s_per_m", h.skin_damping_n_s_per_m, f);
        require_unused("arm_stiffness_n_per_m", h.arm_stiffness_n_per_m, f);
        require_unused("arm_damping_n_s_per_m", h.arm_damping_n_s_per_m, f);
    }
    if (multi) {
        if (h.modes.empty()) throw std::invalid_argument("multi-mode grasp: no modes");
        for (const OperatorMode& mode : h.modes) {
            check_positive("operator mode mass m_i", mode.mass_kg, "kg");
            check_positive("operator mode stiffness k_i", mode.stiffness_n_per_m, "N/m");
            check_non_negative("operator mode damping b_i", mode.damping_n_s_per_m, "N s/m");
        }
    } else if (!h.modes.empty()) {
        throw std::invalid_argument("modes are used only by the 'multi-mode grasp' operator");
    }
}

void check_environment(const EnvironmentModel& e) {
    if (e.kind == EnvironmentModel::Kind::rigid_wall) return;
    check_non_negative("environment mass m_e", e.mass_kg, "kg");
    // A scene's free virtual mass or damper has k_e = 0: the loop keeps a free z = 1.
    check_non_negative("environment stiffness k_e", e.stiffness_n_per_m, "N/m");
    check_non_negative("environment damping b_e", e.damping_n_s_per_m, "N s/m");
}

void check_loop(const DeviceModel& device, const SpringDamperCoupling& coupling, double rate_hz,
                double delay_periods) {
    check_device(device);
    check_rate(rate_hz);
    check_coupling_gains(coupling);
    check_velocity_filter(coupling.velocity_filter_hz, rate_hz);
    check_delay_periods(delay_periods);
}

constexpr double kTunedGripFractionsOfNyquist[] = {0.125, 0.25, 0.5, 0.75, 0.9, 1.0};

}  // namespace

ClosedLoopPoles closed_loop_poles(const DeviceModel& device, const SpringDamperCoupling& coupling,
                                  double rate_hz, const OperatorModel& human,
                                  const EnvironmentModel& environment, double delay_periods) {
    check_loop(device, coupling, rate_hz, delay_periods);
    check_operator(human);
    check_environment(environment);
    const double period_s = 1.0 / rate_hz;
    const theory::LoopDelay delay = theory::split_delay(delay_periods);
    const SampledPlant plant = sample_plant(device, human, period_s, delay.fraction);
    return loop_poles(plant, make_controller(coupling, environment, period_s), delay, period_s);
}

std::vector<OperatorModel> default_operator_sweep(const DeviceModel& device, double rate_hz) {
    check_device(device);
    check_rate(rate_hz);
    std::vector<OperatorModel> sweep{OperatorModel::hands_off()};
    for (double mh : log_grid(0.1, 10.0, 9)) {
        for (double bh : {0.0, 0.3, 1.0, 3.0, 10.0}) {
            sweep.push_back(OperatorModel::heavy_hand(mh, bh));
        }
    }
    for (double mh : log_grid(0.1, 10.0, 5)) {
        for (double kh : log_grid(10.0, 1e4, 7)) {
            for (double bh : {0.0, 1.0, 10.0}) {
                sweep.push_back(OperatorModel::stiff_grasp(mh, kh, bh));
            }
        }
    }
    // Steel grips tuned so that the handle (mass m on k_h) resonates at a fraction r of the
    // Nyquist frequency: k_h = m (r π rate)².
    for (double r : kTunedGripFractionsOfNyquist) {
        const double omega_rad_per_s = r * std::numbers::pi * rate_hz;
        sweep.push_back(OperatorModel::stiff_grasp(
            0.0, device.mass_kg * omega_rad_per_s * omega_rad_per_s, 0.0));
    }
    for (double ks : log_grid(1e2, 1e5, 4)) {
        for (double bs : {0.0, 1.0, 10.0}) {
            for (double mh : log_grid(0.1, 10.0, 5)) {
                for (double ka : {0.0, 1e2, 1e3, 1e4}) {
                    for (double ba : {0.0, 10.0}) {
                        sweep.push_back(OperatorModel::two_mass_grasp(ks, bs, mh, ka, ba));
                    }
                }
            }
        }
    }
    return sweep;
}

std::vector<EnvironmentModel> default_environment_sweep(const DeviceModel& device) {
    check_device(device);
    std::vector<EnvironmentModel> sweep{EnvironmentModel::rigid_wall()};
    for (double mass_ratio : log_grid(0.01, 100.0, 5)) {
        for (double ke : log_grid(1.0, 1e6, 7)) {
            for (double be : {0.0, 1.0, 30.0}) {
                sweep.push_back(EnvironmentModel::mass_spring(mass_ratio * device.mass_kg, ke, be));
            }
        }
    }
    return sweep;
}

void merge(ExactCheck& into, const ExactCheck& other) {
    const int cases = into.cases_checked + other.cases_checked;
    if (other.worst_spectral_radius > into.worst_spectral_radius) into = other;
    into.cases_checked = cases;
}

namespace {

/// A case of a sweep over the tolerance: its |z|, its operator and environment (indices).
struct Excess {
    double spectral_radius;
    std::size_t op, env;
};

/// Whether every case over the tolerance is the rounding of eigenvalues on |z| = 1, not the
/// design: each grows by less than kDecisiveGrowthPerTick, and the same case with the
/// coupling's gains 1 % lower grows by the same to within 0.1 % of its excess. An eigenvalue
/// the gains do not move belongs to the device, the operator or the environment with the
/// coupling's influence removed, all passive, so it cannot lie outside the unit circle: its
/// excess is the error of a near-multiple eigenvalue (lossless modes folded onto one alias
/// by the sampling come out as a cluster whose moduli scatter on both sides of 1 by about
/// the square root of the rounding, 1e-8 and more at high rates; docs/RESULTS.md, "The
/// tuner's effort"). At most kMaxExcessCases cases are held against the gains; more, and the
/// verdict stays unstable.
bool all_gain_invariant(const DeviceModel& device, const SpringDamperCoupling& coupling,
                        const theory::LoopDelay& delay, double period_s,
                        const std::vector<OperatorModel>& operators,
                        const std::vector<EnvironmentModel>& environments,
                        std::vector<Excess>& excess) {
    constexpr std::size_t kMaxExcessCases = 256;
    constexpr double kLowerGains = 0.99;
    constexpr double kSameExcess = 1e-3;
    if (excess.empty() || excess.size() > kMaxExcessCases) return false;
    SpringDamperCoupling lower = coupling;
    lower.stiffness_n_per_m *= kLowerGains;
    lower.damping_n_s_per_m *= kLowerGains;
    for (const Excess& e : excess) {
        if (e.spectral_radius > 1.0 + kDecisiveGrowthPerTick) return false;
        const SampledPlant plant = sample_plant(device, operators[e.op], period_s, delay.fraction);
        const ClosedLoopPoles moved = loop_poles(
            plant, make_controller(lower, environments[e.env], period_s), delay, period_s);
        const double grows = e.spectral_radius - 1.0;
        if (std::abs(moved.spectral_radius - e.spectral_radius) > kSameExcess * grows) {
            return false;
        }
    }
    return true;
}

}  // namespace

ExactCheck check_exact(const DeviceModel& device, const SpringDamperCoupling& coupling,
                       double rate_hz, const std::vector<OperatorModel>& operators,
                       const std::vector<EnvironmentModel>& environments, double delay_periods) {
    check_loop(device, coupling, rate_hz, delay_periods);
    for (const OperatorModel& h : operators) check_operator(h);
    for (const EnvironmentModel& e : environments) check_environment(e);
    const double period_s = 1.0 / rate_hz;
    const theory::LoopDelay delay = theory::split_delay(delay_periods);

    std::vector<Controller> controllers;
    controllers.reserve(environments.size());
    for (const EnvironmentModel& e : environments) {
        controllers.push_back(make_controller(coupling, e, period_s));
    }
    // The operators in contiguous shares, one per core (two on the lab PCs): each share keeps
    // its own worst, and the shares are merged in order with the same strict comparison, so
    // the verdict and the worst case are those of one pass in order.
    // The cases over the tolerance, kept aside to be held against the gains
    // (all_gain_invariant).
    const auto share = [&](std::size_t begin, std::size_t end, std::vector<Excess>& over) {
        ExactCheck part;
        part.worst_spectral_radius = -1.0;
        for (std::size_t j = begin; j < end; ++j) {
            const OperatorModel& h = operators[j];
            // once per operator
            const SampledPlant plant = sample_plant(device, h, period_s, delay.fraction);
            for (std::size_t i = 0; i < environments.size(); ++i) {
                const ClosedLoopPoles poles = loop_poles(plant, controllers[i], delay, period_s);
                ++part.cases_checked;
                if (poles.spectral_radius > 1.0 + kMarginalTolerance) {
                    over.push_back({poles.spectral_radius, j, i});
                }
                if (poles.spectral_radius > part.worst_spectral_radius) {
                    part.worst_spectral_radius = poles.spectral_radius;
                    part.worst_frequency_hz = poles.dominant_frequency_hz;
                    part.worst_operator = h;
                    part.worst_environment = environments[i];
                }
            }
        }
        return part;
    };
    const std::size_t shares =
        operators.size() * environments.size() < kCasesWorthAThread
            ? 1
            : std::clamp<std::size_t>(std::thread::hardware_concurrency(), 1,
                                      std::min<std::size_t>(2, operators.size()));
    std::vector<std::vector<Excess>> over(shares);
    std::vector<std::future<ExactCheck>> parts;
    for (std::size_t k = 1; k < shares; ++k) {
        parts.push_back(std::async(std::launch::async, share, k * operators.size() / shares,
                                   (k + 1) * operators.size() / shares, std::ref(over[k])));
    }
    ExactCheck check = share(0, operators.size() / shares, over[0]);
    for (std::future<ExactCheck>& part : parts) merge(check, part.get());
    check.delay_periods = delay_periods;
    if (check.cases_checked == 0) {
        throw std::invalid_argument("check_exact: the operator or environment sweep is empty");
    }
    check.worst_margin = 1.0 - check.worst_spectral_radius;
    check.stable = check.worst_margin >= -kMarginalTolerance;
    if (!check.stable) {
        std::vector<Excess> excess;
        for (const std::vector<Excess>& found : over) {
            excess.insert(excess.end(), found.begin(), found.end());
        }
        check.stable =
            all_gain_invariant(device, coupling, delay, period_s, operators, environments, excess);
    }
    return check;
}

ExactCheck check_exact(const DeviceModel& device, const SpringDamperCoupling& coupling,
                       double rate_hz, double delay_periods, SearchFor search) {
    check_loop(device, coupling, rate_hz, delay_periods);
    // The adversaries built for this design: the default operators meet the worst lossless
    // environments too, and the alias-tuned operators meet the rigid wall and those.
    const Adversaries adversaries =
        synthesize_adversaries(device, coupling, rate_hz, delay_periods);
    std::vector<EnvironmentModel> tuned_environments{EnvironmentModel::rigid_wall()};
    tuned_environments.insert(tuned_environments.end(), adversaries.environments.begin(),
                              adversaries.environments.end());
    ExactCheck tuned = check_exact(device, coupling, rate_hz, adversaries.operators,
                                   tuned_environments, delay_periods);
    if (search == SearchFor::witness && decisive(tuned)) return tuned;
    std::vector<EnvironmentModel> environments = default_environment_sweep(device);
    environments.insert(environments.end(), adversaries.environments.begin(),
                        adversaries.environments.end());
    ExactCheck check =
        check_exact(device, coupling, rate_hz, default_operator_sweep(device, rate_hz),
                    environments, delay_periods);
    merge(check, tuned);
    return check;
}

}  // namespace hapticd::tune

// ---- shared with the exact admittance loop (exact_model_detail.hpp) ------------------------

namespace hapticd::tune::detail {

void operator_plant(const DeviceModel& device, const OperatorModel& human, Eigen::MatrixXd& a,
                    Eigen::VectorXd& b) {
    continuous_plant(device, human, a, b);
}

std::pair<Eigen::MatrixXd, Eigen::VectorXd> zoh_sample(const Eigen::MatrixXd& a,
                                                       const Eigen::VectorXd& b, double t) {
    return sample_over(a, b, t);
}

void validate_operator(const OperatorModel& human) { check_operator(human); }

void balance_loop(Eigen::MatrixXd& loop) { balance(loop); }

ClosedLoopPoles poles_from_eigenvalues(const Eigen::Ref<const Eigen::VectorXcd>& eigenvalues,
                                       double period_s) {
    ClosedLoopPoles poles;
    poles.eigenvalues.reserve(static_cast<std::size_t>(eigenvalues.size()));
    double dominant_angle = 0.0;
    for (Eigen::Index i = 0; i < eigenvalues.size(); ++i) {
        const theory::Complex lambda = eigenvalues(i);
        poles.eigenvalues.push_back(lambda);
        if (std::abs(lambda) > poles.spectral_radius) {
            poles.spectral_radius = std::abs(lambda);
            dominant_angle = std::abs(std::arg(lambda));
        }
    }
    poles.dominant_frequency_hz = dominant_angle / (2.0 * std::numbers::pi * period_s);
    return poles;
}

std::vector<double> log_grid(double lo, double hi, int n) {
    std::vector<double> grid;
    grid.reserve(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) grid.push_back(lo * std::pow(hi / lo, double(i) / (n - 1)));
    return grid;
}

}  // namespace hapticd::tune::detail
