#include "hapticd/tune/operator_class.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "hapticd/input/range.hpp"

namespace hapticd::tune {
namespace {

/// The value at u in [0, 1] of a range: logarithmic over a decade or more, from 0 by an
/// exponential that puts half the points in the lowest 3% (stiffness and damping matter on a
/// log scale, and 0 is their most interesting value), linear otherwise.
double value_at(const ParameterRange& range, double u) {
    const double lo = range.min, hi = range.max;
    if (hi <= lo) return lo;
    if (lo > 0.0 && hi / lo >= 10.0) return lo * std::pow(hi / lo, u);
    if (lo == 0.0) {
        constexpr double kDecades = 3.0;
        return hi * (std::pow(10.0, kDecades * u) - 1.0) / (std::pow(10.0, kDecades) - 1.0);
    }
    return lo + (hi - lo) * u;
}

/// The inverse of value_at, clamped to [0, 1].
double coordinate_of(const ParameterRange& range, double value) {
    const double lo = range.min, hi = range.max;
    if (hi <= lo) return 0.0;
    double u = 0.0;
    if (lo > 0.0 && hi / lo >= 10.0) {
        u = std::log(value / lo) / std::log(hi / lo);
    } else if (lo == 0.0) {
        constexpr double kDecades = 3.0;
        u = std::log10(1.0 + (std::pow(10.0, kDecades) - 1.0) * value / hi) / kDecades;
    } else {
        u = (value - lo) / (hi - lo);
    }
    return std::clamp(u, 0.0, 1.0);
}

std::string range_text(const ParameterRange& r) {
    std::ostringstream out;
    out << r.min;
    if (r.max != r.min) out << ".." << r.max;
    return out.str();
}

constexpr double kResonanceTolerance = 1e-9;  // relative, for members on the bound itself

}  // namespace

std::array<ParameterRange, kClassParameters> OperatorClass::ranges() const {
    return {hand_mass_kg, grip_stiffness_n_per_m, grip_damping_n_s_per_m, arm_stiffness_n_per_m,
            arm_damping_n_s_per_m};
}

OperatorModel OperatorClass::member(const ClassPoint& point) const {
    const auto r = ranges();
    std::array<double, kClassParameters> v{};
    for (int i = 0; i < kClassParameters; ++i) v[i] = value_at(r[i], point[i]);
    return OperatorModel::two_mass_grasp(v[1], v[2], v[0], v[3], v[4]);
}

ClassPoint OperatorClass::point_of(const OperatorModel& h) const {
    const auto r = ranges();
    const std::array<double, kClassParameters> v{h.hand_mass_kg, h.skin_stiffness_n_per_m,
                                                 h.skin_damping_n_s_per_m, h.arm_stiffness_n_per_m,
                                                 h.arm_damping_n_s_per_m};
    ClassPoint point{};
    for (int i = 0; i < kClassParameters; ++i) point[i] = coordinate_of(r[i], v[i]);
    return point;
}

double OperatorClass::hand_resonance_hz(const OperatorModel& h) {
    return std::sqrt((h.skin_stiffness_n_per_m + h.arm_stiffness_n_per_m) / h.hand_mass_kg) /
           (2.0 * std::numbers::pi);
}

bool OperatorClass::contains(const OperatorModel& h) const {
    if (h.family == OperatorFamily::hands_off) return true;
    if (h.family != OperatorFamily::two_mass_grasp) return false;
    const std::array<double, kClassParameters> v{h.hand_mass_kg, h.skin_stiffness_n_per_m,
                                                 h.skin_damping_n_s_per_m, h.arm_stiffness_n_per_m,
                                                 h.arm_damping_n_s_per_m};
    const auto r = ranges();
    for (int i = 0; i < kClassParameters; ++i) {
        const double slack = 1e-12 * std::max(1.0, std::abs(r[i].max));
        if (v[i] < r[i].min - slack || v[i] > r[i].max + slack) return false;
    }
    return max_resonance_hz <= 0.0 ||
           hand_resonance_hz(h) <= max_resonance_hz * (1.0 + kResonanceTolerance);
}

std::string OperatorClass::describe() const {
    const auto r = ranges();
    static constexpr std::array<const char*, kClassParameters> kSymbols = {"m_h", "k_s", "b_s",
                                                                           "k_a", "b_a"};
    std::ostringstream out;
    out << "two-mass grasps with";
    for (int i = 0; i < kClassParameters; ++i) {
        out << (i == 0 ? " " : ", ") << kSymbols[i] << " " << range_text(r[i]) << " " << kUnits[i];
    }
    if (max_resonance_hz > 0.0) out << " (hand resonance at most " << max_resonance_hz << " Hz)";
    out << ", and hands-off";
    return out.str();
}

void validate(const OperatorClass& operators, const std::string& source) {
    const auto r = operators.ranges();
    for (int i = 0; i < kClassParameters; ++i) {
        const ParameterRange& limit = OperatorClass::kLimits[i];
        for (const double value : {r[i].min, r[i].max}) {
            const bool ok = std::isfinite(value) && value >= limit.min && value <= limit.max;
            if (!ok) {
                const char* unit = OperatorClass::kUnits[i];
                input::reject_out_of_range(
                    source + " " + OperatorClass::kKeys[i], input::format_quantity(value, unit),
                    ">= " + input::format_quantity(limit.min, unit) +
                        " and <= " + input::format_quantity(limit.max, unit));
            }
        }
        if (r[i].min > r[i].max) {
            std::ostringstream message;
            message << source << " " << OperatorClass::kKeys[i] << " = [" << r[i].min << ", "
                    << r[i].max << "] is an empty range: the first value is the least, so it "
                    << "must be <= the second";
            throw std::invalid_argument(message.str());
        }
    }
    const double f = operators.max_resonance_hz;
    if (!(std::isfinite(f) && f >= 0.0 && f <= OperatorClass::kMaxResonanceLimitHz)) {
        input::reject_out_of_range(
            source + " max_resonance", input::format_quantity(f, "Hz"),
            "> 0 and <= " + input::format_quantity(OperatorClass::kMaxResonanceLimitHz, "Hz") +
                " (leave it out for no bound)");
    }
    if (f > 0.0) {
        // The least resonance in the box: the softest springs on the heaviest hand.
        const OperatorModel softest =
            OperatorModel::two_mass_grasp(r[1].min, r[2].min, r[0].max, r[3].min, r[4].min);
        const double least = OperatorClass::hand_resonance_hz(softest);
        if (least > f * (1.0 + kResonanceTolerance)) {
            std::ostringstream message;
            message << source << " max_resonance = " << f
                    << " Hz contradicts the ranges: their softest, heaviest hand (m_h = "
                    << r[0].max << " kg, k_s = " << r[1].min << " N/m, k_a = " << r[3].min
                    << " N/m) already resonates at " << least
                    << " Hz, so the class would hold no hand; raise max_resonance above it or "
                       "lower the stiffness bounds";
            throw std::invalid_argument(message.str());
        }
    }
}

}  // namespace hapticd::tune
