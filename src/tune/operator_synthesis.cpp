#include "hapticd/tune/operator_synthesis.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/theory/passive_model.hpp"
#include "hapticd/tune/environment_assumption.hpp"

namespace hapticd::tune {
namespace {

using theory::Complex;
constexpr double kPi = std::numbers::pi;

/// Absorbers of the free-handle part: zeros of the handle's reactance on `zeros`.
void add_free_handle_modes(double device_mass_kg, const std::vector<double>& zeros,
                           std::vector<OperatorMode>& modes) {
    const std::size_t n = zeros.size();
    std::vector<double> poles(n);
    poles[0] = zeros[0] / std::sqrt(2.0);
    for (std::size_t i = 1; i < n; ++i) poles[i] = std::sqrt(zeros[i - 1] * zeros[i]);
    // C = m Π Ω_j²/p_i², so that X_0(ω) -> m ω as ω -> ∞.
    double c = device_mass_kg;
    for (std::size_t i = 0; i < n; ++i) c *= (zeros[i] * zeros[i]) / (poles[i] * poles[i]);
    for (std::size_t i = 0; i < n; ++i) {
        const double p2 = poles[i] * poles[i];
        double residue = c * p2;
        for (std::size_t j = 0; j < n; ++j) residue *= 1.0 - p2 / (zeros[j] * zeros[j]);
        for (std::size_t l = 0; l < n; ++l) {
            if (l != i) residue /= 1.0 - p2 / (poles[l] * poles[l]);
        }
        modes.push_back({residue / p2, residue, 0.0});
    }
}

}  // namespace

std::vector<double> alias_frequencies_rad_per_s(double theta, double rate_hz, int count) {
    std::vector<double> aliases;
    for (int k = -count; k <= count; ++k) aliases.push_back(std::abs(theta + 2.0 * kPi * k));
    std::sort(aliases.begin(), aliases.end());
    aliases.erase(std::unique(aliases.begin(), aliases.end(),
                              [](double a, double b) { return std::abs(a - b) < 1e-9 * (a + b); }),
                  aliases.end());
    aliases.erase(std::remove(aliases.begin(), aliases.end(), 0.0), aliases.end());
    aliases.resize(static_cast<std::size_t>(count));
    for (double& a : aliases) a *= rate_hz;
    return aliases;
}

OperatorModel alias_tuned_operator(const theory::DeviceModel& device, double theta, double rate_hz,
                                   int aliases, double reactance_n_s_per_m) {
    if (!(theta > 0.0 && theta <= kPi) || aliases < 1) {
        throw std::invalid_argument("alias_tuned_operator: need 0 < θ <= π and >= 1 alias");
    }
    const double period = 1.0 / rate_hz;
    std::vector<OperatorMode> modes;
    const std::vector<double> zeros = alias_frequencies_rad_per_s(theta, rate_hz, aliases);
    add_free_handle_modes(device.mass_kg, zeros, modes);
    double rigid_mass = 0.0;
    double ground_stiffness = 0.0;
    // A reactance below a billionth of the device mass's at the first alias, or a millionth
    // of the device damping that the handle's b + jX is measured against, is rounding: its
    // tan/cot series would be modes of 1e-13 kg on 1e-3 N/m springs, which change nothing but
    // the conditioning (one such grasp stalled the eigenvalue solver).
    const double negligible =
        std::max(1e-9 * device.mass_kg * zeros[0], 1e-6 * device.damping_n_s_per_m);
    const double x = std::abs(reactance_n_s_per_m) < negligible ? 0.0 : reactance_n_s_per_m;
    const int terms = aliases / 2 + 2;
    if (x != 0.0 && std::isfinite(x)) {
        const double residue_per_a = 4.0 / period;
        if (x > 0.0) {
            // A tan(ωT/2) = Σ_k (4A/T) ω / (((2k+1)π/T)² - ω²), A = X / tan(θ/2).
            const double a = x / std::tan(theta / 2.0);
            double kept = 0.0;
            for (int k = 0; k < terms; ++k) {
                const double pole = (2 * k + 1) * kPi / period;
                modes.push_back({a * residue_per_a / (pole * pole), a * residue_per_a, 0.0});
                kept += 1.0 / ((k + 0.5) * (k + 0.5));
            }
            rigid_mass = a * period / (kPi * kPi) * (kPi * kPi / 2.0 - kept);
        } else {
            // -A cot(ωT/2) = -2A/(ωT) + Σ_{k>=1} (4A/T) ω / ((2kπ/T)² - ω²), A = -X tan(θ/2).
            const double a = -x * std::tan(theta / 2.0);
            ground_stiffness = 2.0 * a / period;
            double kept = 0.0;
            for (int k = 1; k <= terms; ++k) {
                const double pole = 2.0 * k * kPi / period;
                modes.push_back({a * residue_per_a / (pole * pole), a * residue_per_a, 0.0});
                kept += 1.0 / (double(k) * k);
            }
            rigid_mass = a * period / (kPi * kPi) * (kPi * kPi / 6.0 - kept);
        }
    }
    std::ostringstream origin;
    origin << "free-handle modes on " << aliases << " aliases of "
           << theory::frequency_hz(theta, period) << " Hz, reactance " << x << " N s/m there";
    return OperatorModel::multi_mode(rigid_mass, ground_stiffness, 0.0, std::move(modes),
                                     origin.str());
}

std::vector<OperatorModel> alias_shaped_operators(const theory::DeviceModel& device, double theta,
                                                  double rate_hz, double delay_periods, int aliases,
                                                  double direction) {
    if (!(theta > 0.0 && theta < kPi) || aliases < 2) {
        throw std::invalid_argument("alias_shaped_operators: need 0 < θ < π and >= 2 aliases");
    }
    const double period = 1.0 / rate_hz;
    const theory::LoopDelay delay = theory::split_delay(delay_periods);
    const std::vector<double> zeros = alias_frequencies_rad_per_s(theta, rate_hz, aliases);
    const auto n = static_cast<Eigen::Index>(zeros.size());
    // The reactance of W = b + jX that puts the alias's c_k Y on its disk's rim point in
    // `direction` ψ: Y = (1 + e^{j(ψ - arg c_k)})/(2b), so X = -b tan((ψ + a_k)/2) with
    // a_k = -arg c_k = (1 + q)θ + φ(θ + 2πk); ψ = π gives b cot(a_k/2).
    Eigen::VectorXd target(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        const double o = zeros[static_cast<std::size_t>(i)] * period;  // |θ + 2πk|
        const double k = std::round((o - theta) / (2.0 * kPi));
        const bool positive = std::abs(o - theta - 2.0 * kPi * k) < 1e-9 * o;
        const double a = (1.0 + delay.whole_periods) * theta + delay.fraction * (positive ? o : -o);
        const double half = (direction + a) / 2.0;
        if (std::abs(std::cos(half)) < 1e-12) return {};  // an infinite reactance
        // X(-ω) = -X(ω): a mirror alias takes the opposite sign at |ω|.
        target(i) = (positive ? -1.0 : 1.0) * device.damping_n_s_per_m * std::tan(half);
    }
    // Foster: -k_0/ω (a spring to ground) or m_∞ ω (a rigid mass), and absorbers a_i ω/(p_i² -
    // ω²), one pole between each two aliases at p_i = ω_i (ω_{i+1}/ω_i)^λ_i; the coefficients
    // must come out >= 0. A compass search over the λ_i (from the geometric means) raises the
    // least coefficient, relative to the largest, until it is >= 0.
    const auto pole = [&](const std::vector<double>& lambda, Eigen::Index j) {
        const auto l = static_cast<std::size_t>(j - 1);
        return zeros[l] * std::pow(zeros[l + 1] / zeros[l], lambda[l]);
    };
    const auto fit = [&](const std::vector<double>& lambda, bool grounded) {
        Eigen::MatrixXd basis(n, n);
        for (Eigen::Index i = 0; i < n; ++i) {
            const double w = zeros[static_cast<std::size_t>(i)];
            basis(i, 0) = grounded ? -1.0 / w : w;
            for (Eigen::Index j = 1; j < n; ++j) {
                const double p = pole(lambda, j);
                basis(i, j) = w / (p * p - w * w);
            }
        }
        return Eigen::VectorXd(basis.colPivHouseholderQr().solve(target));
    };
    const auto least = [](const Eigen::VectorXd& c) {
        if (!c.allFinite()) return -std::numeric_limits<double>::infinity();
        return c.minCoeff() / std::max(c.cwiseAbs().maxCoeff(), 1e-300);
    };
    std::vector<OperatorModel> out;
    for (const bool grounded : {true, false}) {
        std::vector<double> lambda(static_cast<std::size_t>(n - 1), 0.5);
        Eigen::VectorXd c = fit(lambda, grounded);
        double value = least(c);
        for (double step = 0.25; step >= 1e-3 && value < 0.0;) {
            bool improved = false;
            for (double& l : lambda) {
                for (const double sign : {-1.0, 1.0}) {
                    const double saved = l;
                    l = std::clamp(saved + sign * step, 1e-3, 1.0 - 1e-3);
                    const Eigen::VectorXd trial = fit(lambda, grounded);
                    const double trial_value = least(trial);
                    if (trial_value > value) {
                        c = trial;
                        value = trial_value;
                        improved = true;
                    } else {
                        l = saved;
                    }
                }
            }
            if (!improved) step /= 2.0;
        }
        if (value < 0.0) continue;
        std::vector<OperatorMode> modes;
        add_free_handle_modes(device.mass_kg, zeros, modes);
        for (Eigen::Index j = 1; j < n; ++j) {
            const double p = pole(lambda, j);
            if (c(j) > 0.0) modes.push_back({c(j) / (p * p), c(j), 0.0});
        }
        std::ostringstream origin;
        origin << "each of " << aliases << " aliases of " << theory::frequency_hz(theta, period)
               << " Hz on its worst point for " << delay_periods << " periods of delay";
        if (direction != kPi) origin << " (rim direction " << direction << " rad)";
        out.push_back(OperatorModel::multi_mode(grounded ? 0.0 : c(0), grounded ? c(0) : 0.0, 0.0,
                                                std::move(modes), origin.str()));
    }
    return out;
}

EnvironmentModel lossless_environment_with_admittance(double theta, double rate_hz,
                                                      double admittance_imag) {
    if (!(theta > 0.0 && theta < kPi) || admittance_imag == 0.0 ||
        !std::isfinite(admittance_imag)) {
        throw std::invalid_argument(
            "lossless_environment_with_admittance: need 0 < θ < π and a finite admittance != 0");
    }
    const double period = 1.0 / rate_hz;
    // Trapezoidal m_e s + k_e/s on the unit circle: j [m_e (2/T) tan(θ/2) - k_e (T/2) cot(θ/2)].
    const double mass_gain = 2.0 / period * std::tan(theta / 2.0);
    const double spring_gain = period / 2.0 / std::tan(theta / 2.0);
    const double reactance = -1.0 / admittance_imag;  // Z_e = 1/(j h) = -j/h
    // The other element takes a thousandth of the reactance, so that the environment is
    // both grounded (k_e > 0) and has mass.
    if (reactance > 0.0) {
        const double ke = 1e-3 * reactance / spring_gain;
        return EnvironmentModel::lossless_mass_spring((reactance + ke * spring_gain) / mass_gain,
                                                      ke);
    }
    const double me = 1e-3 * -reactance / mass_gain;
    return EnvironmentModel::lossless_mass_spring(me, (me * mass_gain - reactance) / spring_gain);
}

namespace {

// Below 0.01 rad (1.6 Hz at 1 kHz) the aliases of θ sit a thousand times apart, and the
// synthesised modes span masses beyond what the eigenvalue problem resolves; the low band's
// bound is the θ -> 0 limit, which 0.01 already meets to 1e-5.
constexpr double kLowestTheta = 0.01;

/// The fixed spread of frequencies every design's adversaries are built at, π among them.
std::vector<double> spread_of_frequencies() {
    return {kPi, 2.0 * kPi / 3.0, kPi / 2.0, 0.3, 0.1, 0.03, kLowestTheta};
}

/// Adds θ (where a bound binds) unless it is below the band or already in the spread.
void add_if_new(std::vector<double>& thetas, double theta) {
    const bool known = std::any_of(thetas.begin(), thetas.end(),
                                   [&](double t) { return std::abs(t - theta) < 1e-3; });
    if (theta > kLowestTheta && !known) thetas.push_back(theta);
}

/// Alias-tuned operators with 1, 2, 4, 8 and 16 modes for the reactance x at θ.
void add_alias_tuned(std::vector<OperatorModel>& out, const theory::DeviceModel& device,
                     double theta, double rate_hz, double x) {
    for (const int aliases : {1, 2, 4, 8, 16}) {
        // Low in the band the 16th alias is 1000 times the first, and the modes' masses then
        // span more than the eigenvalues resolve (rounding reaches 1e-9).
        if (aliases > 8 && theta < 0.1) continue;
        out.push_back(alias_tuned_operator(device, theta, rate_hz, aliases, x));
    }
}

}  // namespace

Adversaries synthesize_adversaries(const theory::DeviceModel& device,
                                   const theory::SpringDamperCoupling& coupling, double rate_hz,
                                   double delay_periods) {
    const double period = 1.0 / rate_hz;
    const theory::LoopDelay delay = theory::split_delay(delay_periods);
    std::vector<double> thetas = spread_of_frequencies();
    const theory::CouplingCheck passive = theory::check_coupling(
        device, coupling, {theory::HoldModel::passive, delay_periods}, rate_hz, 1024);
    add_if_new(thetas, theory::normalized_frequency(passive.worst_frequency_hz, period));

    Adversaries out;
    for (const double theta : thetas) {
        const Complex zc = theory::coupling_impedance(coupling, theta, period);
        const Complex rotation = std::polar(1.0, -(1.0 + delay.whole_periods) * theta);
        std::vector<double> reactances{(-zc * rotation).imag()};  // the rigid wall's
        const double conductance = (1.0 / zc).real();
        if (conductance > 0.0 && theta < kPi * (1.0 - 1e-9)) {
            // The worst passive environment at θ: lossless (1/Z keeps Re(1/Z_c)), with the
            // susceptance that puts 1/Z nearest the worst operators' -Ĝ, whose disk is centred
            // at -S/(2b), S the alias weight sum (passive_model.hpp).
            const Complex weights = theory::passive_alias_weight_sum(theta, delay_periods);
            const Complex z =
                1.0 / Complex(conductance, -weights.imag() / (2.0 * device.damping_n_s_per_m));
            const double admittance = (1.0 / z - 1.0 / zc).imag();
            // Within a millionth of rigid (or of free) the rigid wall (or the coupling's own
            // spring) is the same case, and the environment's numbers would not be physical.
            const double relative = std::abs(admittance) * std::abs(zc);
            if (relative > 1e-6 && relative < 1e6) {
                out.environments.push_back(
                    lossless_environment_with_admittance(theta, rate_hz, admittance));
            }
            reactances.push_back((-z * rotation).imag());
        }
        for (const double x : reactances) add_alias_tuned(out.operators, device, theta, rate_hz, x);
        // With a fraction of a period of delay each alias has its own worst reactance.
        if (delay.fraction > 0.0 && theta < kPi * (1.0 - 1e-9)) {
            for (const int aliases : {2, 3, 4, 6, 8}) {
                for (OperatorModel& h :
                     alias_shaped_operators(device, theta, rate_hz, delay_periods, aliases)) {
                    out.operators.push_back(std::move(h));
                }
            }
        }
    }
    return out;
}

std::vector<OperatorModel> synthesize_scene_adversaries(
    const theory::DeviceModel& device, const theory::SpringDamperCoupling& coupling, double rate_hz,
    const std::vector<SceneEnvironment>& scene, double delay_periods) {
    const double period = 1.0 / rate_hz;
    const theory::LoopDelay delay = theory::split_delay(delay_periods);
    std::vector<double> thetas = spread_of_frequencies();
    const SceneCheck passive =
        check_passive_scene(device, coupling, rate_hz, scene, delay_periods, 1024);
    add_if_new(thetas, theory::normalized_frequency(passive.worst_frequency_hz, period));
    std::vector<OperatorModel> out;
    for (const double theta : thetas) {
        const Complex rotation = std::polar(1.0, -(1.0 + delay.whole_periods) * theta);
        for (const SceneEnvironment& env : scene) {
            const Complex z = port_impedance(coupling, env.model, theta, period);
            add_alias_tuned(out, device, theta, rate_hz, (-z * rotation).imag());
            if (delay.fraction > 0.0 && theta < kPi * (1.0 - 1e-9)) {
                // The pole at e^{jθ} needs the operators' alias sum Ĝ = -1/Z; it ranges over
                // the disk of centre S/(2b) and radius 1/(2b), S the alias weight sum, and
                // the rim point nearest -1/Z is in the direction arg(-2b/Z - S) from the
                // centre: shape each alias for that direction.
                const Complex weights = theory::passive_alias_weight_sum(theta, delay_periods);
                const double direction = std::arg(-2.0 * device.damping_n_s_per_m / z - weights);
                for (const int aliases : {2, 3, 4, 6, 8}) {
                    for (OperatorModel& h : alias_shaped_operators(
                             device, theta, rate_hz, delay_periods, aliases, direction)) {
                        out.push_back(std::move(h));
                    }
                }
            }
        }
    }
    return out;
}

}  // namespace hapticd::tune
