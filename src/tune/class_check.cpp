#include "hapticd/tune/class_check.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <future>
#include <initializer_list>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <thread>

#include "hapticd/tune/input_checks.hpp"
#include "hapticd/tune/operator_synthesis.hpp"

namespace hapticd::tune {
namespace {

using theory::DeviceModel;
using theory::SpringDamperCoupling;

std::vector<EnvironmentModel> models_of(const std::vector<SceneEnvironment>& scene) {
    std::vector<EnvironmentModel> out;
    out.reserve(scene.size());
    for (const SceneEnvironment& e : scene) out.push_back(e.model);
    return out;
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
    const double theta = kLosslessLowestTheta *
                         std::pow((std::numbers::pi * 0.999) / kLosslessLowestTheta, c.theta_u);
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
        : device_(device),
          coupling_(coupling),
          rate_hz_(rate_hz),
          cls_(cls),
          delay_periods_(delay_periods) {
        // Nothing found yet, under this search's delay: every job starts from this, so a
        // job's worst case keeps the delay when it is merged.
        best_.worst_spectral_radius = -1.0;
        best_.delay_periods = delay_periods;
    }

    /// Once per search.
    ExactCheck run(const std::vector<EnvironmentModel>& environments, bool every_passive) {
        // Stage 1: hands-off, the 3^5 grid (corners, edge midpoints, centre) with the members
        // tuned from each, and the members with two modes on two aliases at once, each
        // against every environment: one job a probe.
        merge(best_, check_exact(device_, coupling_, rate_hz_, {OperatorModel::hands_off()},
                                 environments, delay_periods_));
        if (!decided()) {
            const std::vector<TunedMember> two_modes = two_mode_members();
            in_parallel(kGridPoints + two_modes.size(), [&](ClassSearch& job, std::size_t i) {
                if (i < kGridPoints) {
                    job.probe_grid_point(i, environments);
                } else {
                    job.probe_two_modes(two_modes[i - kGridPoints], environments, every_passive);
                }
            });
        }
        // Stage 2: compass searches from the worst seeds of each band (the whole circle, and
        // the low, middle and high bands of arg z: a lightly damped slow mode must not hide a
        // fast one that the climb could push out of the circle, nor the reverse), and in each
        // band from hands-off. A witness that grows by kDecisiveGrowthPerTick ends the
        // climbs: the verdict is no, and climbing further would only name a worse member (9.4
        // s instead of 0.7 s for the pen-grip class at 5 periods of delay, 3 % past its
        // proof). One job a climb.
        struct Climb {
            std::size_t band;
            std::optional<Seed> from;  ///< none: hands-off
        };
        std::vector<Climb> climbs;
        for (std::size_t band = 0; band < kBands.size(); ++band) {
            std::vector<Seed>& s = seeds_[band];
            std::stable_sort(s.begin(), s.end(),
                             [](const Seed& a, const Seed& b) { return a.radius > b.radius; });
            const std::size_t count = band == 0 ? kClimbs : kBandClimbs;
            for (std::size_t i = 0; i < s.size() && i < count && s[i].radius >= 0.0; ++i) {
                climbs.push_back({band, s[i]});
            }
            if (every_passive) climbs.push_back({band, std::nullopt});
        }
        if (!decided()) {
            in_parallel(climbs.size(), [&](ClassSearch& job, std::size_t i) {
                const Band& band = kBands[climbs[i].band];
                if (climbs[i].from) {
                    job.climb(climbs[i].from->point, climbs[i].from->environment, every_passive,
                              band);
                } else {
                    job.climb_hands_off(band);
                }
            });
        }
        best_.worst_margin = 1.0 - best_.worst_spectral_radius;
        best_.stable = best_.worst_margin >= -kMarginalTolerance;
        return best_;
    }

  private:
    bool decided() const { return decisive(best_); }

    static constexpr std::size_t kClimbs = 6, kBandClimbs = 3;
    static constexpr int kAliasTerms = 100;
    // Down to 2^-16 of each range: a resonance tuned to an alias is a sharp peak.
    static constexpr double kFirstStep = 0.25, kLastStep = 1.0 / 65536.0;
    // A move counts when it raises |z| by more than this: far below the verdict's
    // kMarginalTolerance (1e-8) and above the eigenvalues' rounding away from z = 1 (about
    // 1e-15), where a climb on a flat ridge otherwise moves on noise (at the pen-grip class's
    // proof with 5 periods of delay: 169,000 climb cases instead of 290,000).
    static constexpr double kClimbGain = 1e-12;

    /// A band of arg z, [lo, hi) in rad.
    struct Band {
        double lo, hi;
    };
    static constexpr std::array<Band, 4> kBands = {Band{0.0, 4.0}, Band{0.0, 0.1},
                                                   Band{0.1, std::numbers::pi / 2.0},
                                                   Band{std::numbers::pi / 2.0, 4.0}};

    /// The largest |z| among the eigenvalues in the band; -1 when it holds none. A real
    /// eigenvalue in [1 - 1e-3, 1] is left out: an almost free mass (a free hand, a lossless
    /// environment on a weak spring) sits there for every design and would flatten the
    /// landscape the climbs need (the verdict, in record(), keeps every eigenvalue).
    static double band_radius(const ClosedLoopPoles& poles, const Band& band) {
        double radius = -1.0;
        for (const theory::Complex& z : poles.eigenvalues) {
            if (z.imag() == 0.0 && z.real() >= 1.0 - 1e-3 && z.real() <= 1.0) continue;
            const double angle = std::abs(std::arg(z));
            if (angle >= band.lo && angle < band.hi) radius = std::max(radius, std::abs(z));
        }
        return radius;
    }

    double evaluate(const OperatorModel& h, const EnvironmentModel& e,
                    const Band& band = kBands[0]) {
        const ClosedLoopPoles poles =
            closed_loop_poles(device_, coupling_, rate_hz_, h, e, delay_periods_);
        record(poles, h, e);
        return band_radius(poles, band);
    }

    void record(const ClosedLoopPoles& poles, const OperatorModel& h, const EnvironmentModel& e) {
        ++best_.cases_checked;
        if (poles.spectral_radius > best_.worst_spectral_radius) {
            best_.worst_spectral_radius = poles.spectral_radius;
            best_.worst_frequency_hz = poles.dominant_frequency_hz;
            best_.worst_operator = h;
            best_.worst_environment = e;
        }
    }

    /// Members like h with one of k_s, k_a, m_h changed so that the undamped handle (the
    /// device mass m on k_s, the hand m_h on k_a) has a mode at an alias ω of a frequency of
    /// the spread: det(K - ω² M) = 0 with M = diag(m, m_h), K = [[k_s, -k_s], [-k_s, k_s + k_a]],
    ///   k_s = ω² m (k_a - ω² m_h) / (k_a - ω² (m + m_h)),
    ///   k_a = k_s² / (k_s - ω² m) - k_s + ω² m_h,
    ///   m_h = (k_s + k_a - k_s² / (k_s - ω² m)) / ω².
    std::vector<OperatorModel> tuned_members(const OperatorModel& h) const {
        std::vector<OperatorModel> out;
        const double m = device_.mass_kg;
        const double t = 1.0 / rate_hz_;
        const double pi = std::numbers::pi;
        for (const double theta : {pi, 2.0 * pi / 3.0, pi / 2.0, 0.3, 0.1, 0.03}) {
            for (const double alias : {theta, 2.0 * pi - theta, 2.0 * pi + theta}) {
                const double w2 = (alias / t) * (alias / t);
                OperatorModel k_s = h, k_a = h, m_h = h;
                k_s.skin_stiffness_n_per_m = w2 * m *
                                             (h.arm_stiffness_n_per_m - w2 * h.hand_mass_kg) /
                                             (h.arm_stiffness_n_per_m - w2 * (m + h.hand_mass_kg));
                const double ks = h.skin_stiffness_n_per_m;
                k_a.arm_stiffness_n_per_m = ks * ks / (ks - w2 * m) - ks + w2 * h.hand_mass_kg;
                m_h.hand_mass_kg = (ks + h.arm_stiffness_n_per_m - ks * ks / (ks - w2 * m)) / w2;
                for (const OperatorModel& candidate : {k_s, k_a, m_h}) {
                    const bool finite = std::isfinite(candidate.skin_stiffness_n_per_m) &&
                                        std::isfinite(candidate.arm_stiffness_n_per_m) &&
                                        std::isfinite(candidate.hand_mass_kg);
                    if (finite && cls_.contains(candidate)) out.push_back(candidate);
                }
                if (alias == pi) break;  // π's aliases pair up
            }
        }
        return out;
    }

    /// Members with two undamped free-handle modes put on two aliases at once, Ω_1 and Ω_2 of
    /// a frequency of the spread (a search that moves one parameter at a time never lands
    /// there: issue 27's grasp with modes at 500 and 1500 Hz). For each hand mass of the
    /// class's grid, k_s and k_a solve the two roots of det(K - ω² M) = 0:
    ///   Ω_1² + Ω_2² = k_s/m + (k_s + k_a)/m_h,   Ω_1² Ω_2² = k_s k_a/(m m_h),
    /// so (1/m + 1/m_h) k_s² - (Ω_1² + Ω_2²) k_s + m Ω_1² Ω_2² = 0 and k_a = m m_h Ω_1² Ω_2²/k_s.
    /// The dampings are the class's least (lossless modes are the sharpest).
    struct TunedMember {
        OperatorModel member;
        double theta;  ///< the frequency whose aliases hold its two modes
    };
    std::vector<TunedMember> two_mode_members() const {
        std::vector<TunedMember> out;
        const double m = device_.mass_kg;
        const double t = 1.0 / rate_hz_;
        const double pi = std::numbers::pi;
        const auto r = cls_.ranges();
        for (const double mh : {r[0].min, std::sqrt(r[0].min * r[0].max), r[0].max}) {
            for (const double theta : {pi, 2.0 * pi / 3.0, pi / 2.0, 0.3, 0.1}) {
                std::vector<double> aliases;
                for (int k = 0; k < 3; ++k) {
                    aliases.push_back((2.0 * pi * k + theta) / t);
                    if (theta < pi) aliases.push_back((2.0 * pi * (k + 1) - theta) / t);
                }
                for (std::size_t i = 0; i < aliases.size(); ++i) {
                    for (std::size_t j = i + 1; j < aliases.size(); ++j) {
                        const double w1 = aliases[i] * aliases[i], w2 = aliases[j] * aliases[j];
                        const double a = 1.0 / m + 1.0 / mh, b = w1 + w2, c = m * w1 * w2;
                        const double disc = b * b - 4.0 * a * c;
                        if (!(disc >= 0.0)) continue;
                        for (const double sign : {-1.0, 1.0}) {
                            const double ks = (b + sign * std::sqrt(disc)) / (2.0 * a);
                            if (!(ks > 0.0)) continue;
                            const OperatorModel h = OperatorModel::two_mass_grasp(
                                ks, r[2].min, mh, m * mh * w1 * w2 / ks, r[4].min);
                            if (cls_.contains(h)) out.push_back({h, theta});
                        }
                    }
                }
            }
        }
        return out;
    }

    /// Ĝ(θ) = Σ_k c_k Y(jω_k): the backward-difference velocity per unit force of the device
    /// with member h, through the hold and the delay (docs/stability-models.md, "Every passive
    /// environment"). The sum is cut at kAliasTerms each side (its terms fall as 1/k³): a
    /// search's objective, not a bound.
    theory::Complex sampled_velocity(const OperatorModel& h, double theta) const {
        const double t = 1.0 / rate_hz_;
        const theory::LoopDelay delay = theory::split_delay(delay_periods_);
        const double half = std::sin(theta / 2.0);
        theory::Complex sum{0.0, 0.0};
        for (int k = -kAliasTerms; k <= kAliasTerms; ++k) {
            const double alias = theta + 2.0 * std::numbers::pi * k;
            const theory::Complex s{0.0, alias / t};
            const theory::Complex grip = h.skin_damping_n_s_per_m + h.skin_stiffness_n_per_m / s;
            const theory::Complex hand =
                h.arm_damping_n_s_per_m + h.hand_mass_kg * s + h.arm_stiffness_n_per_m / s;
            const theory::Complex handle = h.family == OperatorFamily::hands_off
                                               ? theory::Complex{}
                                               : grip * hand / (grip + hand);
            const theory::Complex y =
                1.0 / (device_.damping_n_s_per_m + device_.mass_kg * s + handle);
            sum += 4.0 * half * half / (alias * alias) *
                   std::polar(1.0, -(1.0 + delay.whole_periods) * theta - delay.fraction * alias) *
                   y;
        }
        return sum;
    }

    /// The lossless environment worst for member h at θ (0 < θ < π): the loop has a pole at
    /// e^{jθ} iff 1/Z_c + 1/Z_e = -Ĝ, so the worst lossless 1/Z_e is the susceptance
    /// Im(-Ĝ - 1/Z_c), and Re(1/Z_c) + Re Ĝ < 0 says that one is unstable: the
    /// member-plus-environment pair (issue 27, item 2).
    std::optional<EnvironmentModel> worst_lossless_for(const OperatorModel& h, double theta) const {
        if (!(theta > 0.0 && theta < std::numbers::pi * (1.0 - 1e-9))) return std::nullopt;
        const theory::Complex coupling =
            1.0 / theory::coupling_impedance(coupling_, theta, 1.0 / rate_hz_);
        const double susceptance = (-sampled_velocity(h, theta) - coupling).imag();
        if (!(std::abs(susceptance) > 1e-12 * std::abs(coupling))) return std::nullopt;
        return lossless_environment_with_admittance(theta, rate_hz_, susceptance);
    }

    /// Compass search over the operator's coordinates, then (for every passive environment)
    /// over a lossless environment's, then the operator's again; all on the band's radius.
    void climb(ClassPoint point, const EnvironmentModel& environment, bool every_passive,
               const Band& band) {
        climb_operator(point, environment, band);
        if (!every_passive) return;
        climb_operator(point, climb_environment(cls_.member(point), band), band);
    }

    /// The lossless environment worst for `h` in `band`: the best of a 9 x 10 spread of
    /// frequencies and admittances, a compass search over both, then over its mass and
    /// spring.
    EnvironmentModel climb_environment(const OperatorModel& h, const Band& band) {
        LosslessCoordinates best;
        double radius = -2.0;
        for (int i = 0; i <= 8; ++i) {
            for (int j = 0; j <= 9; ++j) {
                const LosslessCoordinates c{i / 8.0, (j + 0.5) / 10.0};
                const double r = evaluate(h, lossless_at(c, coupling_, rate_hz_), band);
                if (r > radius) radius = r, best = c;
            }
        }
        compass_climb({&best.theta_u, &best.admittance_u}, 1.0 / 16.0, radius,
                      [&] { return evaluate(h, lossless_at(best, coupling_, rate_hz_), band); });
        return climb_masses(h, lossless_at(best, coupling_, rate_hz_), band);
    }

    /// From a lossless environment, a compass search over log m_e (1e-5..1e4 kg) and log k_e
    /// (1e-4..1e9 N/m): the corner of an almost free virtual mass that (θ, Y) reach poorly.
    EnvironmentModel climb_masses(const OperatorModel& h, const EnvironmentModel& start,
                                  const Band& band) {
        constexpr double kMassLo = 1e-5, kMassHi = 1e4, kSpringLo = 1e-4, kSpringHi = 1e9;
        const auto env_at = [&](double mu, double ku) {
            return EnvironmentModel::lossless_mass_spring(
                kMassLo * std::pow(kMassHi / kMassLo, mu),
                kSpringLo * std::pow(kSpringHi / kSpringLo, ku));
        };
        double mu = std::clamp(
            std::log(std::max(start.mass_kg, kMassLo) / kMassLo) / std::log(kMassHi / kMassLo), 0.0,
            1.0);
        double ku = std::clamp(std::log(std::max(start.stiffness_n_per_m, kSpringLo) / kSpringLo) /
                                   std::log(kSpringHi / kSpringLo),
                               0.0, 1.0);
        compass_climb({&mu, &ku}, 1.0 / 16.0, evaluate(h, env_at(mu, ku), band),
                      [&] { return evaluate(h, env_at(mu, ku), band); });
        return env_at(mu, ku);
    }

    double climb_operator(ClassPoint& point, const EnvironmentModel& environment,
                          const Band& band = kBands[0]) {
        static_assert(kClassParameters == 5, "one coordinate per class parameter");
        return compass_climb({&point[0], &point[1], &point[2], &point[3], &point[4]}, kFirstStep,
                             evaluate(cls_.member(point), environment, band), [&] {
                                 const OperatorModel h = cls_.member(point);
                                 return cls_.contains(h) ? evaluate(h, environment, band) : -1.0;
                             });
    }

    /// Compass search: each coordinate in [0, 1] in turn is moved by -step and +step and kept
    /// where `value()` rises above `best` by more than kClimbGain; the step halves from
    /// `first_step` to kLastStep when no move helps. Returns the best value; the coordinates are
    /// left at it.
    template <typename Value>
    static double compass_climb(std::initializer_list<double*> coordinates, double first_step,
                                double best, Value value) {
        // The k-th step is first_step / 2^k (exact in binary).
        for (int k = 0; std::ldexp(first_step, -k) >= kLastStep; ++k) {
            const double step = std::ldexp(first_step, -k);
            bool improved = true;
            while (improved) {
                improved = false;
                for (double* u : coordinates) {
                    for (const double sign : {-1.0, 1.0}) {
                        const double saved = *u;
                        *u = std::clamp(saved + sign * step, 0.0, 1.0);
                        const double r = value();
                        if (r > best + kClimbGain) {
                            best = r;
                            improved = true;
                        } else {
                            *u = saved;
                        }
                    }
                }
            }
        }
        return best;
    }

    static constexpr std::size_t kGridPoints = 243;  // 3^5

    struct Seed {
        double radius;
        ClassPoint point;
        EnvironmentModel environment;
    };

    /// work(job, i) for every i in [0, n), each on a fresh search of its own (nothing found,
    /// no seeds), taken in turn from one queue by as many threads as the machine has cores
    /// (a long climb does not leave the other core idle). The jobs' worst cases and seeds are
    /// merged into this search in job order, up to the first job that decided the search
    /// (kDecisiveGrowthPerTick): no job after it is started, and every job before it runs, so
    /// the result is that of one pass in order, however the threads interleave.
    template <typename Work>
    void in_parallel(std::size_t n, Work work) {
        std::vector<ClassSearch> jobs;
        jobs.reserve(n);
        for (std::size_t i = 0; i < n; ++i) {
            jobs.emplace_back(device_, coupling_, rate_hz_, cls_, delay_periods_);
        }
        std::atomic<std::size_t> next{0};
        std::atomic<std::size_t> first_decided{n};
        const auto take_jobs = [&] {
            for (std::size_t i = next.fetch_add(1); i < n && i < first_decided.load();
                 i = next.fetch_add(1)) {
                work(jobs[i], i);
                if (!jobs[i].decided()) continue;
                std::size_t seen = first_decided.load();
                while (i < seen && !first_decided.compare_exchange_weak(seen, i)) {
                }
            }
        };
        const std::size_t helpers =
            std::min<std::size_t>(std::max(1u, std::thread::hardware_concurrency()), n) - 1;
        std::vector<std::future<void>> running;
        for (std::size_t t = 0; t < helpers; ++t) {
            running.push_back(std::async(std::launch::async, take_jobs));
        }
        take_jobs();
        for (std::future<void>& f : running) f.get();
        const std::size_t merged = std::min(n, first_decided.load() + 1);
        for (std::size_t i = 0; i < merged; ++i) {
            merge(best_, jobs[i].best_);
            for (std::size_t band = 0; band < kBands.size(); ++band) {
                seeds_[band].insert(seeds_[band].end(), jobs[i].seeds_[band].begin(),
                                    jobs[i].seeds_[band].end());
            }
        }
    }

    /// One sampling of the plant for all the environments; the seed in each band is the
    /// worst environment's.
    ExactCheck seed(const OperatorModel& h, const ClassPoint& point,
                    const std::vector<EnvironmentModel>& with) {
        ExactCheck c = check_exact(device_, coupling_, rate_hz_, {h}, with, delay_periods_);
        merge(best_, c);
        const ClosedLoopPoles poles =
            closed_loop_poles(device_, coupling_, rate_hz_, h, c.worst_environment, delay_periods_);
        for (std::size_t band = 0; band < kBands.size(); ++band) {
            seeds_[band].push_back({band_radius(poles, kBands[band]), point, c.worst_environment});
        }
        return c;
    }

    /// Grid point `index` of the 3^5 grid, and the members tuned from it.
    void probe_grid_point(std::size_t index, const std::vector<EnvironmentModel>& environments) {
        ClassPoint point{};
        std::size_t rest = index;
        for (double& u : point) u = 0.5 * static_cast<double>(rest % 3), rest /= 3;
        const OperatorModel h = cls_.member(point);
        if (!cls_.contains(h)) return;
        const ExactCheck c = seed(h, point, environments);
        // Synthesis inside the class: the members that put a free-handle mode on an alias of
        // a frequency of the spread (a grid never lands on such a resonance).
        for (const OperatorModel& tuned : tuned_members(h)) {
            const ClassPoint tuned_point = cls_.point_of(tuned);
            for (const EnvironmentModel& e : {c.worst_environment, environments.front()}) {
                const ClosedLoopPoles tp =
                    closed_loop_poles(device_, coupling_, rate_hz_, tuned, e, delay_periods_);
                record(tp, tuned, e);
                for (std::size_t band = 0; band < kBands.size(); ++band) {
                    seeds_[band].push_back({band_radius(tp, kBands[band]), tuned_point, e});
                }
            }
        }
    }

    /// A member with two modes on two aliases, against every environment and (for every
    /// passive environment) the lossless one worst for it.
    void probe_two_modes(const TunedMember& tuned,
                         const std::vector<EnvironmentModel>& environments, bool every_passive) {
        std::vector<EnvironmentModel> paired = environments;
        if (every_passive) {
            if (const auto e = worst_lossless_for(tuned.member, tuned.theta)) paired.push_back(*e);
        }
        (void)seed(tuned.member, cls_.point_of(tuned.member), paired);
    }

    /// Hands-off belongs to every class: the device alone against the lossless environment
    /// worst for it, and from the best almost free virtual mass (k_e at the search's floor),
    /// the worst lossless environment for a delayed loop at low frequency (a tester's
    /// independent search found it 0.05 % inside the limits the first climb gave).
    void climb_hands_off(const Band& band) {
        const OperatorModel alone = OperatorModel::hands_off();
        (void)climb_environment(alone, band);
        EnvironmentModel free_mass;
        double radius = -2.0;
        for (int i = 0; i <= 36; ++i) {
            const EnvironmentModel e = EnvironmentModel::lossless_mass_spring(
                1e-3 * device_.mass_kg * std::pow(10.0, i / 6.0), 1e-4);
            const double r = evaluate(alone, e, band);
            if (r > radius) radius = r, free_mass = e;
        }
        (void)climb_masses(alone, free_mass, band);
    }

    DeviceModel device_;
    SpringDamperCoupling coupling_;
    double rate_hz_;
    OperatorClass cls_;
    double delay_periods_;
    ExactCheck best_;
    std::array<std::vector<Seed>, kBands.size()> seeds_;
};

}  // namespace

std::string StabilityAssumption::describe() const {
    const std::string who = operators
                                ? "the declared operator class (" + operators->describe() + ")"
                                : std::string("every passive operator");
    return who + " and " + environments.describe();
}

ExactCheck check_exact(const DeviceModel& device, const SpringDamperCoupling& coupling,
                       double rate_hz, const StabilityAssumption& assumption, double delay_periods,
                       SearchFor search) {
    const bool every_environment = assumption.environments.every_passive();
    if (!assumption.operators && every_environment) {
        return check_exact(device, coupling, rate_hz, delay_periods, search);
    }
    check_device(device);
    check_rate(rate_hz);
    check_coupling_gains(coupling);
    check_delay_periods(delay_periods);
    const std::vector<EnvironmentModel> scene = models_of(assumption.environments.scene);
    if (!assumption.operators) {
        // Every passive operator against the scene: the alias-tuned operators built for each
        // of the scene's environments, and the default operators.
        ExactCheck tuned =
            check_exact(device, coupling, rate_hz,
                        synthesize_scene_adversaries(device, coupling, rate_hz,
                                                     assumption.environments.scene, delay_periods),
                        scene, delay_periods);
        if (search == SearchFor::witness && decisive(tuned)) return tuned;
        ExactCheck check =
            check_exact(device, coupling, rate_hz, default_operator_sweep(device, rate_hz), scene,
                        delay_periods);
        merge(check, tuned);
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
    ClassSearch class_search(device, coupling, rate_hz, *assumption.operators, delay_periods);
    return class_search.run(environments, every_environment);
}

StiffnessLimit exact_stiffness_limit(const DeviceModel& device, const SpringDamperCoupling& shape,
                                     double rate_hz, const StabilityAssumption& assumption,
                                     double delay_periods, double tolerance) {
    if (!(tolerance > 0.0 && tolerance < 1.0)) {
        throw std::invalid_argument("exact_stiffness_limit: tolerance must be in (0, 1)");
    }
    StiffnessLimit limit;
    // The worst cases of the rejections so far: a design above the limit usually fails on
    // one of them, which spares the whole search (a rejection needs one unstable case; an
    // acceptance always runs the whole check).
    std::vector<std::pair<OperatorModel, EnvironmentModel>> witnesses;
    const auto check = [&](double stiffness) {
        SpringDamperCoupling coupling = shape;
        coupling.stiffness_n_per_m = stiffness;
        for (const auto& [human, environment] : witnesses) {
            ExactCheck quick =
                check_exact(device, coupling, rate_hz, {human}, {environment}, delay_periods);
            if (!quick.stable) return quick;
        }
        ++limit.checks;
        ExactCheck full =
            check_exact(device, coupling, rate_hz, assumption, delay_periods, SearchFor::witness);
        if (!full.stable) witnesses.emplace_back(full.worst_operator, full.worst_environment);
        return full;
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
