// Discrete-time operators evaluated on the unit circle z = e^{jωT}.
//
// Everything in the theory layer is a function of the normalised frequency
// θ = ωT (rad per sample), 0 < θ <= π (π is the Nyquist frequency). The helpers
// here convert between θ and hertz and implement the substitutions the paper uses
// for s: the first (backward) difference of (16) and Tustin's rule of (12).
#pragma once

#include <cmath>
#include <complex>
#include <numbers>

namespace hapticd::theory {

using Complex = std::complex<double>;

/// |z| = sqrt(Re² + Im²), for the sweeps' inner loops. std::abs (glibc's hypot, which
/// std::norm calls too) guards against overflow and costs four times as much: it was 76 % of the
/// filtered alias margin's branch and bound. The magnitudes swept (gains, admittances, filter
/// responses) stay far inside the range where Re² + Im² is finite.
inline double magnitude(Complex z) { return std::sqrt(z.real() * z.real() + z.imag() * z.imag()); }

/// z = e^{jθ} for the normalised frequency θ = ωT (rad per sample).
inline Complex unit_circle_point(double theta) { return std::polar(1.0, theta); }

/// θ = 2π f T.
inline double normalized_frequency(double frequency_hz, double sample_period_s) {
    return 2.0 * std::numbers::pi * frequency_hz * sample_period_s;
}

/// f = θ / (2π T).
inline double frequency_hz(double theta, double sample_period_s) {
    return theta / (2.0 * std::numbers::pi * sample_period_s);
}

/// Nyquist frequency 1/(2T) in hertz.
inline double nyquist_hz(double sample_period_s) { return 0.5 / sample_period_s; }

/// s -> (z - 1)/(T z): the first difference used to discretise the coupling, (16).
inline Complex backward_difference_s(Complex z, double sample_period_s) {
    return (z - 1.0) / (sample_period_s * z);
}

/// s -> (2/T)(z - 1)/(z + 1): Tustin's rule used to discretise the device, (12).
inline Complex tustin_s(Complex z, double sample_period_s) {
    return (2.0 / sample_period_s) * (z - 1.0) / (z + 1.0);
}

/// sin(x)/x with the removable singularity filled in.
template <typename S>
S sinc(const S& x) {
    using std::abs;
    using std::cos;
    using std::sin;
    if (abs(x) < 1e-4) {
        const S x2 = x * x;
        return 1.0 - x2 / 6.0 + x2 * x2 / 120.0;
    }
    return sin(x) / x;
}

}  // namespace hapticd::theory
