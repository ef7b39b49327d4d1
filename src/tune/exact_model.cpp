#include "hapticd/tune/exact_model.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <unsupported/Eigen/MatrixFunctions>

#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tune {
namespace {

using theory::DeviceModel;
using theory::SpringDamperCoupling;

// Fixed upper bounds keep every matrix on the stack: the plant has at most 4 states
// (two-mass grasp), the controller at most 3 (x_d[n-1], x_e[n-1], v_e[n-1]).
constexpr int kMaxPlant = 4;
constexpr int kMaxMemory = 3;
constexpr int kMaxLoop = kMaxPlant + kMaxMemory;
using PlantMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxPlant + 1, kMaxPlant + 1>;
using PlantVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxPlant + 1, 1>;
using LoopMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxLoop, kMaxLoop>;
using MemoryMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxMemory, kMaxMemory + 1>;
using ControlRow = Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMaxMemory + 1>;

/// Device + operator sampled with an exact ZOH on F_d: s[n+1] = Φ s[n] + Γ F[n], and the
/// encoder reads x_d = s(0).
struct SampledPlant {
    PlantMatrix phi;
    PlantVector gamma;
};

/// Continuous state space ds/dt = A s + B F_d of the device (10) with the operator attached.
/// States: [x_d, v_d] or, for the two-mass grasp, [x_d, v_d, x_h, v_h].
void continuous_plant(const DeviceModel& device, const OperatorModel& human, PlantMatrix& a,
                      PlantVector& b) {
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
    // The other families add a rigid mass, a damper and a spring to ground to (10):
    // (m + m_h) dv/dt + (b + b_h) v + k_h x = -F_d.
    const double total_mass = m + human.hand_mass_kg;
    a.setZero(2, 2);
    b.setZero(2);
    a(0, 1) = 1.0;
    a(1, 0) = -human.hand_stiffness_n_per_m / total_mass;
    a(1, 1) = -(c + human.hand_damping_n_s_per_m) / total_mass;
    b(1) = -1.0 / total_mass;
}

/// Φ = e^{AT}, Γ = ∫_0^T e^{Aτ} dτ B, both read off exp([[A, B], [0, 0]] T).
SampledPlant sample_plant(const DeviceModel& device, const OperatorModel& human, double period_s) {
    PlantMatrix a;
    PlantVector b;
    continuous_plant(device, human, a, b);
    const Eigen::Index n = a.rows();
    PlantMatrix augmented = PlantMatrix::Zero(n + 1, n + 1);
    augmented.topLeftCorner(n, n) = a * period_s;
    augmented.topRightCorner(n, 1) = b * period_s;
    const PlantMatrix e = augmented.exp();
    return {e.topLeftCorner(n, n), e.topRightCorner(n, 1)};
}

/// The controller of one tick as linear maps of w = (x_d[n], memory[n]):
///   F[n] = force · w,   memory[n+1] = next · w.
struct Controller {
    ControlRow force;
    MemoryMatrix next;
};

Controller make_controller(const SpringDamperCoupling& coupling, const EnvironmentModel& env,
                           double period_s) {
    const double kc = coupling.stiffness_n_per_m;
    const double bc = coupling.damping_n_s_per_m;
    const double t = period_s;
    Controller ctl;
    if (env.kind == EnvironmentModel::Kind::rigid_wall) {
        // w = (x_d[n], x_d[n-1]); (16) with x_e = v_e = 0: F = k_c x_d + b_c (x_d[n] - x_d[n-1])/T.
        ctl.force.resize(2);
        ctl.force << kc + bc / t, -bc / t;
        ctl.next.resize(1, 2);
        ctl.next << 1.0, 0.0;
        return ctl;
    }
    // w = (x_d[n], x_d[n-1], x_e[n-1], v_e[n-1]); the implicit update of the header.
    const double me = env.mass_kg, ke = env.stiffness_n_per_m, be = env.damping_n_s_per_m;
    const double d = me + t * (bc + be) + t * t * (kc + ke);
    ControlRow x_d(4), v_d(4), v_e(4), x_e(4);
    x_d << 1.0, 0.0, 0.0, 0.0;
    v_d << 1.0 / t, -1.0 / t, 0.0, 0.0;
    v_e << (t * kc + bc) / d, -bc / d, -t * (kc + ke) / d, me / d;
    x_e << 0.0, 0.0, 1.0, 0.0;
    x_e += t * v_e;
    ctl.force = kc * (x_d - x_e) + bc * (v_d - v_e);
    ctl.next.resize(3, 4);
    ctl.next << x_d, x_e, v_e;
    return ctl;
}

/// Closed-loop state (s[n], memory[n]) -> (s[n+1], memory[n+1]), with x_d[n] = s(0).
LoopMatrix closed_loop_matrix(const SampledPlant& plant, const Controller& ctl) {
    const Eigen::Index n = plant.phi.rows();
    const Eigen::Index q = ctl.next.rows();
    LoopMatrix loop(n + q, n + q);
    loop.topLeftCorner(n, n) = plant.phi;
    loop.topLeftCorner(n, 1) += plant.gamma * ctl.force(0);
    loop.topRightCorner(n, q) = plant.gamma * ctl.force.tail(q);
    loop.bottomLeftCorner(q, n).setZero();
    loop.bottomLeftCorner(q, 1) = ctl.next.col(0);
    loop.bottomRightCorner(q, q) = ctl.next.rightCols(q);
    return loop;
}

/// Parlett-Reinsch balancing: a diagonal similarity, by powers of two, that evens the row
/// and column norms. The loop matrix mixes metres, metres per second and newtons, and
/// Eigen's real Schur iteration can fail to converge on it unbalanced (a two-mass grasp
/// with a 0.1 g hand on a 1e6 N/m arm did).
void balance(LoopMatrix& a) {
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

ClosedLoopPoles poles_of(LoopMatrix loop, double period_s) {
    balance(loop);
    Eigen::EigenSolver<LoopMatrix> solver(loop, /*computeEigenvectors=*/false);
    if (solver.info() != Eigen::Success) {
        throw std::runtime_error("exact model: the closed-loop eigenvalue solver did not converge");
    }
    ClosedLoopPoles poles;
    const auto& values = solver.eigenvalues();
    poles.eigenvalues.reserve(static_cast<std::size_t>(values.size()));
    double dominant_angle = 0.0;
    for (Eigen::Index i = 0; i < values.size(); ++i) {
        const theory::Complex lambda = values(i);
        poles.eigenvalues.push_back(lambda);
        if (std::abs(lambda) > poles.spectral_radius) {
            poles.spectral_radius = std::abs(lambda);
            dominant_angle = std::abs(std::arg(lambda));
        }
    }
    poles.dominant_frequency_hz = dominant_angle / (2.0 * std::numbers::pi * period_s);
    return poles;
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
    const bool grounded_hand = f == OperatorFamily::heavy_hand || f == OperatorFamily::stiff_grasp;
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
    if (f == OperatorFamily::stiff_grasp) {
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
}

void check_environment(const EnvironmentModel& e) {
    if (e.kind == EnvironmentModel::Kind::rigid_wall) return;
    check_non_negative("environment mass m_e", e.mass_kg, "kg");
    check_positive("environment stiffness k_e", e.stiffness_n_per_m, "N/m");
    check_non_negative("environment damping b_e", e.damping_n_s_per_m, "N s/m");
}

void check_loop(const DeviceModel& device, const SpringDamperCoupling& coupling, double rate_hz) {
    check_device(device);
    check_rate(rate_hz);
    check_non_negative("coupling stiffness k_c", coupling.stiffness_n_per_m, "N/m");
    check_non_negative("coupling damping b_c", coupling.damping_n_s_per_m, "N s/m");
}

constexpr double kTunedGripFractionsOfNyquist[] = {0.125, 0.25, 0.5, 0.75, 0.9, 1.0};

/// n points from lo to hi, equally spaced in log(value).
std::vector<double> log_grid(double lo, double hi, int n) {
    std::vector<double> grid;
    for (int i = 0; i < n; ++i) grid.push_back(lo * std::pow(hi / lo, double(i) / (n - 1)));
    return grid;
}

}  // namespace

std::string_view to_string(OperatorFamily family) {
    switch (family) {
        case OperatorFamily::hands_off:
            return "hands-off";
        case OperatorFamily::heavy_hand:
            return "heavy hand";
        case OperatorFamily::stiff_grasp:
            return "stiff grasp";
        case OperatorFamily::two_mass_grasp:
            return "two-mass grasp";
    }
    return "unknown";
}

OperatorModel OperatorModel::hands_off() { return {}; }

OperatorModel OperatorModel::heavy_hand(double hand_mass_kg, double hand_damping_n_s_per_m) {
    OperatorModel h;
    h.family = OperatorFamily::heavy_hand;
    h.hand_mass_kg = hand_mass_kg;
    h.hand_damping_n_s_per_m = hand_damping_n_s_per_m;
    return h;
}

OperatorModel OperatorModel::stiff_grasp(double hand_mass_kg, double hand_stiffness_n_per_m,
                                         double hand_damping_n_s_per_m) {
    OperatorModel h = heavy_hand(hand_mass_kg, hand_damping_n_s_per_m);
    h.family = OperatorFamily::stiff_grasp;
    h.hand_stiffness_n_per_m = hand_stiffness_n_per_m;
    return h;
}

OperatorModel OperatorModel::two_mass_grasp(double skin_stiffness_n_per_m,
                                            double skin_damping_n_s_per_m, double hand_mass_kg,
                                            double arm_stiffness_n_per_m,
                                            double arm_damping_n_s_per_m) {
    OperatorModel h;
    h.family = OperatorFamily::two_mass_grasp;
    h.skin_stiffness_n_per_m = skin_stiffness_n_per_m;
    h.skin_damping_n_s_per_m = skin_damping_n_s_per_m;
    h.hand_mass_kg = hand_mass_kg;
    h.arm_stiffness_n_per_m = arm_stiffness_n_per_m;
    h.arm_damping_n_s_per_m = arm_damping_n_s_per_m;
    return h;
}

std::string OperatorModel::describe() const {
    std::ostringstream s;
    s << to_string(family);
    switch (family) {
        case OperatorFamily::hands_off:
            break;
        case OperatorFamily::heavy_hand:
            s << " (m_h = " << hand_mass_kg << " kg, b_h = " << hand_damping_n_s_per_m << " N s/m)";
            break;
        case OperatorFamily::stiff_grasp:
            s << " (m_h = " << hand_mass_kg << " kg, k_h = " << hand_stiffness_n_per_m
              << " N/m, b_h = " << hand_damping_n_s_per_m << " N s/m)";
            break;
        case OperatorFamily::two_mass_grasp:
            s << " (k_s = " << skin_stiffness_n_per_m << " N/m, b_s = " << skin_damping_n_s_per_m
              << " N s/m, m_h = " << hand_mass_kg << " kg, k_a = " << arm_stiffness_n_per_m
              << " N/m, b_a = " << arm_damping_n_s_per_m << " N s/m)";
            break;
    }
    return s.str();
}

EnvironmentModel EnvironmentModel::rigid_wall() { return {}; }

EnvironmentModel EnvironmentModel::mass_spring(double mass_kg, double stiffness_n_per_m,
                                               double damping_n_s_per_m) {
    return {Kind::mass_spring, mass_kg, stiffness_n_per_m, damping_n_s_per_m};
}

std::string EnvironmentModel::describe() const {
    if (kind == Kind::rigid_wall) return "rigid wall";
    std::ostringstream s;
    s << "mass-spring (m_e = " << mass_kg << " kg, k_e = " << stiffness_n_per_m
      << " N/m, b_e = " << damping_n_s_per_m << " N s/m)";
    return s.str();
}

ClosedLoopPoles closed_loop_poles(const DeviceModel& device, const SpringDamperCoupling& coupling,
                                  double rate_hz, const OperatorModel& human,
                                  const EnvironmentModel& environment) {
    check_loop(device, coupling, rate_hz);
    check_operator(human);
    check_environment(environment);
    const double period_s = 1.0 / rate_hz;
    const SampledPlant plant = sample_plant(device, human, period_s);
    return poles_of(closed_loop_matrix(plant, make_controller(coupling, environment, period_s)),
                    period_s);
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

ExactCheck check_exact(const DeviceModel& device, const SpringDamperCoupling& coupling,
                       double rate_hz, const std::vector<OperatorModel>& operators,
                       const std::vector<EnvironmentModel>& environments) {
    check_loop(device, coupling, rate_hz);
    for (const OperatorModel& h : operators) check_operator(h);
    for (const EnvironmentModel& e : environments) check_environment(e);
    const double period_s = 1.0 / rate_hz;

    std::vector<Controller> controllers;
    controllers.reserve(environments.size());
    for (const EnvironmentModel& e : environments) {
        controllers.push_back(make_controller(coupling, e, period_s));
    }
    ExactCheck check;
    check.worst_spectral_radius = -1.0;
    for (const OperatorModel& h : operators) {
        const SampledPlant plant = sample_plant(device, h, period_s);  // once per operator
        for (std::size_t i = 0; i < environments.size(); ++i) {
            const ClosedLoopPoles poles =
                poles_of(closed_loop_matrix(plant, controllers[i]), period_s);
            ++check.cases_checked;
            if (poles.spectral_radius > check.worst_spectral_radius) {
                check.worst_spectral_radius = poles.spectral_radius;
                check.worst_frequency_hz = poles.dominant_frequency_hz;
                check.worst_operator = h;
                check.worst_environment = environments[i];
            }
        }
    }
    if (check.cases_checked == 0) {
        throw std::invalid_argument("check_exact: the operator or environment sweep is empty");
    }
    check.worst_margin = 1.0 - check.worst_spectral_radius;
    check.stable = check.worst_margin >= -kMarginalTolerance;
    return check;
}

ExactCheck check_exact(const DeviceModel& device, const SpringDamperCoupling& coupling,
                       double rate_hz) {
    return check_exact(device, coupling, rate_hz, default_operator_sweep(device, rate_hz),
                       default_environment_sweep(device));
}

}  // namespace hapticd::tune
