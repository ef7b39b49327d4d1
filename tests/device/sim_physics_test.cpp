// The simulated device's physics: exact ZOH integration against closed forms and an
// independent RK4 reference, the operator families against hapticd::tune's exact model,
// passivity, quantisation, determinism, Coulomb friction and the push profile.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "hapticd/device/sim/axis_plant.hpp"
#include "hapticd/device/sim/sim_device.hpp"
#include "hapticd/tune/exact_model.hpp"

namespace hapticd::device::sim {
namespace {

SimConfig lockstep_config(int axes = 1) {
    SimConfig c;
    c.axes = axes;
    c.rate_hz = 1000.0;
    c.mass_kg = 0.1;
    c.damping_n_s_per_m = 2.0;
    c.counts_per_meter = 1e5;
    c.force_limit_n = 20.0;
    c.clock = SimClock::lockstep;
    return c;
}

HumanModel heavy_hand(double mh, double bh) {
    HumanModel h;
    h.family = HumanFamily::heavy_hand;
    h.hand_mass_kg = mh;
    h.hand_damping_n_s_per_m = bh;
    return h;
}

HumanModel stiff_grasp(double mh, double kh, double bh, double set_point_m = 0.0) {
    HumanModel h = heavy_hand(mh, bh);
    h.family = HumanFamily::stiff_grasp;
    h.hand_stiffness_n_per_m = kh;
    h.push.from_m = h.push.to_m = set_point_m;
    return h;
}

HumanModel two_mass(double ks, double bs, double mh, double ka, double ba,
                    double set_point_m = 0.0) {
    HumanModel h;
    h.family = HumanFamily::two_mass_grasp;
    h.skin_stiffness_n_per_m = ks;
    h.skin_damping_n_s_per_m = bs;
    h.hand_mass_kg = mh;
    h.arm_stiffness_n_per_m = ka;
    h.arm_damping_n_s_per_m = ba;
    h.push.from_m = h.push.to_m = set_point_m;
    return h;
}

/// A multi-mode grasp: a hand of mass mh on the handle, k_h and b_h to the set-point, and the
/// absorbers (mass, stiffness, damping).
HumanModel multi_mode(double mh, double kh, double bh, const std::vector<OperatorMode>& modes) {
    HumanModel h = stiff_grasp(mh, kh, bh);
    h.family = HumanFamily::multi_mode_grasp;
    for (const OperatorMode& mode : modes) h.modes[static_cast<std::size_t>(h.mode_count++)] = mode;
    return h;
}

/// Three absorbers on a 0.2 kg hand: 80 Hz, 400 Hz (lightly damped) and 2 kHz, above Nyquist.
HumanModel three_absorbers() {
    return multi_mode(0.2, 800.0, 1.5,
                      {{0.05, 0.05 * std::pow(2 * std::numbers::pi * 80, 2), 0.2},
                       {0.01, 0.01 * std::pow(2 * std::numbers::pi * 400, 2), 0.01},
                       {0.002, 0.002 * std::pow(2 * std::numbers::pi * 2000, 2), 0.0}});
}

Command force(double f0, double f1 = 0.0, double f2 = 0.0) {
    Command c;
    c.enable = true;
    c.force_n = {f0, f1, f2};
    return c;
}

// ---------------------------------------------------------------------------------------
// Exact integration

// (10) hands-off under a constant held force F from rest at x0:
//   v(t) = (F/b)(1 - e^{-t/τ}),  x(t) = x0 + (F/b)(t - τ(1 - e^{-t/τ})),  τ = m/b.
TEST(SimPhysics, MassDamperUnderHeldForceMatchesClosedForm) {
    SimConfig c = lockstep_config();
    c.initial_position_m[0] = 0.01;
    SimDevice dev;
    dev.open(c);
    const double m = c.mass_kg, b = c.damping_n_s_per_m, F = 1.5, tau = m / b, x0 = 0.01;
    for (int n = 1; n <= 3000; ++n) {
        ASSERT_EQ(dev.write(force(F)), IoResult::ok);
        const double t = n * 1e-3;
        const double decay = -std::expm1(-t / tau);  // 1 - e^{-t/τ}, accurately
        const double v = F / b * decay;
        const double x = x0 + F / b * (t - tau * decay);
        const auto& s = dev.plant(0).state();
        ASSERT_NEAR(s.velocity_mps, v, 1e-12 * std::abs(F / b)) << "tick " << n;
        ASSERT_NEAR(s.position_m, x, 1e-12 * std::abs(x)) << "tick " << n;
    }
    EXPECT_DOUBLE_EQ(dev.time_s(), 3.0);
}

// A stiff grasp (m_h on the handle, k_h, b_h to a fixed set-point) released from an offset
// oscillates freely: e(t) = e0 e^{-αt} (cos ω_d t + (α/ω_d) sin ω_d t), with M = m + m_h,
// α = (b + b_h)/(2M), ω_0² = k_h/M, ω_d² = ω_0² - α².
TEST(SimPhysics, StiffGraspFreeOscillationMatchesClosedForm) {
    SimConfig c = lockstep_config();
    const double x_s = 0.002, e0 = 0.005;
    c.initial_position_m[0] = x_s + e0;
    c.human[0] = stiff_grasp(0.4, 2000.0, 1.0, x_s);
    SimDevice dev;
    dev.open(c);
    const double M = 0.5, alpha = (2.0 + 1.0) / (2 * M), w0 = std::sqrt(2000.0 / M);
    const double wd = std::sqrt(w0 * w0 - alpha * alpha);
    for (int n = 1; n <= 2000; ++n) {
        ASSERT_EQ(dev.write(force(0.0)), IoResult::ok);
        const double t = n * 1e-3;
        const double env = std::exp(-alpha * t);
        const double e = e0 * env * (std::cos(wd * t) + alpha / wd * std::sin(wd * t));
        const double v = -e0 * w0 * w0 / wd * env * std::sin(wd * t);
        const auto& s = dev.plant(0).state();
        ASSERT_NEAR(s.position_m - x_s, e, 1e-12 * e0) << "tick " << n;
        ASSERT_NEAR(s.velocity_mps, v, 1e-12 * e0 * w0) << "tick " << n;
    }
}

// An independent reference: RK4 on the equations of axis_plant.hpp, with the set-point
// moving linearly within each period, many substeps per period.
struct Rk4Reference {
    double m, b;
    HumanModel h;
    std::vector<double> s;  // x, v, then each operator mass's position and velocity

