// The prediction for HilDelay: the linearised sampled-data loop of a heavy hand pressed into
// a penalty wall, with no coupling and a loop delay, and Colgate and Schenkel's bound with
// the delay in it.
//
// Plant: the handle with the hand mass on it, (m + m_h) dv/dt + (b + b_h) v = f (the paper's
// (10) with the sim's heavy hand, docs/sim-device.md), sampled x[n] = x(nT) (the encoder's
// quantisation left out). Controller: the wall in contact, f[n] = -K x[n] - B (x[n] - x[n-1]) / T
// (its damper on the backward difference, as the servo's rigid step gives it), K the stiffness the
// handle feels (the wall's plus the scene's other springs). Hold: f[n] acts over
// [nT + D, (n+1)T + D), D = (q + φ) T (command_pipeline.hpp). Over period n the plant thus
// sees f[n-q-1] for φT, then f[n-q] for (1 - φ)T, and with E(t) = e^{A t},
// G(t) = ∫_0^t e^{A s} g ds for the plant's (A, g):
//
//     s[n+1] = E(T) s[n] + E((1-φ)T) G(φT) f[n-q-1] + G((1-φ)T) f[n-q].
//
// The loop's state is (x, v, x[n-1], f[n-1], ..., f[n-q-1]); its dominant eigenvalue λ gives
// the growth rate of the oscillation's envelope, ln|λ| / T per second.
//
// Heavy-hand limit. For ωT << 1 (ω² = K/(m + m_h)) the hold and the delay act as a pure
// delay of T/2 + D on the spring: K x(t - T/2 - D) ≈ K x - K (T/2 + D) v, a negative damping
// K T (1 + 2D/T)/2 against b + b_h + B (the wall's damper keeps its full value to first order
// in ωT). The loop is stable iff, approximately,
//
//     K < 2 (b + b_h + B) / (T (1 + 2 D/T)),
//
// Colgate and Schenkel's b > K T/2 + B with the delay, and the envelope grows at about
// (K T (1 + 2 D/T)/2 - b - b_h - B) / (2 (m + m_h)) per second.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <unsupported/Eigen/MatrixFunctions>

namespace hapticd::testing {

struct HeavyHandOnAWall {
    double mass_kg = 0.1;                 ///< m + m_h
    double damping_n_s_per_m = 2.0;       ///< b + b_h, to ground
    double stiffness_n_per_m = 0.0;       ///< K, all springs on the handle
    double wall_damping_n_s_per_m = 0.0;  ///< B, on the backward difference
    double period_s = 1e-3;               ///< T
    double delay_periods = 0.0;           ///< D / T
};

struct LoopPole {
    double growth_per_s = 0.0;  ///< ln|λ| / T of the dominant eigenvalue
    double frequency_hz = 0.0;  ///< arg λ / (2 π T)
};

/// Colgate and Schenkel's stiffness bound with the delay, in the heavy-hand limit (above).
inline double delayed_stiffness_bound_n_per_m(const HeavyHandOnAWall& loop) {
    return 2.0 * (loop.damping_n_s_per_m + loop.wall_damping_n_s_per_m) /
           (loop.period_s * (1.0 + 2.0 * loop.delay_periods));
}

/// The heavy-hand limit's growth rate of the envelope, per second.
inline double heavy_hand_growth_per_s(const HeavyHandOnAWall& loop) {
    const double negative_damping =
        loop.stiffness_n_per_m * loop.period_s * (1.0 + 2.0 * loop.delay_periods) / 2.0;
    return (negative_damping - loop.damping_n_s_per_m - loop.wall_damping_n_s_per_m) /
           (2.0 * loop.mass_kg);
}

/// The dominant pole of the exact linearised sampled loop (above).
inline LoopPole sampled_loop_pole(const HeavyHandOnAWall& loop) {
    using Matrix3 = Eigen::Matrix3d;
    const double T = loop.period_s;
    const int q = static_cast<int>(std::floor(loop.delay_periods + 1e-9));
    const double phi = std::max(0.0, loop.delay_periods - q);
    Matrix3 a = Matrix3::Zero();  // (x, v, f held)
    a(0, 1) = 1.0;
    a(1, 1) = -loop.damping_n_s_per_m / loop.mass_kg;
    a(1, 2) = 1.0 / loop.mass_kg;
    const Matrix3 lead = (a * (phi * T)).exp();
    const Matrix3 lag = (a * ((1.0 - phi) * T)).exp();
    const Eigen::Matrix2d e = lag.topLeftCorner<2, 2>() * lead.topLeftCorner<2, 2>();
    const Eigen::Vector2d g_old = lag.topLeftCorner<2, 2>() * lead.block<2, 1>(0, 2);
    const Eigen::Vector2d g_new = lag.block<2, 1>(0, 2);

    const int n = 3 + q + 1;  // x, v, x[n-1], f[n-1] .. f[n-q-1]
    Eigen::MatrixXd loop_matrix = Eigen::MatrixXd::Zero(n, n);
    Eigen::RowVectorXd f_now = Eigen::RowVectorXd::Zero(n);  // f[n] from the state
    f_now(0) = -loop.stiffness_n_per_m - loop.wall_damping_n_s_per_m / T;
    f_now(2) = loop.wall_damping_n_s_per_m / T;
    const Eigen::RowVectorXd f_new =
        q == 0 ? f_now : Eigen::RowVectorXd(Eigen::RowVectorXd::Unit(n, 3 + q - 1));
    const Eigen::RowVectorXd f_old = Eigen::RowVectorXd::Unit(n, 3 + q);
    loop_matrix.topLeftCorner(2, 2) = e;
    for (int row = 0; row < 2; ++row) {
        loop_matrix.row(row) += g_old(row) * f_old + g_new(row) * f_new;
    }
    loop_matrix(2, 0) = 1.0;     // x[n] becomes x[n-1]
    loop_matrix.row(3) = f_now;  // f[n] becomes f[n-1]
    for (int j = 1; j <= q; ++j) loop_matrix(3 + j, 3 + j - 1) = 1.0;

    const Eigen::VectorXcd eigenvalues = loop_matrix.eigenvalues();
    std::complex<double> dominant = 0.0;
    for (const std::complex<double>& lambda : eigenvalues) {
        if (std::abs(lambda) > std::abs(dominant)) dominant = lambda;
    }
    return {std::log(std::abs(dominant)) / T,
            std::abs(std::arg(dominant)) / (2.0 * 3.14159265358979323846 * T)};
}

}  // namespace hapticd::testing
