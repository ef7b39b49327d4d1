// A declared class of operators (docs/stability-models.md, "Operator classes"): the hands a
// lab actually has, rather than every passive operator.
//
// The unconditional guarantee (the `passive` model) holds for every passive operator, and
// the operators that reach it have lossless modes near the aliases of Nyquist: stiffnesses
// near (2N - 1)² m (π/T)², about 1e6 N/m on a 0.1 kg device at 1 kHz. No hand does that. A
// class bounds the hand instead, on the two-mass grasp of the exact model:
//
//   handle --(grip k_s, b_s)-- hand mass m_h --(arm k_a, b_a)-- ground
//
// with each parameter in a declared interval, and optionally a highest operator
// resonance: the hand's own natural frequency with the handle held still,
// sqrt((k_s + k_a)/m_h)/(2π), at most f_max. Hands-off (the operator lets go) belongs to
// every class. A rigid hold is the limit k_s -> inf; a class reaches it as closely as its
// upper grip stiffness.
//
// A design is proven for a class by tune/class_proof.hpp (the passive condition bounded over
// the class's box, alias by alias) and searched for a member that breaks it by
// tune/class_check.hpp (the class's grid, members with modes tuned to the aliases, and
// pattern searches from the worst of them); the verdict says which proof it rests on.
#pragma once

#include <array>
#include <string>

#include "hapticd/tune/exact_model.hpp"

namespace hapticd::tune {

/// A closed interval [min, max]; min == max is a single value.
struct ParameterRange {
    double min = 0.0;
    double max = 0.0;
};

/// The parameters of a class member, in the order of OperatorClass::ranges().
inline constexpr int kClassParameters = 5;
using ClassPoint = std::array<double, kClassParameters>;  ///< each coordinate in [0, 1]

struct OperatorClass {
    ParameterRange hand_mass_kg;            ///< m_h, within [1e-6, 1e3] kg (a milligram up)
    ParameterRange grip_stiffness_n_per_m;  ///< k_s, within [0, 1e7] N/m
    ParameterRange grip_damping_n_s_per_m;  ///< b_s, within [0, 1e4] N s/m
    ParameterRange arm_stiffness_n_per_m;   ///< k_a, within [0, 1e7] N/m
    ParameterRange arm_damping_n_s_per_m;   ///< b_a, within [0, 1e4] N s/m
    double max_resonance_hz = 0.0;          ///< f_max > 0, or 0 for no such bound

    /// The keys of the [operator] table, in the order of the ranges.
    static constexpr std::array<const char*, kClassParameters> kKeys = {
        "hand_mass", "grip_stiffness", "grip_damping", "arm_stiffness", "arm_damping"};
    static constexpr std::array<const char*, kClassParameters> kUnits = {"kg", "N/m", "N s/m",
                                                                         "N/m", "N s/m"};
    /// The allowed values of each key.
    static constexpr std::array<ParameterRange, kClassParameters> kLimits = {
        ParameterRange{1e-6, 1e3}, ParameterRange{0.0, 1e7}, ParameterRange{0.0, 1e4},
        ParameterRange{0.0, 1e7}, ParameterRange{0.0, 1e4}};
    static constexpr double kMaxResonanceLimitHz = 1e5;

    std::array<ParameterRange, kClassParameters> ranges() const;

    /// The member at `point` (each coordinate in [0, 1]: 0 is the range's min, 1 its max;
    /// wide ranges are spaced logarithmically, see operator_class.cpp).
    OperatorModel member(const ClassPoint& point) const;
    /// The inverse of member() for a two-mass grasp (clamped to the class's ranges).
    ClassPoint point_of(const OperatorModel& two_mass_grasp) const;

    /// Whether a member lies inside the class (the resonance bound, when declared).
    bool contains(const OperatorModel& two_mass_grasp) const;

    /// The hand's natural frequency with the handle held still, sqrt((k_s + k_a)/m_h)/(2π).
    static double hand_resonance_hz(const OperatorModel& two_mass_grasp);

    /// For example "two-mass grasps with m_h 0.1..2 kg, k_s 0..3000 N/m, b_s 2..30 N s/m,
    /// k_a 0..1000 N/m, b_a 0..20 N s/m (hand resonance at most 40 Hz), and hands-off".
    std::string describe() const;
};

/// Throws std::invalid_argument naming the key, the value and the allowed range when a
/// bound is out of range or not finite, when min > max, or when no member satisfies the
/// resonance bound (a contradictory class). `source` prefixes the key, e.g. "lab.toml:
/// [operator]".
void validate(const OperatorClass& operators, const std::string& source);

}  // namespace hapticd::tune
