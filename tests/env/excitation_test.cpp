// The excitation of hapticd --identify: the multisine's spectrum, crest factor and swing
// (excitation_signal.hpp), and the environment that plays it: the envelope, the force
// limit, the workspace rule, the still wait, and no allocation in the tick (excitation.hpp).
#include "hapticd/env/excitation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <iostream>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "alloc_guard.hpp"

namespace hapticd::env {
namespace {

constexpr double kPi = std::numbers::pi;

// The pen display of the paper (m = 0.1 kg, b = 2 N s/m, 1 kHz) with the band the daemon
// chooses for it: half its corner b/(2π m) = 3.18 Hz to ten times it.
constexpr double kMass = 0.1;
constexpr double kDamping = 2.0;

MultisineSettings pen_signal(int axes = 1) {
    const double corner_hz = kDamping / (2.0 * kPi * kMass);
    MultisineSettings s;
    s.sample_rate_hz = 1000.0;
    s.axes = axes;
    s.band_low_hz = corner_hz / 2.0;
    s.band_high_hz = 10.0 * corner_hz;
    s.period_s = 4.0 / s.band_low_hz;
    s.lines_per_decade = 10.0;
    s.peak_force_n = 0.75;
    return s;
}

ExcitationSettings pen_excitation(int axes = 1) {
    ExcitationSettings s;
    s.signal = pen_signal(axes);
    s.periods = 3;
    s.fade_s = 1.0;
    s.workspace_half_width_m = 0.03;
    s.force_limit_n = 20.0;
    return s;
}

/// One DFT bin of x[0..L) at harmonic h: (2/L) sum x[n] e^{-j 2π h n / L}, i.e. A e^{jφ}
/// for a line A cos(2π h n / L + φ).
std::complex<double> line_of(const std::vector<double>& x, int harmonic) {
    const auto length = static_cast<std::int64_t>(x.size());
    std::complex<double> sum = 0.0;
    for (std::int64_t n = 0; n < length; ++n) {
        const double angle =
            -2.0 * kPi * static_cast<double>((harmonic * n) % length) / static_cast<double>(length);
        sum += x[static_cast<std::size_t>(n)] * std::polar(1.0, angle);
    }
    return 2.0 * sum / static_cast<double>(length);
}

/// The environment's forces on `axis` over whole periods: samples F .. F + K L.
std::vector<double> full_periods(const ExcitationEnvironment& e, int axis) {
    std::vector<double> x;
    const std::int64_t begin = e.fade_samples();
    const std::int64_t end = e.samples() - e.fade_samples();
    for (std::int64_t j = begin; j < end; ++j) x.push_back(e.scheduled_force_n(j)[axis]);
    return x;
}

TEST(EnvExcitation, LinesAreAQuasiLogGridInsideTheBand) {
    const Multisine signal(pen_signal());
    const std::vector<MultisineLine>& lines = signal.lines(0);
    std::cout << "[excitation] pen display, 1 axis: " << lines.size() << " lines:";
    for (const MultisineLine& line : lines) std::cout << " " << line.frequency_hz;
    std::cout << " Hz; period " << signal.period_s() << " s\n";
    ASSERT_GE(lines.size(), 10u);
    const MultisineSettings& s = signal.settings();
    EXPECT_GE(lines.front().frequency_hz, s.band_low_hz * (1.0 - 1e-3));  // a tick's rounding
    EXPECT_LE(lines.back().frequency_hz, s.band_high_hz);
    for (std::size_t i = 0; i < lines.size(); ++i) {
        EXPECT_NEAR(lines[i].frequency_hz, lines[i].harmonic / signal.period_s(), 1e-12);
        if (i == 0) continue;
        // Each step is one harmonic or the decade's ratio 10^(1/10) = 1.26, rounded.
        const double ratio = static_cast<double>(lines[i].harmonic) / lines[i - 1].harmonic;
        EXPECT_TRUE(lines[i].harmonic == lines[i - 1].harmonic + 1 || ratio < 1.26 * 1.1)
            << "line " << i;
    }
    // Below and above the corner (3.18 Hz) alike: 10 lines per decade, either side.
    const auto below = std::count_if(lines.begin(), lines.end(),
                                     [](const MultisineLine& l) { return l.frequency_hz < 3.18; });
    EXPECT_GE(below, 3);
    EXPECT_GE(static_cast<long>(lines.size()) - below, 9);
}

TEST(EnvExcitation, SpectrumIsTheLinesAndNothingElse) {
    const ExcitationEnvironment e(pen_excitation());
    const std::vector<double> x = full_periods(e, 0);
    const auto period = static_cast<std::int64_t>(e.signal().period_samples());
    ASSERT_EQ(static_cast<std::int64_t>(x.size()), 3 * period);
    const std::vector<MultisineLine>& lines = e.signal().lines(0);
    std::set<int> excited;
    double line_power = 0.0;
    for (const MultisineLine& line : lines) {
        // Three periods: the line is harmonic 3 h of the record.
        const std::complex<double> measured = line_of(x, 3 * line.harmonic);
        EXPECT_NEAR(std::abs(measured), line.amplitude_n, 1e-9 * line.amplitude_n);
        EXPECT_NEAR(std::remainder(std::arg(measured) - line.phase_rad, 2.0 * kPi), 0.0, 1e-9);
        excited.insert(3 * line.harmonic);
        line_power += 0.5 * line.amplitude_n * line.amplitude_n;
    }
    // Parseval: the mean square is the lines' power, so every other bin is empty.
    double mean_square = 0.0;
    for (const double u : x) mean_square += u * u / static_cast<double>(x.size());
    const double off_line_fraction = std::abs(mean_square - line_power) / mean_square;
    std::cout << "[excitation] power off the " << lines.size()
              << " lines (3 periods): " << off_line_fraction << " of the total\n";
    EXPECT_LT(off_line_fraction, 1e-12);
    // And by value at bins next to the lines, and between periods (no leakage).
    for (const int bin : {1, 2, 3 * lines.front().harmonic - 1, 3 * lines.front().harmonic + 1,
                          3 * lines.back().harmonic + 3}) {
        ASSERT_EQ(excited.count(bin), 0u);
        EXPECT_LT(std::abs(line_of(x, bin)), 1e-12) << "bin " << bin;
    }
    // The mean (bin 0) is zero: no drift from the signal itself.
    double mean = 0.0;
    for (const double u : x) mean += u / static_cast<double>(x.size());
    EXPECT_LT(std::abs(mean), 1e-12);
}

TEST(EnvExcitation, AxesGetDisjointLinesSoTheirSignalsAreOrthogonal) {
    const ExcitationEnvironment e(pen_excitation(3));
    std::vector<std::vector<double>> x;
    x.reserve(3);
    for (int axis = 0; axis < 3; ++axis) x.push_back(full_periods(e, axis));
    std::set<int> seen;
    for (int axis = 0; axis < 3; ++axis) {
        EXPECT_GE(e.signal().lines(axis).size(), 10u);
        for (const MultisineLine& line : e.signal().lines(axis)) {
            EXPECT_TRUE(seen.insert(line.harmonic).second) << "harmonic " << line.harmonic;
            for (int other = 0; other < 3; ++other) {
                const double amplitude = std::abs(line_of(x[other], 3 * line.harmonic));
                if (other == axis) {
                    EXPECT_NEAR(amplitude, line.amplitude_n, 1e-9);
                } else {
                    EXPECT_LT(amplitude, 1e-12) << "axis " << other << " at axis " << axis
                                                << "'s line " << line.frequency_hz << " Hz";
                }
            }
        }
        double cross = 0.0;  // zero correlation over whole periods
        for (std::size_t n = 0; n < x[axis].size(); ++n) cross += x[axis][n] * x[(axis + 1) % 3][n];
        EXPECT_LT(std::abs(cross / static_cast<double>(x[axis].size())), 1e-12);
    }
}

TEST(EnvExcitation, TableIsTheLineFormulaAndPeaksAtTheAmplitude) {
    for (int axes = 1; axes <= 3; ++axes) {
        const Multisine signal(pen_signal(axes));
        for (int axis = 0; axis < axes; ++axis) {
            double peak = 0.0;
            for (std::int64_t n = 0; n < static_cast<std::int64_t>(signal.period_samples()); ++n) {
                EXPECT_NEAR(signal.sample(axis, n), signal.evaluate_lines(axis, n), 1e-12);
                peak = std::max(peak, std::abs(signal.sample(axis, n)));
            }
            EXPECT_NEAR(peak, 0.75, 1e-12);
            // Periodic for any n, negative ones included.
            const auto length = static_cast<std::int64_t>(signal.period_samples());
            EXPECT_EQ(signal.sample(axis, -1), signal.sample(axis, length - 1));
            EXPECT_EQ(signal.sample(axis, 5 * length + 7), signal.sample(axis, 7));
        }
    }
}

TEST(EnvExcitation, CrestFactorIsLowFarBelowEqualPhases) {
    for (int axes = 1; axes <= 3; ++axes) {
        const Multisine signal(pen_signal(axes));
        for (int axis = 0; axis < axes; ++axis) {
            const double crest = signal.crest_factor(axis);
            const double equal_phases = std::sqrt(2.0 * signal.lines(axis).size());
            std::cout << "[excitation] " << axes << " axes, axis " << axis << ": "
                      << signal.lines(axis).size() << " lines, crest factor " << crest
                      << " (equal phases: " << equal_phases << ")\n";
            EXPECT_LT(crest, 2.3);
            EXPECT_LT(crest, 0.5 * equal_phases);
        }
    }
}

// m dv/dt + b v = f under an exact zero-order hold, one period T per sample.
struct MassDamper {
    double x = 0.0, v = 0.0;
    void step(double f, double period_s) {
        const double decay = std::exp(-kDamping / kMass * period_s);
        const double v_end = f / kDamping;
        x += v_end * period_s + (v - v_end) * (1.0 - decay) * kMass / kDamping;
        v = v_end + (v - v_end) * decay;
    }
};

TEST(EnvExcitation, PredictedSwingMatchesTheModelDrivenFromRest) {
    ExcitationSettings settings = pen_excitation();
    settings.fade_s = 0.5 * Multisine(settings.signal).period_s();  // the daemon's default
    const ExcitationEnvironment e(settings);
    MassDamper device;
    double swing = 0.0, centre = 0.0;
    std::int64_t centre_samples = 0;
    for (std::int64_t j = 0; j < e.samples(); ++j) {
        device.step(e.scheduled_force_n(j)[0], 1e-3);
        swing = std::max(swing, std::abs(device.x));
        if (j >= e.fade_samples() && j < e.samples() - e.fade_samples()) {
            centre += device.x;
            ++centre_samples;
        }
    }
    centre /= static_cast<double>(centre_samples);
    const double predicted = e.signal().steady_state_excursion_m(kMass, kDamping);
    std::cout << "[excitation] swing from rest " << 1e3 * swing << " mm, predicted "
              << 1e3 * predicted << " mm; mean position over the periods " << 1e3 * centre
              << " mm; at the end " << 1e3 * device.x << " mm\n";
    EXPECT_NEAR(swing, predicted, 0.1 * predicted);
    EXPECT_LT(std::abs(centre), 0.1 * predicted);     // the fade keeps the centre put
    EXPECT_LT(std::abs(device.x), 0.05 * predicted);  // and it comes back
}

TEST(EnvExcitation, EnvelopeFadesInAndOutAroundWholePeriods) {
    const ExcitationEnvironment e(pen_excitation());
    const std::int64_t fade = e.fade_samples();
    ASSERT_EQ(fade, 1000);
    EXPECT_EQ(e.samples(), 2 * fade + 3 * static_cast<std::int64_t>(e.signal().period_samples()));
    EXPECT_EQ(e.envelope(-1), 0.0);
    EXPECT_EQ(e.envelope(0), 0.0);
    EXPECT_NEAR(e.envelope(fade / 2), 0.5, 1e-12);
    EXPECT_EQ(e.envelope(fade), 1.0);
    EXPECT_EQ(e.envelope(e.samples() - fade - 1), 1.0);
    EXPECT_EQ(e.envelope(e.samples() - fade), 1.0);
    EXPECT_NEAR(e.envelope(e.samples() - fade / 2), 0.5, 1e-12);
    EXPECT_GT(e.envelope(e.samples() - 1), 0.0);
    EXPECT_LT(e.envelope(e.samples() - 1), 1e-5);
    EXPECT_EQ(e.envelope(e.samples()), 0.0);
    // The full periods start at phase 0 of the table.
    EXPECT_EQ(e.scheduled_force_n(fade).x, e.signal().sample(0, 0));
    // No step at the seams: from tick to tick the force changes no more than it does within
    // the full periods (where the fastest line sets the pace).
    auto step_at = [&](std::int64_t j) {
        return std::abs(e.scheduled_force_n(j + 1).x - e.scheduled_force_n(j).x);
    };
    double within_periods = 0.0, anywhere = 0.0;
    for (std::int64_t j = -1; j <= e.samples(); ++j) {
        anywhere = std::max(anywhere, step_at(j));
        if (j >= fade && j + 1 < e.samples() - fade)
            within_periods = std::max(within_periods, step_at(j));
    }
    EXPECT_LE(anywhere, 1.01 * within_periods);
    EXPECT_EQ(step_at(-1), 0.0);
    EXPECT_LT(step_at(e.samples() - 1), 1e-5);
}

/// Plays the environment as step_rigid does (evaluate, then commit at the same state) with
/// the handle at `x` and velocity `v`; returns the force.
Vec3 tick(ExcitationEnvironment& e, const Vec3& x, const Vec3& v = Vec3(0.0)) {
    const PenaltyForce force = e.evaluate(x, v);
    e.commit(x, v);
    return force.force_n;
}

TEST(EnvExcitation, ForceNeverExceedsTheLimit) {
    ExcitationSettings settings = pen_excitation(3);
    settings.signal.peak_force_n = 1.0;
    settings.still_time_s = 0.0;
    const double unclamped = Multisine(settings.signal).peak_vector_norm_n();
    ASSERT_GT(unclamped, 1.0);
    settings.force_limit_n = 0.8;  // below every axis's own peak, let alone the vector's
    ExcitationEnvironment e(settings);
    e.reset(Vec3(0.0));
    double largest = 0.0;
    std::int64_t clamped = 0;
    while (e.phase() != ExcitationEnvironment::Phase::finished) {
        const std::int64_t j = e.samples_played();
        const Vec3 f = tick(e, Vec3(0.0));
        largest = std::max(largest, glm::length(f));
        if (glm::length(f) > 0.8 - 1e-12) ++clamped;
        // Clamping keeps the direction.
        Vec3 raw(0.0);
        for (int axis = 0; axis < 3; ++axis) {
            raw[axis] = e.envelope(j) * e.signal().sample(axis, j - e.fade_samples());
        }
        if (glm::length(raw) > 1e-9) {
            EXPECT_NEAR(glm::dot(f, raw), glm::length(f) * glm::length(raw), 1e-9);
        }
    }
    std::cout << "[excitation] limit 0.8 N on a 1 N-per-axis signal (vector peak " << unclamped
              << " N): largest |f| " << largest << " N, clamped in " << clamped << " of "
              << e.samples() << " ticks\n";
    EXPECT_LE(largest, 0.8 * (1.0 + 1e-15));
    EXPECT_GT(clamped, 0);
}

TEST(EnvExcitation, WaitsForAStillHandleThenCentresTheWorkspaceThere) {
    ExcitationEnvironment e(pen_excitation());
    ASSERT_EQ(e.still_ticks(), 200);
    e.reset(Vec3(0.004, 0.0, 0.0));
    // 300 ticks moving: no force, no start.
    for (int i = 0; i < 300; ++i) {
        EXPECT_EQ(tick(e, Vec3(0.004 + 1e-4 * i, 0, 0), Vec3(0.1, 0, 0)), Vec3(0.0));
    }
    // 199 still ticks are not enough ...
    for (int i = 0; i < 199; ++i) EXPECT_EQ(tick(e, Vec3(0.0339, 0, 0)), Vec3(0.0));
    EXPECT_EQ(e.phase(), ExcitationEnvironment::Phase::waiting_for_still);
    // ... the 200th starts it: the next tick plays sample 0.
    EXPECT_EQ(tick(e, Vec3(0.0339, 0, 0), Vec3(0.019, 0, 0)), Vec3(0.0));
    EXPECT_EQ(e.phase(), ExcitationEnvironment::Phase::running);
    EXPECT_EQ(e.start_tick(), 500);
    EXPECT_EQ(e.center_m(), Vec3(0.0339, 0, 0));
    for (std::int64_t j = 0; j < 100; ++j) {
        EXPECT_EQ(tick(e, Vec3(0.0339 + 0.029, 0, 0)), e.scheduled_force_n(j)) << j;
    }
    EXPECT_EQ(e.samples_played(), 100);
}

TEST(EnvExcitation, LeavingTheWorkspaceZeroesTheForceInThatTickAndForEver) {
    ExcitationSettings settings = pen_excitation(2);
    settings.still_time_s = 0.0;
    settings.workspace_half_width_m = 0.015625;  // binary fractions: the faces are exact
    ExcitationEnvironment e(settings);
    const Vec3 centre(0.125, -0.25, 0.0);
    e.reset(centre);
    (void)tick(e, centre);  // starts at once; centred here
    for (int i = 0; i < 1500; ++i) {
        // The faces count as inside; the unused third axis is not checked.
        const Vec3 x = centre + Vec3(i % 2 == 0 ? 0.015625 : -0.015625, -0.015625, 5.0);
        EXPECT_EQ(tick(e, x), e.scheduled_force_n(i));
    }
    ASSERT_NE(e.scheduled_force_n(1500), Vec3(0.0));
    const Vec3 outside = centre + Vec3(0.0, 0.0156251, 0.0);
    EXPECT_EQ(e.evaluate(outside, Vec3(0.0)).force_n, Vec3(0.0));  // in that very tick
    e.commit(outside, Vec3(0.0));
    EXPECT_EQ(e.phase(), ExcitationEnvironment::Phase::left_workspace);
    EXPECT_EQ(e.exit_position_m(), outside);
    EXPECT_EQ(e.samples_played(), 1500);
    // Back inside, still nothing: latched for the rest of the run, resets included.
    for (int i = 0; i < 5000; ++i) EXPECT_EQ(tick(e, centre), Vec3(0.0));
    e.reset(centre);
    EXPECT_EQ(tick(e, centre), Vec3(0.0));
    EXPECT_EQ(e.phase(), ExcitationEnvironment::Phase::left_workspace);
    // A non-finite position is outside too.
    ExcitationEnvironment nan_run(settings);
    nan_run.reset(centre);
    (void)tick(nan_run, centre);
    EXPECT_EQ(tick(nan_run, Vec3(std::nan(""), -0.25, 0.0)), Vec3(0.0));
    EXPECT_EQ(nan_run.phase(), ExcitationEnvironment::Phase::left_workspace);
}

TEST(EnvExcitation, ResetAfterTheStartEndsItBeforeRestartsTheWait) {
    ExcitationEnvironment e(pen_excitation());
    e.reset(Vec3(0.0));
    for (int i = 0; i < 150; ++i) (void)tick(e, Vec3(0.0));
    e.reset(Vec3(0.0));  // before the start: the still wait begins again
    for (int i = 0; i < 199; ++i) (void)tick(e, Vec3(0.0));
    EXPECT_EQ(e.phase(), ExcitationEnvironment::Phase::waiting_for_still);
    (void)tick(e, Vec3(0.0));
    EXPECT_EQ(e.phase(), ExcitationEnvironment::Phase::running);
    for (int i = 0; i < 700; ++i) (void)tick(e, Vec3(0.0));
    e.reset(Vec3(0.0));  // a link recovery or a re-arm mid-run: one shot, it ends
    EXPECT_EQ(e.phase(), ExcitationEnvironment::Phase::interrupted);
    EXPECT_EQ(tick(e, Vec3(0.0)), Vec3(0.0));
}

TEST(EnvExcitation, PlaysToTheEndThenZero) {
    ExcitationSettings settings = pen_excitation();
    settings.periods = 1;
    settings.fade_s = 0.1;
    ExcitationEnvironment e(settings);
    e.reset(Vec3(0.0));
    std::int64_t ticks = 0;
    while (e.phase() != ExcitationEnvironment::Phase::finished && ticks < 100'000) {
        (void)tick(e, Vec3(0.0));
        ++ticks;
    }
    EXPECT_EQ(ticks, 200 + e.samples());
    EXPECT_EQ(tick(e, Vec3(0.0)), Vec3(0.0));
    EXPECT_EQ(std::string(to_string(e.phase())), "finished");
}

TEST(EnvExcitation, IsAPureSourceWithZeroJacobians) {
    ExcitationSettings settings = pen_excitation(3);
    settings.still_time_s = 0.0;
    ExcitationEnvironment e(settings);
    e.reset(Vec3(0.0));
    for (int i = 0; i < 1200; ++i) (void)tick(e, Vec3(0.0));
    const PenaltyForce f = e.evaluate(Vec3(0.001, -0.002, 0.003), Vec3(0.1, 0.2, -0.3));
    EXPECT_NE(f.force_n, Vec3(0.0));
    EXPECT_EQ(f.stiffness_n_per_m, Mat3(0.0));
    EXPECT_EQ(f.damping_n_s_per_m, Mat3(0.0));
}

TEST(EnvExcitation, TickNeverAllocates) {
    ExcitationSettings settings = pen_excitation(3);
    settings.still_time_s = 0.01;
    settings.workspace_half_width_m = 0.05;
    ExcitationEnvironment excitation(settings);
    ImpedanceEnvironment& environment = excitation;
    double checksum = 0.0;
    const hapticd::testing::AllocationGuard guard;
    environment.reset(Vec3(0.0));
    for (std::int64_t i = 0; i < 2 * excitation.samples(); ++i) {
        const Vec3 x(0.01 * std::sin(1e-3 * static_cast<double>(i)), 0.0, 0.0);
        checksum += environment.evaluate(x, Vec3(0.0)).force_n.x;
        environment.commit(x, Vec3(0.0));
        if (i == excitation.samples() + 10) environment.reset(x);
    }
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_NE(checksum, 0.0);
}

TEST(EnvExcitation, RejectsSettingsThatMakeNoSignal) {
    auto message_of = [](const MultisineSettings& s) -> std::string {
        try {
            const Multisine signal(s);
        } catch (const std::invalid_argument& e) {
            return e.what();
        }
        return "no error";
    };
    MultisineSettings s = pen_signal();
    s.band_high_hz = 600.0;
    EXPECT_NE(message_of(s).find("band_high_hz = 600"), std::string::npos) << message_of(s);
    s = pen_signal(3);
    s.band_low_hz = 10.0;
    s.band_high_hz = 12.0;
    EXPECT_NE(message_of(s).find("fewer than 2"), std::string::npos) << message_of(s);
    s = pen_signal();
    s.axes = 4;
    EXPECT_NE(message_of(s).find("axes = 4"), std::string::npos);
    s = pen_signal();
    s.period_s = 0.001;
    EXPECT_NE(message_of(s).find("samples"), std::string::npos);
    ExcitationSettings bad = pen_excitation();
    bad.workspace_half_width_m = 0.0;
    EXPECT_THROW(ExcitationEnvironment{bad}, std::invalid_argument);
    bad = pen_excitation();
    bad.periods = 0;
    EXPECT_THROW(ExcitationEnvironment{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace hapticd::env