    std::vector<double> derivative(const std::vector<double>& y, double f, double xs,
                                   double vs) const {
        const double x = y[0], v = y[1];
        std::vector<double> d(y.size(), 0.0);
        d[0] = v;
        switch (h.family) {
            case HumanFamily::hands_off:
                d[1] = (f - b * v) / m;
                break;
            case HumanFamily::heavy_hand:
                d[1] = (f - (b + h.hand_damping_n_s_per_m) * v) / (m + h.hand_mass_kg);
                break;
            case HumanFamily::stiff_grasp:
                d[1] = (f - b * v - h.hand_damping_n_s_per_m * (v - vs) -
                        h.hand_stiffness_n_per_m * (x - xs)) /
                       (m + h.hand_mass_kg);
                break;
            case HumanFamily::two_mass_grasp: {
                const double xh = y[2], vh = y[3];
                const double skin =
                    h.skin_stiffness_n_per_m * (x - xh) + h.skin_damping_n_s_per_m * (v - vh);
                const double arm =
                    h.arm_stiffness_n_per_m * (xh - xs) + h.arm_damping_n_s_per_m * (vh - vs);
                d[1] = (f - b * v - skin) / m;
                d[2] = vh;
                d[3] = (skin - arm) / h.hand_mass_kg;
                break;
            }
            case HumanFamily::multi_mode_grasp: {
                double on_handle = f - b * v - h.hand_damping_n_s_per_m * (v - vs) -
                                   h.hand_stiffness_n_per_m * (x - xs);
                for (int i = 0; i < h.mode_count; ++i) {
                    const OperatorMode& mode = h.modes[static_cast<std::size_t>(i)];
                    const double xi = y[2 + 2 * i], vi = y[3 + 2 * i];
                    const double spring =
                        mode.stiffness_n_per_m * (x - xi) + mode.damping_n_s_per_m * (v - vi);
                    on_handle -= spring;
                    d[2 + 2 * i] = vi;
                    d[3 + 2 * i] = spring / mode.mass_kg;
                }
                d[1] = on_handle / (m + h.hand_mass_kg);
                break;
            }
        }
        return d;
    }
    void period(double T, double f, double xs0, double xs1, int substeps) {
        const double h_s = T / substeps, vs = (xs1 - xs0) / T;
        for (int i = 0; i < substeps; ++i) {
            const double t0 = i * h_s;
            auto add = [](const std::vector<double>& a, const std::vector<double>& d, double k) {
                std::vector<double> out(a.size());
                for (std::size_t j = 0; j < a.size(); ++j) out[j] = a[j] + k * d[j];
                return out;
            };
            const auto k1 = derivative(s, f, xs0 + vs * t0, vs);
            const auto k2 = derivative(add(s, k1, h_s / 2), f, xs0 + vs * (t0 + h_s / 2), vs);
            const auto k3 = derivative(add(s, k2, h_s / 2), f, xs0 + vs * (t0 + h_s / 2), vs);
            const auto k4 = derivative(add(s, k3, h_s), f, xs0 + vs * (t0 + h_s), vs);
            for (std::size_t j = 0; j < s.size(); ++j) {
                s[j] += h_s / 6 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
            }
        }
    }
};

/// The operator's own masses of `human`: the two-mass grasp's hand, or the absorbers.
int operator_masses(const HumanModel& human) {
    if (human.family == HumanFamily::two_mass_grasp) return 1;
    return human.family == HumanFamily::multi_mode_grasp ? human.mode_count : 0;
}

void expect_matches_rk4(const HumanModel& human) {
    SimConfig c = lockstep_config();
    c.initial_position_m[0] = 0.003;
    c.human[0] = human;
    SimDevice dev;
    dev.open(c);
    const int masses = operator_masses(human);
    std::vector<double> start{0.003, 0.0};
    for (int i = 0; i < masses; ++i) start.insert(start.end(), {0.003, 0.0});
    Rk4Reference ref{c.mass_kg, c.damping_n_s_per_m, human, start};
    ASSERT_EQ(dev.plant(0).states(), 2 + 2 * masses);
    double scale = 1e-3;
    for (int n = 0; n < 400; ++n) {
        const double f = 2.0 * std::sin(0.05 * n) + (n % 7 == 0 ? 1.0 : 0.0);
        // The sim's clock: the double nearest n / rate (sim_device.cpp, units_to_s).
        const double t0 = n / 1000.0, t1 = (n + 1) / 1000.0;
        // The absorber at 2 kHz needs finer steps for RK4 to stay within 1e-9 of the truth.
        ref.period(1e-3, f, human.push.set_point_m(t0), human.push.set_point_m(t1),
                   masses > 1 ? 1000 : 200);
        ASSERT_EQ(dev.write(force(f)), IoResult::ok);
        const auto& s = dev.plant(0).state();
        for (std::size_t j = 0; j <= static_cast<std::size_t>(masses); ++j) {
            scale = std::max(scale, std::abs(ref.s[2 * j]));
        }
        ASSERT_NEAR(s.position_m, ref.s[0], 1e-9 * scale) << human.push.to_m << " tick " << n;
        ASSERT_NEAR(s.velocity_mps, ref.s[1], 1e-7 * (1 + std::abs(ref.s[1]))) << "tick " << n;
        for (int i = 0; i < masses; ++i) {
            const auto k = static_cast<std::size_t>(i);
            const double xi = ref.s[2 + 2 * k], vi = ref.s[3 + 2 * k];
            ASSERT_NEAR(s.mass_position_m[k], xi, 1e-9 * scale) << "mass " << i << " tick " << n;
            ASSERT_NEAR(s.mass_velocity_mps[k], vi, 1e-7 * (1 + std::abs(vi)))
                << "mass " << i << " tick " << n;
        }
        ASSERT_DOUBLE_EQ(s.set_point_m, human.push.set_point_m(t1));
    }
}

TEST(SimPhysics, EveryOperatorFamilyMatchesAnIndependentRk4Reference) {
    expect_matches_rk4(HumanModel{});
    expect_matches_rk4(heavy_hand(0.3, 1.5));
    expect_matches_rk4(stiff_grasp(0.3, 800.0, 2.0, 0.001));
    expect_matches_rk4(two_mass(3000.0, 5.0, 0.4, 300.0, 8.0, -0.001));
    HumanModel pushing = stiff_grasp(0.3, 800.0, 2.0);
    pushing.push = PushProfile{0.003, 0.013, 0.05, 0.1, 0.1};
    expect_matches_rk4(pushing);
    HumanModel arm_push = two_mass(3000.0, 5.0, 0.4, 300.0, 8.0);
    arm_push.push = PushProfile{0.003, -0.007, 0.02, 0.15, 0.05};
    expect_matches_rk4(arm_push);
    expect_matches_rk4(three_absorbers());
    HumanModel absorbers_pushed = three_absorbers();
    absorbers_pushed.push = PushProfile{0.003, 0.009, 0.04, 0.1, 0.05};
    expect_matches_rk4(absorbers_pushed);
}

// ---------------------------------------------------------------------------------------
// The operator families are those of hapticd::tune's exact model: close the loop of the
// sim's own one-period transition with the coupling (16) against a rigid wall and compare
// the spectral radius with tune::closed_loop_poles for the same operator.

double sim_closed_loop_spectral_radius(const HumanModel& human, double kc, double bc) {
    AxisPlant plant;
    const double T = 1e-3;
    plant.configure(0.1, 2.0, 0.0, human, T, 0.0);
    const Eigen::MatrixXd e = plant.period_transition();
    const int n = plant.states();
    // z = (s, x_d[n-1]); f on the handle = -F, F = k_c x + b_c (x - x_prev)/T.
    Eigen::MatrixXd loop = Eigen::MatrixXd::Zero(n + 1, n + 1);
    loop.topLeftCorner(n, n) = e.topLeftCorner(n, n);
    const Eigen::VectorXd gamma = e.block(0, n, n, 1);  // column of f
    loop.topLeftCorner(n, 1) += gamma * -(kc + bc / T);
    loop.topRightCorner(n, 1) = gamma * (bc / T);
    loop(n, 0) = 1.0;
    return loop.eigenvalues().cwiseAbs().maxCoeff();
}

tune::OperatorModel as_tune(const HumanModel& h) {
    switch (h.family) {
        case HumanFamily::hands_off:
            return tune::OperatorModel::hands_off();
        case HumanFamily::heavy_hand:
            return tune::OperatorModel::heavy_hand(h.hand_mass_kg, h.hand_damping_n_s_per_m);
        case HumanFamily::stiff_grasp:
            return tune::OperatorModel::stiff_grasp(h.hand_mass_kg, h.hand_stiffness_n_per_m,
                                                    h.hand_damping_n_s_per_m);
        case HumanFamily::two_mass_grasp:
            return tune::OperatorModel::two_mass_grasp(
                h.skin_stiffness_n_per_m, h.skin_damping_n_s_per_m, h.hand_mass_kg,
                h.arm_stiffness_n_per_m, h.arm_damping_n_s_per_m);
        case HumanFamily::multi_mode_grasp: {
            std::vector<tune::OperatorMode> modes;
            for (int i = 0; i < h.mode_count; ++i) {
                const OperatorMode& m = h.modes[static_cast<std::size_t>(i)];
                modes.push_back({m.mass_kg, m.stiffness_n_per_m, m.damping_n_s_per_m});
            }
            return tune::OperatorModel::multi_mode(h.hand_mass_kg, h.hand_stiffness_n_per_m,
                                                   h.hand_damping_n_s_per_m, modes, "test");
        }
    }
    return {};
}

TEST(SimPhysics, OperatorFamiliesMatchTheExactModel) {
    const std::vector<HumanModel> humans{HumanModel{},
                                         heavy_hand(1.0, 0.0),
                                         heavy_hand(0.2, 3.0),
                                         stiff_grasp(0.5, 1000.0, 1.0),
                                         stiff_grasp(0.0, 4e5, 0.0),
                                         two_mass(1e4, 1.0, 0.5, 1e3, 10.0),
                                         three_absorbers(),
                                         multi_mode(0.0, 0.0, 0.0, {{0.3, 1e6, 0.0}})};
    for (const auto& human : humans) {
        for (const auto& [kc, bc] : {std::pair{1000.0, 0.0}, {3600.0, 0.5}, {9000.0, 0.0}}) {
            const auto poles = tune::closed_loop_poles({0.1, 2.0}, {kc, bc}, 1000.0, as_tune(human),
                                                       tune::EnvironmentModel::rigid_wall());
            EXPECT_NEAR(sim_closed_loop_spectral_radius(human, kc, bc), poles.spectral_radius, 1e-9)
                << as_tune(human).describe() << " k_c = " << kc << " b_c = " << bc;
        }
    }
}

// ---------------------------------------------------------------------------------------
// Passivity: with zero force and a fixed set-point, the mechanical energy never increases.

void expect_energy_never_increases(const HumanModel& human, double coulomb_n) {
    SCOPED_TRACE(testing::Message() << "family " << static_cast<int>(human.family)
                                    << ", m_h = " << human.hand_mass_kg << ", F_c = " << coulomb_n);
    SimConfig c = lockstep_config();
    c.coulomb_n = coulomb_n;
    c.human[0] = human;
    c.initial_position_m[0] = 0.0;
    SimDevice dev;
    dev.open(c);
    AxisPlant::State kick = dev.plant(0).state();
    kick.velocity_mps = 0.3;
    kick.position_m = 0.004;
    for (int i = 0; i < operator_masses(human); ++i) {
        kick.mass_position_m[static_cast<std::size_t>(i)] = -0.002 * (i + 1);
    }
    const_cast<AxisPlant&>(dev.plant(0)).set_state(kick);
    const double initial_j = dev.plant(0).energy_j();
    double energy = initial_j;
    ASSERT_GT(energy, 0.0);
    for (int n = 0; n < 5000; ++n) {
        ASSERT_EQ(dev.write(force(0.0)), IoResult::ok);
        const double next = dev.plant(0).energy_j();
        ASSERT_LE(next, energy * (1 + 1e-12) + 1e-300) << "tick " << n;
        energy = next;
    }
    EXPECT_LT(energy, 0.9 * initial_j);  // the device's damping b did dissipate
}

TEST(SimPhysics, EnergyNeverIncreasesWithPassiveOperatorsAndZeroForce) {
    for (double coulomb : {0.0, 0.2}) {
        expect_energy_never_increases(HumanModel{}, coulomb);
        expect_energy_never_increases(heavy_hand(0.5, 0.0), coulomb);
        expect_energy_never_increases(stiff_grasp(0.5, 3000.0, 0.0), coulomb);
        expect_energy_never_increases(stiff_grasp(0.0, 5e5, 0.0), coulomb);
        expect_energy_never_increases(two_mass(1e4, 0.0, 0.5, 1e3, 0.0), coulomb);
        expect_energy_never_increases(three_absorbers(), coulomb);
    }
}

// ---------------------------------------------------------------------------------------
// Encoder, determinism, force handling

TEST(SimPhysics, EncoderCountsAreFloorOfPositionTimesResolution) {
    SimConfig c = lockstep_config(3);
    c.counts_per_meter = 1e5;
    c.initial_position_m = {0.0123456, -0.0000123, -0.02};
    SimDevice dev;
    dev.open(c);
    Sample s;
    ASSERT_EQ(dev.read(s), IoResult::ok);
    EXPECT_EQ(s.encoder_counts[0], 1234);  // floor(1234.56)
    EXPECT_EQ(s.encoder_counts[1], -2);    // floor(-1.23)
    EXPECT_EQ(s.encoder_counts[2], static_cast<std::int64_t>(std::floor(-0.02 * 1e5)));
    EXPECT_EQ(s.sequence, 0u);
    EXPECT_EQ(s.device_time_s, 0.0);
    // As the handle moves, the counts follow floor(x cpm) exactly.
    for (int n = 1; n <= 200; ++n) {
        dev.write(force(1.0, -1.0, 0.5));
        ASSERT_EQ(dev.read(s), IoResult::ok);
        EXPECT_EQ(s.sequence, static_cast<std::uint64_t>(n));
        EXPECT_EQ(s.device_time_s, n / 1000.0);
        for (int i = 0; i < 3; ++i) {
            ASSERT_EQ(s.encoder_counts[i],
                      static_cast<std::int64_t>(std::floor(dev.plant(i).state().position_m * 1e5)));
        }
    }
}

TEST(SimPhysics, LockstepRunsAreBitIdentical) {
    SimConfig c = lockstep_config(3);
    c.human = {stiff_grasp(0.3, 500.0, 1.0), two_mass(5e3, 1.0, 0.3, 200.0, 5.0),
               heavy_hand(1.0, 1.0)};
    c.coulomb_n = 0.05;
    c.faults.drop_probability = 0.05;
    c.faults.late_probability = 0.05;
    c.faults.seed = 1234;
    auto run = [&c] {
        SimDevice dev;
        dev.open(c);
        std::vector<Sample> samples;
        Sample s;
        for (int n = 0; n < 2000; ++n) {
            dev.read(s);
            samples.push_back(s);
            dev.write(
                force(3.0 * std::sin(0.01 * n), std::cos(0.03 * n), n % 50 < 25 ? 2.0 : -2.0));
        }
        return samples;
    };
    const auto a = run(), b = run();
    ASSERT_EQ(a.size(), b.size());
    bool moved = false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i].encoder_counts, b[i].encoder_counts) << i;
        ASSERT_EQ(a[i].status, b[i].status) << i;
        ASSERT_EQ(a[i].sequence, b[i].sequence) << i;
        ASSERT_EQ(a[i].device_time_s, b[i].device_time_s) << i;
        moved = moved || a[i].encoder_counts != a[0].encoder_counts;
    }
    EXPECT_TRUE(moved);
}

