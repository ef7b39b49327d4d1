// The discrete spring-damper virtual coupling of the paper, per axis on a 3-vector.
//
//   (16)  Z_c(z) = (b_c + k_c/s) |_{s -> (z-1)/(Tz)}
//
// With the device velocity taken by backward difference, v[n] = (x[n] - x[n-1])/T, the
// integrator k_c T z/(z-1) of (16) acting on (v_d - v_e) is exactly k_c (x_d - x_e), so the
// coupling force on the virtual tool is
//
//   F_c[n] = k_c (x_d[n] - x_e[n]) + b_c (v_d[n] - v_e[n]),   the handle gets -F_c[n].
//
// Two connections (Section III):
//   (17) impedance (penalty) environment: the coupling is in series with f_env, and the
//        massless tool x_e balances k_c (x_d - x_e) + b_c (v_d - v_e) + f_env(x_e, v_e) = 0.
//        step() solves this by Newton's method with the Jacobian that PenaltyForce carries.
//   (22) admittance (constraint) environment: the environment returns x_e for the device
//        state and gains; the coupling force follows from the same expression.
//
// Velocity filter (CouplingGains::velocity_filter_hz = f_c > 0; theory/velocity_filter.hpp):
// the damper acts on a first-order low-pass of the relative velocity,
//
//   u[n] = a u[n-1] + (1 - a) (v_d[n] - v_e[n]),   a = exp(-2π f_c T),
//   F_c[n] = k_c (x_d[n] - x_e[n]) + b_c u[n],
//
// which is Z_c(z) = k_c T/(1 - z⁻¹) + b_c (1 - a)/(1 - a z⁻¹) on the backward-difference
// velocity, the impedance every model analyses. The force is still affine in x_e: in (17) the
// current tick's damping weight is (1 - a) b_c and a b_c u[n-1] is a known force, so the
// Newton solve is unchanged in form (Jacobian k_c + (1 - a) b_c/T + ...). After an overrun
// the step spans period_s = several T and a = exp(-2π f_c period_s): the continuous low-pass
// sampled over the actual interval. u[n] is committed with the step, never by a failed
// solve (nothing is committed then); reset() and track_device() set u = 0, so a coupling
// that restarts (after a fault, a disarm, a reconnect: the loop calls reset() before the
// first coupled step) starts with an empty filter, like both sides at rest. f_c = 0 is
// exactly the unfiltered coupling, to the bit.
//
// Real-time: step() never allocates, locks or throws; a failed solve is reported in the
// returned CouplingStep (converged / finite), never by exception.
#pragma once

#include <algorithm>
#include <cmath>
#include <glm/matrix.hpp>

#include "hapticd/servo/environment_port.hpp"
#include "hapticd/theory/velocity_filter.hpp"

