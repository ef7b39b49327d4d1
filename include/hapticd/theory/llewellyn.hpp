// Passivity (7) and Llewellyn's unconditional-stability criteria (8) for a two-port
// evaluated at one frequency, with margins that say how far it is from failing.
#pragma once

#include <functional>

#include "hapticd/theory/twoport.hpp"

namespace hapticd::theory {

/// Passivity of a two-port at one frequency, (6)-(7): P + P^H >= 0.
struct PassivityResult {
    bool passive = false;
    /// Smallest eigenvalue of (P + P^H)/2. Non-negative iff (7) holds.
    double min_eigenvalue = 0.0;
};

/// (7), written with the conjugate that the Hermitian part (6) requires:
///   Re p11 >= 0, Re p22 >= 0, Re p11 Re p22 - |(p12 + conj(p21))/2|^2 >= 0.
/// (7) as printed omits the conjugate; with it, passivity and (8) coincide for
/// reciprocal networks as Section II-C states (tested).
PassivityResult passivity(const TwoPort& network);

/// Llewellyn's criteria (8) at one frequency.
struct LlewellynResult {
    bool unconditionally_stable = false;
    double re_p11 = 0.0;
    double re_p22 = 0.0;
    /// Llewellyn's invariant stability factor
    ///   eta = (2 Re p11 Re p22 - Re(p12 p21)) / |p12 p21|,
    /// the same number in all four immittance forms; (8) holds iff Re p11 >= 0 and
    /// eta >= 1. +inf for a unilateral network (p12 p21 = 0).
    double stability_factor = 0.0;
    /// Relative margin of the second inequality of (8):
    ///   2 Re p11 Re p22 / (|p12 p21| + Re(p12 p21)) - 1.
    /// >= 0 iff it holds. Unlike eta - 1 it stays finite as ω -> 0 for the haptic
    /// interface, where both sides of (8) vanish like ω². For (18) it is exactly the
    /// ratio of the two sides of (21) minus one. +inf where the right side is zero.
    double margin = 0.0;
};

LlewellynResult llewellyn(const TwoPort& network);

/// (8) checked at every frequency up to Nyquist: how far the network is from failing, and
/// where. `network_at(θ)` gives the two-port at the normalised frequency θ = ωT.
struct LlewellynSweep {
    bool unconditionally_stable = false;  ///< (8) held at every frequency checked
    double worst_margin = 0.0;            ///< smallest LlewellynResult::margin
    double worst_frequency_hz = 0.0;      ///< where it occurs
    double worst_re_p11 = 0.0;            ///< smallest Re p11 (the first inequality of (8))
};
LlewellynSweep llewellyn_over_frequency(const std::function<TwoPort(double)>& network_at,
                                        double rate_hz, int grid_points = 4096);

}  // namespace hapticd::theory
