#include "hapticd/tune/class_check.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "hapticd/tune/input_checks.hpp"
#include "hapticd/tune/operator_synthesis.hpp"

namespace hapticd::tune {
namespace {

using theory::DeviceModel;
using theory::SpringDamperCoupling;

std::vector<EnvironmentModel> models_of(const std::vector<SceneEnvironment>& scene) {
    std::vector<EnvironmentModel> out;
    for (const SceneEnvironment& e : scene) out.push_back(e.model);
    return out;
}

/// Keeps the larger of two checks and adds up their cases.
void merge(ExactCheck& into, const ExactCheck& other) {
    const int cases = into.cases_checked + other.cases_checked;
    if (other.worst_spectral_radius > into.worst_spectral_radius) into = other;
    into.cases_checked = cases;
}

/// A lossless environment on two coordinates in [0, 1]: the frequency θ at which it takes
/// the admittance jY, and Y, signed and logarithmic over 12 decades around 1/|Z_c|.
struct LosslessCoordinates {
    double theta_u = 0.5, admittance_u = 0.5;
};

constexpr double kLosslessLowestTheta = 0.01;
constexpr double kAdmittanceDecades = 6.0;  // each side of 1/|Z_c|

EnvironmentModel lossless_at(const LosslessCoordinates& c, const SpringDamperCoupling& coupling,
                             double rate_hz) {
    const double theta =
        kLosslessLowestTheta * std::pow((std::numbers::pi * 0.999) / kLosslessLowestTheta,
                                        c.theta_u);
    const double zc = std::abs(theory::coupling_impedance(coupling, theta, 1.0 / rate_hz));
    const double signed_u = 2.0 * c.admittance_u - 1.0;  // -1..1
    const double magnitude =
        std::pow(10.0, kAdmittanceDecades * (2.0 * std::abs(signed_u) - 1.0)) / std::max(zc, 1e-9);
    return lossless_environment_with_admittance(theta, rate_hz,
                                                signed_u >= 0.0 ? magnitude : -magnitude);
}

/// The search of a class (the file comment of class_check.hpp).
class ClassSearch {
  public:
    ClassSearch(const DeviceModel& device, const SpringDamperCoupling& coupling, double rate_hz,
                const OperatorClass& cls, double delay_periods)
        : device_(device), coupling_(coupling), rate_hz_(rate_hz), cls_(cls),
          delay_periods_(delay_periods) {}

    ExactCheck run(const std::vector<EnvironmentModel>& environments, bool every_passive) {
        best_.worst_spectral_radius = -1.0;
        best_.delay_periods = delay_periods_;
        // Stage 1: hands-off and the 3^5 grid meet every environment.
        merge(best_, check_exact(device_, coupling_, rate_hz_, {OperatorModel::hands_off()},
                                 environments, delay_periods_));
        struct Seed {
            double radius;
            ClassPoint point;
            EnvironmentModel environment;
        };
        std::vector<Seed> seeds;
        ClassPoint point{};
        for (int index = 0; index < 243; ++index) {
            int rest = index;
            for (double& u : point) u = 0.5 * (rest % 3), rest /= 3;
            const OperatorModel h = cls_.member(point);
            if (!cls_.contains(h)) continue;
            // One sampling of the plant for all environments; the seed is its worst one.
            const ExactCheck c =
                check_exact(device_, coupling_, rate_hz_, {h}, environments, delay_periods_);
            merge(best_, c);
            seeds.push_back({c.worst_spectral_radius, point, c.worst_environment});
        }
        // Stage 2: a compass search from the six worst (distinct operators).
        std::sort(seeds.begin(), seeds.end(),
                  [](const Seed& a, const Seed& b) { return a.radius > b.radius; });
        for (std::size_t i = 0; i < seeds.size() && i < kClimbs; ++i) {
            climb(seeds[i].point, seeds[i].environment, every_passive);
        }
        best_.worst_margin = 1.0 - best_.worst_spectral_radius;
        best_.stable = best_.worst_margin >= -kMarginalTolerance;
        return best_;
    }

  private:
    static constexpr int kClimbs = 6;
    static constexpr double kFirstStep = 0.25, kLastStep = 1.0 / 256.0;

    double evaluate(const OperatorModel& h, const EnvironmentModel& e) {
        const ClosedLoopPoles poles = closed_loop_poles(device_, coupling_, rate_hz_, h, e,
                                                        delay_periods_);
        ++best_.cases_checked;
        if (poles.spectral_radius > best_.worst_spectral_radius) {
            best_.worst_spectral_radius = poles.spectral_radius;
            best_.worst_frequency_hz = poles.dominant_frequency_hz;
            best_.worst_operator = h;
            best_.worst_environment = e;
        }
        return poles.spectral_radius;
    }