TEST(SimPhysics, ForceIsClampedDisabledOrRefused) {
    SimConfig c = lockstep_config(2);
    c.force_limit_n = 5.0;
    SimDevice dev;
    dev.open(c);
    EXPECT_EQ(dev.write(force(12.0, -7.0)), IoResult::ok);
    EXPECT_EQ(dev.held_force_n()[0], 5.0);
    EXPECT_EQ(dev.held_force_n()[1], -5.0);
    Command off = force(3.0, 3.0);
    off.enable = false;
    EXPECT_EQ(dev.write(off), IoResult::ok);
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
    EXPECT_EQ(dev.write(force(std::nan(""), 1.0)), IoResult::error);
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
    EXPECT_EQ(dev.held_force_n()[1], 0.0);
    dev.write(force(2.0, 2.0));
    dev.close();
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
    EXPECT_EQ(dev.held_force_n()[1], 0.0);
    Sample s;
    EXPECT_EQ(dev.read(s), IoResult::disconnected);
    EXPECT_EQ(dev.write(force(1.0)), IoResult::disconnected);
}

TEST(SimPhysics, InfoDescribesTheClock) {
    SimConfig c = lockstep_config(2);
    SimDevice dev;
    dev.open(c);
    DeviceInfo info = dev.info();
    EXPECT_EQ(info.axes, 2);
    EXPECT_EQ(info.name, "sim");
    EXPECT_TRUE(info.paces_loop);
    EXPECT_TRUE(info.lockstep);
    EXPECT_EQ(info.counts_per_meter, 1e5);
    EXPECT_EQ(info.force_limit_n, 20.0);
    c.clock = SimClock::realtime;
    dev.open(c);
    info = dev.info();
    EXPECT_FALSE(info.paces_loop);
    EXPECT_FALSE(info.lockstep);
}