namespace hapticd::servo {

/// Newton solve settings for the series connection (17).
struct SeriesSolverOptions {
    int max_evaluations = 8;          ///< evaluate() calls per tick, >= 1
    double force_tolerance_n = 1e-9;  ///< converged when max |residual| <= this
};

/// What one coupling step produced. Forces in newtons, positions in metres, velocities m/s.
struct CouplingStep {
    Vec3 device_velocity_mps{0.0};  ///< v_d, backward difference (16)
    Vec3 tool_position_m{0.0};      ///< x_e
    Vec3 tool_velocity_mps{0.0};    ///< v_e, backward difference
    Vec3 tool_force_n{0.0};         ///< F_c = k_c (x_d - x_e) + b_c u, on the tool
    Vec3 damper_velocity_mps{0.0};  ///< u: v_d - v_e, or its low-pass with a velocity filter
    Vec3 handle_force_n{0.0};       ///< -F_c, on the device handle
    double residual_n = 0.0;        ///< max |balance residual| of (17); 0 for (22)
    int evaluations = 0;            ///< evaluate() calls used by (17); 0 for (22)
    bool converged = true;          ///< (17) met force_tolerance_n within max_evaluations
    bool finite = true;             ///< false: NaN/Inf seen; nothing was committed
};

inline bool all_finite(const Vec3& v) noexcept {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

inline double max_abs(const Vec3& v) noexcept {
    return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}

class VirtualCoupling {
  public:
    VirtualCoupling() = default;
    explicit VirtualCoupling(const CouplingGains& gains, SeriesSolverOptions options = {})
        : gains_(gains), options_(options) {}

    const CouplingGains& gains() const noexcept { return gains_; }
    /// New gains from the next step on (the caller restarts the history: reset()).
    void set_gains(const CouplingGains& gains) noexcept { gains_ = gains; }

    /// Both sides at rest at `device_position_m`: x_d[n-1] = x_e[n-1] = it, u[n-1] = 0.
    void reset(const Vec3& device_position_m) noexcept {
        previous_device_position_m_ = device_position_m;
        previous_tool_position_m_ = device_position_m;
        previous_damper_velocity_mps_ = Vec3(0.0);
    }

    const Vec3& previous_device_position_m() const noexcept { return previous_device_position_m_; }
    const Vec3& previous_tool_position_m() const noexcept { return previous_tool_position_m_; }
    /// u[n-1], the velocity the damper acted on in the last committed step (0 after reset).
    const Vec3& previous_damper_velocity_mps() const noexcept {
        return previous_damper_velocity_mps_;
    }

    /// The device velocity that step() would use: (x_d - x_d[n-1]) / period_s.
    Vec3 device_velocity_mps(const Vec3& device_position_m, double period_s) const noexcept {
        return (device_position_m - previous_device_position_m_) / period_s;
    }

    /// Advances only the device side (no environment), e.g. while a fault is latched: the
    /// tool rests on the device and the velocity filter is emptied (u[n-1] = 0).
    void track_device(const Vec3& device_position_m) noexcept {
        previous_device_position_m_ = device_position_m;
        previous_tool_position_m_ = device_position_m;
        previous_damper_velocity_mps_ = Vec3(0.0);
    }

    /// (17): series connection to an impedance environment. `period_s` is the time since the
    /// previous step (T, or a multiple of it after an overrun).
    ///
    /// Newton's method on the balance residual, warm-started at the last solution: a wall
    /// that is not touched costs one evaluation, a piecewise-linear wall 2-3. A residual that
    /// is discontinuous (a damped wall entered at speed: f jumps by b_w v at the surface) has
    /// no exact root and makes Newton bounce between the two sides; then the solve falls back
    /// to false position (Illinois) on the segment between them, which closes in on the
    /// surface. The iterate with the smallest residual is the one committed.
    template <ImpedancePort Environment>
    CouplingStep step(Environment& environment, const Vec3& device_position_m,
                      double period_s) noexcept {
        const double k_c = gains_.stiffness_n_per_m;
        const double pole = filter_pole(period_s);
        // The damper's weight on this tick's v_d - v_e: b_c, or (1 - a) b_c with the filter,
        // whose memory a b_c u[n-1] is a known force here.
        const double b_now = (1.0 - pole) * gains_.damping_n_s_per_m;
        const Vec3 carried_n = pole * gains_.damping_n_s_per_m * previous_damper_velocity_mps_;
        const bool filtered = pole > 0.0;
        const double inverse_period = 1.0 / period_s;
        const Vec3& x_d = device_position_m;
        CouplingStep out;
        out.device_velocity_mps = (x_d - previous_device_position_m_) * inverse_period;
        const Vec3& v_d = out.device_velocity_mps;

        // (17): residual of the force balance on the massless tool at a trial x_e.
        PenaltyForce penalty;
        auto residual_at = [&](const Vec3& x_e) noexcept {
            const Vec3 v_e = (x_e - previous_tool_position_m_) * inverse_period;
            penalty = environment.evaluate(x_e, v_e);
            ++out.evaluations;
            Vec3 coupling_n = k_c * (x_d - x_e) + b_now * (v_d - v_e);
            if (filtered) coupling_n += carried_n;
            return Vec3(coupling_n + penalty.force_n);
        };

        Vec3 x_e = previous_tool_position_m_;
        Vec3 residual = residual_at(x_e);
        Vec3 best_x_e = x_e;
        double best_residual_n = max_abs(residual);
        Vec3 before_x_e = x_e;  // the iterate before x_e, for bounce detection
        bool finite = all_finite(residual);
        while (finite && best_residual_n > options_.force_tolerance_n &&
               out.evaluations < options_.max_evaluations) {
            // -d(residual)/d(x_e) = (k_c + b_now/T) I + K_env + D_env/T: positive definite for
            // a passive environment, so the Newton step x_e += A^{-1} residual is well defined.
            const Mat3 jacobian = Mat3(k_c + b_now * inverse_period) + penalty.stiffness_n_per_m +
                                  penalty.damping_n_s_per_m * inverse_period;
            const double det = glm::determinant(jacobian);
            if (!std::isfinite(det) || det == 0.0) break;  // singular: keep the best iterate
            const Vec3 next_x_e = x_e + glm::inverse(jacobian) * residual;
            const Vec3 next_residual = residual_at(next_x_e);
            finite = all_finite(next_x_e) && all_finite(next_residual);
            if (!finite) break;
            keep_best(next_x_e, next_residual, best_x_e, best_residual_n);
            const bool bounced = out.evaluations > 2 &&
                                 max_abs(next_x_e - before_x_e) < 0.5 * max_abs(next_x_e - x_e);
            if (bounced) {
                finite = false_position(residual_at, x_e, residual, next_x_e, next_residual,
                                        out.evaluations, best_x_e, best_residual_n);
                break;
            }
            before_x_e = x_e;
            x_e = next_x_e;
            residual = next_residual;
        }
        out.finite = finite;
        if (!finite) {
            out.converged = false;
            out.tool_position_m = previous_tool_position_m_;
            return out;
        }
        out.residual_n = best_residual_n;
        out.converged = best_residual_n <= options_.force_tolerance_n;
        const Vec3 v_e = (best_x_e - previous_tool_position_m_) * inverse_period;
        environment.commit(best_x_e, v_e);
        return finish(out, x_d, best_x_e, v_e, pole);
    }

    /// No coupling at all, the conventional design the paper improves on: the impedance
    /// environment is evaluated at the device itself (x_e = x_d, v_e = v_d) and its force goes
    /// straight to the handle. Stable only while the environment meets Colgate and
    /// Schenkel's wall bound b > K T/2 + |B|; the daemon offers it for experiments.
    template <ImpedancePort Environment>
    CouplingStep step_rigid(Environment& environment, const Vec3& device_position_m,
                            double period_s) noexcept {
        const Vec3& x_d = device_position_m;
        CouplingStep out;
        out.device_velocity_mps = (x_d - previous_device_position_m_) / period_s;
        const PenaltyForce penalty = environment.evaluate(x_d, out.device_velocity_mps);
        out.evaluations = 1;
        out.finite = all_finite(penalty.force_n);
        if (!out.finite) {
            out.converged = false;
            out.tool_position_m = previous_tool_position_m_;
            return out;
        }
        environment.commit(x_d, out.device_velocity_mps);
        out.tool_position_m = x_d;
        out.tool_velocity_mps = out.device_velocity_mps;
        out.tool_force_n = -penalty.force_n;  // what the tool would need to stay put
        out.handle_force_n = penalty.force_n;
        previous_device_position_m_ = x_d;
        previous_tool_position_m_ = x_d;
        return out;
    }

    /// (22): coupling to an admittance environment, which returns x_e itself. With a velocity
    /// filter the environment is handed the unfiltered coupling that exerts the same force
    /// this tick (environment_port.hpp): damping (1 - a) b_c and the device velocity
    /// v_d + a u[n-1]/(1 - a), since (1 - a) b_c (v_d + a u[n-1]/(1 - a) - v_e) =
    /// (1 - a) b_c (v_d - v_e) + a b_c u[n-1].
    template <AdmittancePort Environment>
    CouplingStep step(Environment& environment, const Vec3& device_position_m,
                      double period_s) noexcept {
        const double inverse_period = 1.0 / period_s;
        const double pole = filter_pole(period_s);
        const Vec3& x_d = device_position_m;
        CouplingStep out;
        out.device_velocity_mps = (x_d - previous_device_position_m_) * inverse_period;
        Vec3 x_e;
        if (pole > 0.0) {
            const CouplingGains equivalent{
                .stiffness_n_per_m = gains_.stiffness_n_per_m,
                .damping_n_s_per_m = (1.0 - pole) * gains_.damping_n_s_per_m,
                .velocity_filter_hz = 0.0};
            const Vec3 velocity =
                out.device_velocity_mps + (pole / (1.0 - pole)) * previous_damper_velocity_mps_;
            x_e = environment.step(x_d, velocity, equivalent, period_s);
        } else {
            x_e = environment.step(x_d, out.device_velocity_mps, gains_, period_s);
        }
        if (!all_finite(x_e)) {
            out.finite = false;
            out.converged = false;
            out.tool_position_m = previous_tool_position_m_;
            return out;
        }
        const Vec3 v_e = (x_e - previous_tool_position_m_) * inverse_period;
        return finish(out, x_d, x_e, v_e, pole);
    }

  private:
    static void keep_best(const Vec3& x_e, const Vec3& residual, Vec3& best_x_e,
                          double& best_residual_n) noexcept {
        const double size = max_abs(residual);
        if (size < best_residual_n) {
            best_residual_n = size;
            best_x_e = x_e;
        }
    }

    // Illinois false position along the segment a -> b, on phi(t) = d . r(a + t d), d = b - a.
    // phi is decreasing for a passive environment; it needs phi(0) > 0 > phi(1). Returns false
    // if a residual was not finite.
    template <typename Residual>
    bool false_position(Residual& residual_at, const Vec3& a, const Vec3& residual_a, const Vec3& b,
                        const Vec3& residual_b, int& evaluations, Vec3& best_x_e,
                        double& best_residual_n) const noexcept {
        const Vec3 direction = b - a;
        double t_low = 0.0, t_high = 1.0;
        double phi_low = glm::dot(direction, residual_a);
        double phi_high = glm::dot(direction, residual_b);
        if (!(phi_low > 0.0 && phi_high < 0.0)) return true;  // no bracket: keep the best
        int retained_side = 0;  // -1: low kept twice in a row, +1: high
        while (evaluations < options_.max_evaluations &&
               best_residual_n > options_.force_tolerance_n) {
            const double t = t_low + phi_low * (t_high - t_low) / (phi_low - phi_high);
            const Vec3 x_e = a + t * direction;
            const Vec3 residual = residual_at(x_e);
            if (!all_finite(residual)) return false;
            keep_best(x_e, residual, best_x_e, best_residual_n);
            const double phi = glm::dot(direction, residual);
            if (phi > 0.0) {
                t_low = t;
                phi_low = phi;
                if (retained_side == 1) phi_high *= 0.5;  // Illinois: unstick the far end
                retained_side = 1;
            } else {
                t_high = t;
                phi_high = phi;
                if (retained_side == -1) phi_low *= 0.5;
                retained_side = -1;
            }
        }
        return true;
    }

    /// a of the velocity filter over `period_s` (0 without one), recomputed only when the
    /// interval changes (an overrun), so a steady loop pays no exp().
    double filter_pole(double period_s) noexcept {
        if (!(gains_.velocity_filter_hz > 0.0)) return 0.0;
        if (period_s != pole_period_s_) {
            pole_period_s_ = period_s;
            pole_ = theory::velocity_filter_pole(gains_.velocity_filter_hz, period_s);
        }
        return pole_;
    }

    CouplingStep finish(CouplingStep& out, const Vec3& x_d, const Vec3& x_e, const Vec3& v_e,
                        double pole) noexcept {
        out.tool_position_m = x_e;
        out.tool_velocity_mps = v_e;
        // (16): F_c = k_c (x_d - x_e) + b_c u, u = v_d - v_e or, with the velocity filter,
        // a u[n-1] + (1 - a)(v_d - v_e); on the tool; the handle gets -F_c.
        const Vec3 relative_velocity = out.device_velocity_mps - v_e;
        out.damper_velocity_mps =
            pole > 0.0 ? pole * previous_damper_velocity_mps_ + (1.0 - pole) * relative_velocity
                       : relative_velocity;
        out.tool_force_n = gains_.stiffness_n_per_m * (x_d - x_e) +
                           gains_.damping_n_s_per_m * out.damper_velocity_mps;
        out.handle_force_n = -out.tool_force_n;
        out.finite = all_finite(out.tool_force_n);
        previous_device_position_m_ = x_d;
        previous_tool_position_m_ = x_e;
        previous_damper_velocity_mps_ = out.damper_velocity_mps;
        return out;
    }

    CouplingGains gains_{};
    SeriesSolverOptions options_{};
    Vec3 previous_device_position_m_{0.0};    ///< x_d[n-1]
    Vec3 previous_tool_position_m_{0.0};      ///< x_e[n-1]
    Vec3 previous_damper_velocity_mps_{0.0};  ///< u[n-1], the velocity filter's state
    double pole_period_s_ = 0.0;              ///< the interval pole_ is for
    double pole_ = 0.0;                       ///< a = exp(-2π f_c pole_period_s_)
};

}  // namespace hapticd::servo