    /// Compass search over the operator's coordinates, then (for every passive environment)
    /// over a lossless environment's, then the operator's again.
    void climb(ClassPoint point, EnvironmentModel environment, bool every_passive) {
        double radius = climb_operator(point, environment);
        if (!every_passive) return;
        LosslessCoordinates best_env;
        double env_radius = -1.0;
        // Start the environment from the best of a small spread of lossless ones.
        const OperatorModel h = cls_.member(point);
        for (const double tu : {0.0, 0.25, 0.5, 0.75, 1.0}) {
            for (const double au : {0.1, 0.3, 0.45, 0.55, 0.7, 0.9}) {
                const LosslessCoordinates c{tu, au};
                const double r = evaluate(h, lossless_at(c, coupling_, rate_hz_));
                if (r > env_radius) env_radius = r, best_env = c;
            }
        }
        if (env_radius <= radius) return;
        for (double step = kFirstStep; step >= kLastStep; step /= 2.0) {
            bool improved = true;
            while (improved) {
                improved = false;
                for (double* u : {&best_env.theta_u, &best_env.admittance_u}) {
                    for (const double sign : {-1.0, 1.0}) {
                        const double saved = *u;
                        *u = std::clamp(saved + sign * step, 0.0, 1.0);
                        const double r = evaluate(h, lossless_at(best_env, coupling_, rate_hz_));
                        if (r > env_radius) {
                            env_radius = r;
                            improved = true;
                        } else {
                            *u = saved;
                        }
                    }
                }
            }
        }
        climb_operator(point, lossless_at(best_env, coupling_, rate_hz_));
    }

    double climb_operator(ClassPoint& point, const EnvironmentModel& environment) {
        double radius = evaluate(cls_.member(point), environment);
        for (double step = kFirstStep; step >= kLastStep; step /= 2.0) {
            bool improved = true;
            while (improved) {
                improved = false;
                for (double& u : point) {
                    for (const double sign : {-1.0, 1.0}) {
                        const double saved = u;
                        u = std::clamp(saved + sign * step, 0.0, 1.0);
                        const OperatorModel h = cls_.member(point);
                        const double r = cls_.contains(h) ? evaluate(h, environment) : -1.0;
                        if (r > radius) {
                            radius = r;
                            improved = true;
                        } else {
                            u = saved;
                        }
                    }
                }
            }
        }
        return radius;
    }

    DeviceModel device_;
    SpringDamperCoupling coupling_;
    double rate_hz_;
    OperatorClass cls_;
    double delay_periods_;
    ExactCheck best_;
};

}  // namespace

std::string StabilityAssumption::describe() const {
    const std::string who =
        operators ? "the declared operator class (" + operators->describe() + ")"
                  : std::string("every passive operator");
    return who + " and " + environments.describe();
}

ExactCheck check_exact(const DeviceModel& device, const SpringDamperCoupling& coupling,
                       double rate_hz, const StabilityAssumption& assumption,
                       double delay_periods) {
    const bool every_environment = assumption.environments.every_passive();
    if (!assumption.operators && every_environment) {
        return check_exact(device, coupling, rate_hz, delay_periods);
    }
    check_device(device);
    check_rate(rate_hz);
    check_coupling_gains(coupling);
    check_delay_periods(delay_periods);
    const std::vector<EnvironmentModel> scene = models_of(assumption.environments.scene);
    if (!assumption.operators) {
        // Every passive operator against the scene: the default operators, and the
        // alias-tuned ones built for each of the scene's environments.
        ExactCheck check = check_exact(device, coupling, rate_hz,
                                       default_operator_sweep(device, rate_hz), scene,
                                       delay_periods);
        merge(check, check_exact(device, coupling, rate_hz,
                                 synthesize_scene_adversaries(device, coupling, rate_hz,
                                                              assumption.environments.scene,
                                                              delay_periods),
                                 scene, delay_periods));
        return check;
    }
    std::vector<EnvironmentModel> environments = scene;
    if (every_environment) {
        // The default environments and the lossless ones worst for the passive bound; the
        // search then also climbs over lossless environments.
        environments = default_environment_sweep(device);
        const Adversaries adversaries =
            synthesize_adversaries(device, coupling, rate_hz, delay_periods);
        environments.insert(environments.end(), adversaries.environments.begin(),
                            adversaries.environments.end());
    }
    ClassSearch search(device, coupling, rate_hz, *assumption.operators, delay_periods);
    return search.run(environments, every_environment);
}

StiffnessLimit exact_stiffness_limit(const DeviceModel& device, double coupling_damping_n_s_per_m,
                                     double rate_hz, const StabilityAssumption& assumption,
                                     double delay_periods, double tolerance) {
    if (!(tolerance > 0.0 && tolerance < 1.0)) {
        throw std::invalid_argument("exact_stiffness_limit: tolerance must be in (0, 1)");
    }
    StiffnessLimit limit;
    const auto check = [&](double stiffness) {
        ++limit.checks;
        return check_exact(device, {stiffness, coupling_damping_n_s_per_m}, rate_hz, assumption,
                           delay_periods);
    };
    ExactCheck at_lo = check(0.0);
    if (!at_lo.stable) {
        limit.at_limit = at_lo;
        return limit;
    }
    // Bracket from the heavy-hand scale 2b/T upward by doubling.
    double lo = 0.0;
    double hi = 2.0 * device.damping_n_s_per_m * rate_hz;
    for (;;) {
        const ExactCheck c = check(hi);
        if (!c.stable) break;
        lo = hi;
        at_lo = c;
        if (hi >= kMaxCouplingStiffness) break;
        hi = std::min(2.0 * hi, kMaxCouplingStiffness);
    }
    while (hi - lo > tolerance * hi && lo < kMaxCouplingStiffness) {
        const double mid = 0.5 * (lo + hi);
        const ExactCheck c = check(mid);
        if (c.stable) {
            lo = mid;
            at_lo = c;
        } else {
            hi = mid;
        }
    }
    limit.stiffness_n_per_m = lo;
    limit.rejected_n_per_m = hi;
    limit.at_limit = at_lo;
    return limit;
}

}  // namespace hapticd::tune