// ---------------------------------------------------------------------------------------
// Coulomb friction

// Breakaway: with F > F_c from rest the handle moves as (10) under F - F_c, exactly.
TEST(SimPhysics, CoulombSlidingIsTheMassDamperUnderTheReducedForce) {
    SimConfig c = lockstep_config();
    c.coulomb_n = 1.0;
    SimDevice dev;
    dev.open(c);
    const double m = 0.1, b = 2.0, F = 3.0 - 1.0, tau = m / b;
    for (int n = 1; n <= 500; ++n) {
        dev.write(force(3.0));
        const double t = n * 1e-3, decay = -std::expm1(-t / tau);
        ASSERT_NEAR(dev.plant(0).state().position_m, F / b * (t - tau * decay), 1e-11 * F / b * t);
    }
}

TEST(SimPhysics, CoulombStictionHoldsBelowBreakaway) {
    SimConfig c = lockstep_config();
    c.coulomb_n = 1.0;
    c.human[0] = heavy_hand(0.5, 1.0);
    c.initial_position_m[0] = 0.01;
    SimDevice dev;
    dev.open(c);
    for (int n = 0; n < 500; ++n) dev.write(force(n % 2 ? 0.9 : -0.9));
    EXPECT_EQ(dev.plant(0).state().position_m, 0.01);
    EXPECT_EQ(dev.plant(0).state().velocity_mps, 0.0);
}

