// A proof that a coupling is stable for every member of a declared operator class
// (operator_class.hpp, and hands-off) and every passive environment (docs/stability-models.md,
// "A class's proof"). It is the passive model's condition with the class in place of every
// passive operator:
//
//   no pole at e^{jθ} for any passive environment iff  Re(1/Z_c(θ)) + Re Ĝ(θ) > 0,
//   Ĝ = Σ_k c_k Y(jω_k),  c_k = 4 sin²(θ/2) e^{-j a_k} / o_k²,  o_k = θ + 2πk,
//   a_k = (1 + q)θ + φ o_k,  ω_k = o_k / T,  Y = 1/(b + jmω + Z_h(jω)),
//
// divided through by 2 sin²(θ/2). Over an interval of θ each alias is bounded below
// separately, each by its own worst member (a member may differ from alias to alias, so the
// bound is below the class's true worst, never above it):
//
//   1. Z_h = 1/(1/Z_s + 1/Z_a) with Z_s = b_s - j k_s/ω and Z_a = b_a + j(m_h ω - k_a/ω).
//      Over the class's box and the interval's ω each of Z_s and Z_a sweeps exactly a
//      rectangle; the exact ranges of Re and Im of a reciprocal over a rectangle, summed, and
//      inverted again, give an interval [X_lo, X_hi] that holds Im Z_h of every member
//      (widened to hold 0: hands-off).
//   2. So W = b + jmω + Z_h lies in the half-strip Re W >= b, Im W in [mω_lo + X_lo,
//      mω_hi + X_hi] (Re Z_h >= 0: the members are passive). The least Re(e^{-ja}/W) over
//      the strip is in closed form (the strip's three edges, each a quadratic's roots), and
//      over an interval of a it is at an end of the interval unless cos a < 0 inside it.
//   3. The weight 2/o² is taken at the interval's end that makes the term least; the
//      aliases past |k| = K sum to at least -1/(π² (K - 1/2) b) (the passive disk).
//   4. On every interval the passive condition is a bound too (a class is a subset of every
//      passive operator): the interval's bound is the larger of the two, and on [0, θ_0]
//      only the passive one holds.
//   5. Re(1/Z_c)/(2 sin²(θ/2)) = R / (2 R² s² + 2 (K c - b_c Im B s)²), s = sin(θ/2),
//      c = cos(θ/2), K = k_c T/2, R = b_c Re B + K (B the velocity filter, 1 without one), is
//      bounded below over the interval by interval arithmetic on monotone pieces.
//
// The margin is bounded below on a partition of [0, π] (geometric below 0.05 rad, steps of
// 1e-3 rad above); an interval whose bound is not positive is halved, down to 1e-9 rad,
// before the proof fails there. The bound of step 3 does not depend on the coupling, so a
// prover computes it once for a bisection on k_c. The proof ignores the class's resonance
// bound (a superset of members). Arithmetic is IEEE double without directed rounding.
#pragma once

#include <vector>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/tune/operator_class.hpp"

namespace hapticd::tune {

struct ClassProof {
    bool holds = false;
    /// The least lower bound of Re(1/Z_c)/(2 sin²(θ/2)) + Re Ĝ/(2 sin²(θ/2)) over θ, times
    /// 2b: in units of the passive disk's radius. Where the proof holds, the least over the
    /// intervals it used (> 0); where it fails, the least over the partition before halving.
    double worst_margin = 0.0;
    double worst_frequency_hz = 0.0;  ///< the middle of the interval where it is least
};

/// The class's alias-sum bound for one device, rate, delay and class, for any coupling.
class ClassProver {
  public:
    /// Throws std::invalid_argument for a rate, delay or device out of the models' ranges.
    ClassProver(const theory::DeviceModel& device, const OperatorClass& operators, double rate_hz,
                double delay_periods);

    ClassProof prove(const theory::SpringDamperCoupling& coupling) const;

    /// The largest k_c at the coupling's b_c (and velocity filter) that prove() accepts, by
    /// bisection to 1e-4 relative from `known_n_per_m` up (a k_c already proven some other
    /// way, or 0). The stiffness it returns has been proven (or is `known_n_per_m`).
    struct Limit {
        double stiffness_n_per_m = 0.0;  ///< proven (0: not even k_c = 0)
        double rejected_n_per_m = 0.0;   ///< not proven (kMaxCouplingStiffness: none found)
        int proofs = 0;                  ///< calls of prove()
    };
    Limit stiffness_limit(const theory::SpringDamperCoupling& shape, double known_n_per_m) const;

    /// A lower bound on Σ_k (2/o_k²) Re(e^{-j a_k} Y(jω_k)) over θ in [lo, hi] (0 <= lo <
    /// hi <= π) and every member: the larger of the class's bound (steps 1-3) and the
    /// passive one (step 4).
    double alias_bound(double lo, double hi) const;
    /// Steps 1-3 alone: -inf where lo = 0 (the k = 0 weight is unbounded there).
    double class_alias_bound(double lo, double hi) const;

  private:
    struct Interval {
        double lo = 0.0;
        double hi = 0.0;
        double alias_bound = 0.0;  ///< the larger of the class's and the passive bound
    };
    double passive_alias_bound(double lo, double hi) const;
    /// The bound on [lo, hi] in units of the passive disk's radius (ClassProof::worst_margin).
    double interval_margin(const theory::SpringDamperCoupling& coupling, double lo, double hi,
                           double alias_bound) const;
    double frequency_hz(const Interval& interval) const;
    /// Whether the margin over [lo, hi] is positive, halving where it is not; `worst` takes the
    /// least interval's bound and middle.
    bool prove_interval(const theory::SpringDamperCoupling& coupling, double lo, double hi,
                        double bound, int depth, ClassProof& worst) const;

    theory::DeviceModel device_;
    OperatorClass operators_;
    double period_s_ = 0.0;
    int whole_periods_ = 0;
    double fraction_ = 0.0;
    std::vector<Interval> partition_;
};

}  // namespace hapticd::tune
