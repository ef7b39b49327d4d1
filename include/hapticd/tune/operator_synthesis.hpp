// Adversaries for the exact model, built by synthesis rather than found on a grid: passive
// operators with their modes on the aliases of a frequency, and the lossless environment
// that is worst there (docs/stability-models.md, "Why a sweep is not enough").
//
// At a frequency θ the hold feeds the handle's motion at every alias ω_k = |θ + 2πk|/T at
// once. With no delay (and for whole periods of it) the loop sits on the unit circle at
// z = e^{jθ} exactly when the handle's impedance is b + jX at every alias (the same X on
// the aliases θ + 2πk, -X on their mirrors 2πk - θ), with
//     b + jX = ζ = -Z(e^{jθ}) e^{-j(1+q)θ},   Z = 1/(1/Z_c + Y_e)
// (passive_model.hpp): the least b that passivity needs is then the b at which the loop is
// marginal, and with the modes on the first N aliases the bound is approached as N grows.
// The synthesis:
//   - free-handle modes on the aliases (reactance 0 there): the handle's total reactance
//         X_0(ω) = C ω Π_j (1 - ω²/Ω_j²) / Π_i (1 - ω²/p_i²),
//     zeros Ω_j on the first N aliases, poles p_i interlaced below them (p_1 < Ω_1 < p_2 <
//     ... < p_N < Ω_N), C chosen so that the mass at high frequency is the device's own m.
//     Interlacing makes every residue positive (Foster), so X_0 - m ω is an operator: N
//     absorbers, mass r_i/p_i² on a spring r_i, with r_i the residue at p_i;
//   - the reactance ±X at the aliases: X tan(ωT/2)/tan(θ/2) for X > 0 and
//     -|X| cot(ωT/2)/cot(θ/2) for X < 0 take exactly ±X there (tan and cot have period π);
//     their Mittag-Leffler series are absorbers at the odd (tan) or even (cot) multiples of
//     π/T, with a spring to ground for cot; the series is cut after K terms and its tail
//     kept as the rigid mass it is at the low aliases.
#pragma once

#include <numbers>
#include <vector>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/tune/environment_assumption.hpp"
#include "hapticd/tune/exact_model.hpp"

namespace hapticd::tune {

/// The first `count` distinct aliases |θ + 2πk|/T of θ, in rad/s, ascending.
std::vector<double> alias_frequencies_rad_per_s(double theta, double rate_hz, int count);

/// A lossless multi-mode grasp that gives the handle (device mass included) the reactance
/// +X on the aliases θ + 2πk and -X on 2πk - θ, for the first `aliases` of them.
OperatorModel alias_tuned_operator(const theory::DeviceModel& device, double theta, double rate_hz,
                                   int aliases, double reactance_n_s_per_m);

/// With a fraction φ of a period of delay each alias k has its own worst point on the passive
/// disk: W = b + j b cot(a_k/2), a_k = (1 + q)θ + φ(θ + 2πk) (docs/stability-models.md, "Every
/// passive environment"), the rim point of the operators' alias sum in the direction ψ = π;
/// for one environment the rim point nearest it is in another direction ψ, and there
/// W = b - j b tan((ψ + a_k)/2). Lossless multi-mode grasps that put the first `aliases`
/// (>= 2) of θ there: free-handle modes on the aliases, and a Foster reactance through the
/// targets (a spring to ground or a rigid mass, and absorbers with a pole between each two
/// aliases, placed by a compass search): one with the spring and one with the mass, each
/// where a placement makes every coefficient >= 0 (none where neither does).
std::vector<OperatorModel> alias_shaped_operators(const theory::DeviceModel& device, double theta,
                                                  double rate_hz, double delay_periods, int aliases,
                                                  double direction = std::numbers::pi);

/// The lossless (trapezoidal) mass-spring whose admittance at θ is j·admittance_imag (m/(N s)).
/// θ in (0, π); admittance_imag != 0.
EnvironmentModel lossless_environment_with_admittance(double theta, double rate_hz,
                                                      double admittance_imag);

struct Adversaries {
    std::vector<OperatorModel> operators;
    std::vector<EnvironmentModel> environments;
};

/// For the frequencies where the passive bound of this design binds (and a fixed spread of
/// others, π among them): the worst lossless environment, and alias-tuned operators with
/// 1, 2, 4 and 8 modes for it and for the rigid wall.
Adversaries synthesize_adversaries(const theory::DeviceModel& device,
                                   const theory::SpringDamperCoupling& coupling, double rate_hz,
                                   double delay_periods);

/// The same for a scene (environment_assumption.hpp): for each of its environments, at the
/// spread of frequencies and where the passive bound with the scene binds, alias-tuned
/// operators for the reactance b + jX = -Z e^{-j(1+q)θ} that Z = 1/(1/Z_c + 1/Z_e) needs.
std::vector<OperatorModel> synthesize_scene_adversaries(
    const theory::DeviceModel& device, const theory::SpringDamperCoupling& coupling, double rate_hz,
    const std::vector<SceneEnvironment>& scene, double delay_periods);

}  // namespace hapticd::tune