// A free handle (b = 0) launched at v0 decelerates at F_c/m and stops after m v0²/(2 F_c).
TEST(SimPhysics, CoulombStopsAFreeHandleAndDoesNotReverseIt) {
    SimConfig c = lockstep_config();
    c.coulomb_n = 0.5;
    c.damping_n_s_per_m = 0.0;
    SimDevice dev;
    dev.open(c);
    AxisPlant::State s = dev.plant(0).state();
    s.velocity_mps = 0.2;
    const_cast<AxisPlant&>(dev.plant(0)).set_state(s);
    for (int n = 0; n < 100; ++n) dev.write(force(0.0));  // stops at t = 0.04 s
    EXPECT_EQ(dev.plant(0).state().velocity_mps, 0.0);
    EXPECT_NEAR(dev.plant(0).state().position_m, 0.1 * 0.2 * 0.2 / (2 * 0.5), 1e-6);
}

// ---------------------------------------------------------------------------------------
// Push profile

TEST(SimPhysics, PushProfileIsATrapezoid) {
    const PushProfile p{0.001, 0.011, 0.5, 0.2, 1.0};
    EXPECT_EQ(p.set_point_m(0.0), 0.001);
    EXPECT_EQ(p.set_point_m(0.5), 0.001);
    EXPECT_NEAR(p.set_point_m(0.6), 0.006, 1e-15);
    EXPECT_NEAR(p.set_point_m(0.7), 0.011, 1e-15);
    EXPECT_EQ(p.set_point_m(1.6), 0.011);
    EXPECT_NEAR(p.set_point_m(1.8), 0.006, 1e-15);
    EXPECT_NEAR(p.set_point_m(1.9), 0.001, 1e-15);
    EXPECT_EQ(p.set_point_m(100.0), 0.001);
    EXPECT_TRUE(PushProfile{}.is_fixed());
}

TEST(SimPhysics, StiffGraspFollowsItsPushProfile) {
    SimConfig c = lockstep_config();
    c.human[0] = stiff_grasp(0.5, 2000.0, 40.0);
    c.human[0].push = PushProfile{0.0, 0.02, 0.1, 0.3, 0.5};
    SimDevice dev;
    dev.open(c);
    Sample s;
    for (int n = 0; n < 800; ++n) dev.write(force(0.0));  // t = 0.8 s, in the hold
    dev.read(s);
    EXPECT_NEAR(s.encoder_counts[0], 0.02 * 1e5, 3);
    EXPECT_EQ(dev.plant(0).state().set_point_m, 0.02);
    for (int n = 0; n < 1000; ++n) dev.write(force(0.0));  // t = 1.8 s, back at the start
    dev.read(s);
    EXPECT_NEAR(s.encoder_counts[0], 0.0, 3);
}

}  // namespace
}  // namespace hapticd::device::sim
