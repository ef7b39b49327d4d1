#include "hapticd/tune/identification.hpp"

#include <ceres/ceres.h>
#include <ceres/manifold.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <tuple>
#include <utility>

#include "hapticd/input/range.hpp"
#include "hapticd/tune/identification_model.hpp"
#include "identification_data.hpp"

namespace hapticd::tune {
namespace {

using detail::AxisData;
using detail::format;
using detail::median;
using detail::percent;
using detail::refuse;
using detail::SegmentRange;

using Jet = ceres::Jet<double, 6>;  // d/d(log m, log b, F_c, F_0, x0, v0)
constexpr int kGlobalSize = 4;      // log m, log b, F_c, F_0
constexpr int kStateSize = 2;       // a segment's x0, v0
constexpr int kCoulombIndex = 2;
using Matrix4 = Eigen::Matrix4d;
using Vector4 = Eigen::Vector4d;
using Matrix6 = Eigen::Matrix<double, kGlobalSize + kStateSize, kGlobalSize + kStateSize>;
using Vector6 = Eigen::Matrix<double, kGlobalSize + kStateSize, 1>;

// The Huber loss is quadratic out to kHuberK robust standard deviations of the residual
// (never less than the quantisation noise q/√12); the first pass uses kFirstPassScale
// residual units (encoder steps, or µm when the positions are not quantised).
constexpr double kHuberK = 2.0;
constexpr double kFirstPassScale = 10.0;
// When a pass stops: near the optimum, parameters k standard errors off raise the cost by
// about k²/N relative (N samples), so a relative cost change below k²/N means the fit moves
// by less than k standard errors. The final pass stops at k = 0.01; pass 1, which only has
// to find the residuals' scale, at k = 0.1. (A fixed tolerance would either stop short on
// short logs or, on long ones, crawl on through the kinks that stiction puts in the cost.)
constexpr double kFirstPassStepInStdErrors = 0.1;
constexpr double kFinalStepInStdErrors = 0.01;
// Without quantisation (resolution unknown), residuals are computed in this unit, m.
constexpr double kUnquantisedUnitM = 1e-6;
// The range m and b are searched in (exp() cannot overflow); an estimate on its edge is
// refused.
constexpr double kMassRangeKg[] = {1e-5, 1e5};
constexpr double kDampingRangeNsPerM[] = {1e-5, 1e7};
// The smallest eigenvalue of the (scaled) information matrix below which the log is
// declared unable to separate the parameters.
constexpr double kMinInformationEigenvalue = 1e-10;
constexpr const char* kParameterNames[] = {"the mass m", "the damping b",
                                           "the Coulomb friction F_c", "the force offset F_0"};

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Simulates a segment from (global, state) with its derivatives: calls visit(j, x_j) for each
/// of its `length` samples, x_j the position with its derivatives by (log m, log b, F_c, F_0,
/// x0, v0). `force` points at the segment's first row; with a loop delay the holds reach
/// back `delay.history()` rows before it (HoldDelay). Nothing is stored. Returns false when
/// the simulation is not finite; `stuck` counts the holds after which the handle is at rest
/// (stuck by Coulomb friction).
template <typename Visit>
bool simulate_segment(const double* force, std::size_t length, double period_s,
                      const HoldDelay& delay, const double* global, const double* state,
                      Visit&& visit, std::size_t* stuck = nullptr) {
    const Jet mass = exp(Jet(global[0], 0));
    const Jet damping = exp(Jet(global[1], 1));
    const Jet coulomb(global[2], 2);
    const Jet offset(global[3], 3);
    const Jet a = damping / mass;
    // A fractional delay splits each period in two holds: the older force, then the newer.
    const double early_s = delay.fraction * period_s;
    const double late_s = period_s - early_s;
    const HoldConstants<Jet> early = hold_constants(a, early_s);
    const HoldConstants<Jet> late = hold_constants(a, late_s);
    const std::ptrdiff_t lag = static_cast<std::ptrdiff_t>(delay.whole_periods);
    MotionState<Jet> motion{Jet(state[0], 4), Jet(state[1], 5)};
    visit(std::size_t{0}, motion.x);
    std::size_t at_rest = 0;
    for (std::size_t j = 1; j < length; ++j) {
        const double* acting = force + (static_cast<std::ptrdiff_t>(j) - 1 - lag);  // F[n - q]
        if (early_s > 0.0) {
            hold_step(motion, mass, a, coulomb, Jet(acting[-1]) + offset, early, early_s);
        }
        hold_step(motion, mass, a, coulomb, Jet(acting[0]) + offset, late, late_s);
        visit(j, motion.x);
        at_rest += motion.v == 0.0;
    }
    if (stuck != nullptr) *stuck = at_rest;
    // ceres::isfinite(Jet) looks at the value only; a NaN derivative would corrupt the
    // step just as well. Positions only accumulate, so the last one carries any NaN.
    return std::isfinite(motion.x.a) && motion.x.v.allFinite();
}

/// The Huber loss' scale a (and b = a², as ceres::HuberLoss keeps it), shared by the blocks.
struct HuberScale {
    double a = kFirstPassScale;
    double b = kFirstPassScale * kFirstPassScale;
};

/// One shooting segment as one Ceres residual block: (simulated - logged position) of each of
/// its fresh samples, in units of `unit_m`, with the Huber loss applied per sample inside the
/// block exactly as Ceres applies a loss to a one-residual block (residual_block.cc,
/// corrector.cc: cost ½ρ(r²), residual and Jacobian scaled by √ρ'(r²), no curvature term since
/// ρ'' <= 0 for Huber). The block's cost is ½ of its squared norm, so one more residual, with
/// a zero Jacobian, carries Σ (ρ(r²) - ρ'(r²) r²) over the samples outside the scale: cost,
/// gradient and Gauss-Newton matrix are those of one block per sample with a Huber loss each,
/// at one block (and one Jacobian row block) per segment instead of per sample.
class SegmentResidual final : public ceres::CostFunction {
  public:
    SegmentResidual(const AxisData& data, const SegmentRange& range, std::size_t fresh,
                    double unit_m, const HuberScale* huber)
        : force_(data.f->data() + range.start),
          logged_(data.x->data() + range.start),
          masked_(data.masked.data() + range.start),
          length_(range.length),
          period_s_(data.period_s),
          delay_(data.delay),
          inverse_unit_(1.0 / unit_m),
          huber_(huber) {
        set_num_residuals(static_cast<int>(fresh) + 1);
        mutable_parameter_block_sizes()->assign({kGlobalSize, kStateSize});
    }

    bool Evaluate(double const* const* parameters, double* residuals,
                  double** jacobians) const override {
        double* global_jacobian = jacobians != nullptr ? jacobians[0] : nullptr;
        double* state_jacobian = jacobians != nullptr ? jacobians[1] : nullptr;
        const double a = huber_->a;
        const double b = huber_->b;
        double excess = 0.0;
        std::size_t k = 0;  // the residual's index in the block
        const bool finite = simulate_segment(
            force_, length_, period_s_, delay_, parameters[0], parameters[1],
            [&](std::size_t j, const Jet& x) {
                if (masked_[j]) return;
                const double r = (x.a - logged_[j]) * inverse_unit_;
                const double s = r * r;
                double scale = 1.0;  // √ρ'(s): 1 inside the scale
                if (s > b) {         // ceres::HuberLoss::Evaluate, outlier region
                    const double root = std::sqrt(s);
                    const double rho0 = 2.0 * a * root - b;
                    const double rho1 = std::max(std::numeric_limits<double>::min(), a / root);
                    scale = std::sqrt(rho1);
                    const double corrected = r * scale;
                    excess += rho0 - corrected * corrected;
                }
                residuals[k] = s > b ? r * scale : r;
                if (global_jacobian != nullptr) {
                    for (int p = 0; p < kGlobalSize; ++p) {
                        const double d = x.v[p] * inverse_unit_;
                        global_jacobian[k * kGlobalSize + p] = s > b ? d * scale : d;
                    }
                }
                if (state_jacobian != nullptr) {
                    for (int p = 0; p < kStateSize; ++p) {
                        const double d = x.v[kGlobalSize + p] * inverse_unit_;
                        state_jacobian[k * kStateSize + p] = s > b ? d * scale : d;
                    }
                }
                ++k;
            });
        if (!finite) return false;
        residuals[k] = std::sqrt(std::max(excess, 0.0));
        if (global_jacobian != nullptr) {
            std::fill_n(global_jacobian + k * kGlobalSize, kGlobalSize, 0.0);
        }
        if (state_jacobian != nullptr)
            std::fill_n(state_jacobian + k * kStateSize, kStateSize, 0.0);
        return true;
    }

  private:
    const double* force_;
    const double* logged_;
    const char* masked_;
    std::size_t length_;
    double period_s_;
    HoldDelay delay_;
    double inverse_unit_;
    const HuberScale* huber_;
};

/// The covariance of (log m, log b, F_c, F_0).
struct Uncertainty {
    Matrix4 clustered;    ///< segment-clustered sandwich: what is reported
    Matrix4 independent;  ///< σ² (JᵀJ)⁻¹: residuals taken as independent
};

/// The output-error problem: one residual block per shooting segment (the Huber loss per
/// sample), the four parameters shared by all, two initial-state parameters per segment.
class OutputErrorFit {
  public:
    OutputErrorFit(const AxisData& data, const std::vector<SegmentRange>& ranges,
                   const detail::StartingGuess& guess, double unit_m, int max_iterations)
        : data_(data), unit_m_(unit_m) {
        const auto inside = [](double value, const double(&range)[2]) {
            return std::clamp(value, 2.0 * range[0], 0.5 * range[1]);
        };
        global_ = {std::log(inside(guess.mass_kg, kMassRangeKg)),
                   std::log(inside(guess.damping_n_s_per_m, kDampingRangeNsPerM)), guess.coulomb_n,
                   guess.offset_n};
        segments_.reserve(ranges.size());
        for (const SegmentRange& range : ranges) {
            segments_.push_back(
                {range,
                 {detail::initial_position(data, range), detail::initial_velocity(data, range)}});
        }
        problem_ = std::make_unique<ceres::Problem>();
        for (Segment& s : segments_) {
            const auto first = data.masked.begin() + static_cast<std::ptrdiff_t>(s.range.start);
            const auto fresh = static_cast<std::size_t>(
                std::count(first, first + static_cast<std::ptrdiff_t>(s.range.length), 0));
            problem_->AddResidualBlock(new SegmentResidual(data, s.range, fresh, unit_m, &huber_),
                                       nullptr, global_.data(), s.state.data());
            samples_ += fresh;
        }
        // m and b through their logarithms, inside a physical range. F_c is not bounded:
        // the model is defined for F_c < 0 (it never sticks), and a bound that is active
        // (a device without friction) stalls the trust region; see hold_coulomb_at_zero().
        problem_->SetParameterLowerBound(global_.data(), 0, std::log(kMassRangeKg[0]));
        problem_->SetParameterUpperBound(global_.data(), 0, std::log(kMassRangeKg[1]));
        problem_->SetParameterLowerBound(global_.data(), 1, std::log(kDampingRangeNsPerM[0]));
        problem_->SetParameterUpperBound(global_.data(), 1, std::log(kDampingRangeNsPerM[1]));

        options_.linear_solver_type = ceres::DENSE_SCHUR;
        options_.num_threads = 1;
        options_.max_num_iterations = max_iterations;
        options_.gradient_tolerance = 1e-14;
        options_.parameter_tolerance = 1e-10;
        options_.logging_type = ceres::SILENT;
    }

    /// Solves with a Huber loss of scale `huber_scale` (residual units) until the cost
    /// changes by less than `function_tolerance` (relative); refuses on failure.
    ceres::Solver::Summary solve(double huber_scale, double function_tolerance) {
        huber_ = {huber_scale, huber_scale * huber_scale};
        huber_scale_ = huber_scale;
        options_.function_tolerance = function_tolerance;
        // Schur elimination of the segments' states: the reduced system is 4 x 4. (A fresh
        // ordering each time: Ceres edits the one it is given.)
        auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
        for (Segment& s : segments_) ordering->AddElementToGroup(s.state.data(), 0);
        ordering->AddElementToGroup(global_.data(), 1);
        options_.linear_solver_ordering = ordering;
        ceres::Solver::Summary summary;
        ceres::Solve(options_, problem_.get(), &summary);
        iterations_ += static_cast<int>(summary.iterations.size()) - 1;
        if (summary.termination_type == ceres::FAILURE ||
            summary.termination_type == ceres::USER_FAILURE) {
            refuse(RefusalReason::fit_failed, "the fit failed: " + summary.message);
        }
        return summary;
    }

    /// Fits only the segments' initial states, the four parameters held: each segment on its
    /// own, so that the joint fit starts from states consistent with the starting guess.
    void solve_states() {
        problem_->SetParameterBlockConstant(global_.data());
        ceres::Solver::Options options = options_;
        options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;  // block diagonal
        options.linear_solver_ordering = nullptr;
        options.function_tolerance = tolerance(kFirstPassStepInStdErrors);
        options.max_num_iterations = 20;
        ceres::Solver::Summary summary;
        ceres::Solve(options, problem_.get(), &summary);
        iterations_ += static_cast<int>(summary.iterations.size()) - 1;
        problem_->SetParameterBlockVariable(global_.data());
    }

    /// Holds F_c at 0 from now on (a fit that wanted negative friction).
    void hold_coulomb_at_zero() {
        global_[kCoulombIndex] = 0.0;
        problem_->SetManifold(global_.data(),
                              new ceres::SubsetManifold(kGlobalSize, {kCoulombIndex}));
    }

    /// Robust standard deviation of the residuals (residual units): 1.4826 median |r|.
    double robust_sigma() {
        std::vector<double> magnitudes;
        magnitudes.reserve(samples_);
        for_each_residual(
            [&](double r, const Vector6&, std::size_t) { magnitudes.push_back(std::abs(r)); });
        return 1.4826 * median(std::move(magnitudes));
    }

    /// Fraction of the holds after which the fitted model's handle is at rest.
    double stuck_fraction() {
        std::size_t stuck = 0;
        std::size_t holds = 0;
        for (const Segment& s : segments_) {
            std::size_t at_rest = 0;
            simulate(
                s, [](std::size_t, const Jet&) {}, &at_rest);
            stuck += at_rest;
            holds += s.range.length - 1;
        }
        return static_cast<double>(stuck) / static_cast<double>(std::max<std::size_t>(holds, 1));
    }

    /// RMS of the residuals, m.
    double residual_rms_m() {
        double sum = 0.0;
        for_each_residual([&](double r, const Vector6&, std::size_t) { sum += r * r; });
        return std::sqrt(sum / static_cast<double>(samples_)) * unit_m_;
    }

    /// The covariance at the solution: the bread (JᵀJ)⁻¹ of the four parameters with the
    /// segments' states eliminated (the inverse of the Schur complement, what
    /// ceres::Covariance computed from a QR of the whole Jacobian), the meat from each
    /// segment's score. Refuses when the log cannot separate the parameters.
    Uncertainty uncertainty() {
        // Per segment: the information of its samples with the weights Ceres' Huber corrector
        // uses (1 inside the scale, δ/|r| outside), and its score Σ ψ(r) ∂r/∂θ; each folded
        // into the totals as soon as it is complete, so nothing here grows with the log.
        Matrix4 reduced = Matrix4::Zero();  // Σ_k A_k - B_k D_k⁻¹ B_kᵀ
        Matrix4 meat = Matrix4::Zero();     // Σ_k g_k g_kᵀ
        double sum_psi2 = 0.0;
        for (std::size_t k = 0; k < segments_.size(); ++k) {
            const Segment& s = segments_[k];
            Matrix6 information = Matrix6::Zero();
            Vector4 score = Vector4::Zero();
            simulate(s, [&](std::size_t j, const Jet& x) {
                const std::size_t row = s.range.start + j;
                if (data_.masked[row]) return;
                const double r = (x.a - (*data_.x)[row]) / unit_m_;
                const Vector6 J(x.v / unit_m_);
                const double weight =
                    std::abs(r) <= huber_scale_ ? 1.0 : huber_scale_ / std::abs(r);
                const double psi = std::clamp(r, -huber_scale_, huber_scale_);  // ρ'(r²) r
                information += weight * J * J.transpose();
                score += psi * J.head<kGlobalSize>();
                sum_psi2 += psi * psi;
            });
            reduced += reduced_information(k, information);
            meat += score * score.transpose();
        }
        const Matrix4 bread = check_information(reduced);

        // Sandwich with the segments as clusters: within a segment, force noise correlates
        // the residuals; across segments (each with its own initial state) it does not.
        const double clusters = static_cast<double>(segments_.size());
        if (clusters > 1.0) meat *= clusters / (clusters - 1.0);
        const double dof =
            std::max(1.0, static_cast<double>(samples_) - static_cast<double>(parameters()));
        return {bread * meat * bread, bread * (sum_psi2 / dof)};
    }

    /// The relative cost change that corresponds to a step of `k` standard errors.
    double tolerance(double k) const { return k * k / static_cast<double>(samples_); }

    const std::array<double, kGlobalSize>& global() const { return global_; }
    std::size_t samples() const { return samples_; }
    std::size_t segments() const { return segments_.size(); }
    std::size_t parameters() const { return kGlobalSize + kStateSize * segments_.size(); }
    int iterations() const { return iterations_; }

  private:
    struct Segment {
        SegmentRange range;
        std::array<double, kStateSize> state;
    };

    /// Simulates segment `s` at the current parameters (simulate_segment).
    template <typename Visit>
    bool simulate(const Segment& s, Visit&& visit, std::size_t* stuck = nullptr) const {
        return simulate_segment(data_.f->data() + s.range.start, s.range.length, data_.period_s,
                                data_.delay, global_.data(), s.state.data(),
                                std::forward<Visit>(visit), stuck);
    }

    /// Calls visit(residual, ∂residual/∂(global, state), segment) for every fresh sample at
    /// the current parameters, segment by segment.
    template <typename Visit>
    void for_each_residual(Visit visit) const {
        for (std::size_t k = 0; k < segments_.size(); ++k) {
            const Segment& s = segments_[k];
            simulate(s, [&](std::size_t j, const Jet& x) {
                const std::size_t row = s.range.start + j;
                if (data_.masked[row]) return;
                visit((x.a - (*data_.x)[row]) / unit_m_, Vector6(x.v / unit_m_), k);
            });
        }
    }

    /// Segment k's information M about (global, state), its state eliminated (Schur
    /// complement): A - B D⁻¹ Bᵀ. A segment that sits in stiction from its start has no use
    /// for v0 (any small v0 stops at once): its v0 is held (in the covariance and in any
    /// refit) and only x0 is eliminated.
    Matrix4 reduced_information(std::size_t k, const Matrix6& M) {
        const double span_s = static_cast<double>(segments_[k].range.length) * data_.period_s;
        const Matrix4 A = M.topLeftCorner<kGlobalSize, kGlobalSize>();
        if (M(5, 5) > 1e-10 * M(4, 4) * span_s * span_s) {
            const Eigen::Matrix<double, kGlobalSize, kStateSize> B =
                M.topRightCorner<kGlobalSize, kStateSize>();
            const Eigen::Matrix2d D = M.bottomRightCorner<kStateSize, kStateSize>();
            return A - B * D.ldlt().solve(B.transpose());
        }
        problem_->SetManifold(segments_[k].state.data(),
                              new ceres::SubsetManifold(kStateSize, {1}));
        const Vector4 b = M.block<kGlobalSize, 1>(0, kGlobalSize);
        return A - b * b.transpose() / M(4, 4);
    }

    /// The information about the four parameters once each segment's initial state is
    /// eliminated, scaled to unit diagonal: refuses if it is singular, naming the parameters
    /// the log cannot tell apart. Returns its inverse, the covariance of the four (JᵀJ)⁻¹
    /// (zero in F_c's row and column when F_c is held).
    Matrix4 check_information(const Matrix4& reduced) {
        const bool coulomb_held = problem_->GetManifold(global_.data()) != nullptr;
        Vector4 scale = reduced.diagonal().cwiseMax(0.0).cwiseSqrt();
        if (coulomb_held) scale[kCoulombIndex] = 1.0;  // its row is out of the problem
        for (int p = 0; p < kGlobalSize; ++p) {
            if (!(scale[p] > 0.0)) {
                refuse(RefusalReason::too_little_excitation,
                       std::string(kParameterNames[p]) +
                           " has no effect on the simulated positions of this log");
            }
        }
        Matrix4 normalized =
            scale.cwiseInverse().asDiagonal() * reduced * scale.cwiseInverse().asDiagonal();
        if (coulomb_held) {
            normalized.row(kCoulombIndex).setZero();
            normalized.col(kCoulombIndex).setZero();
            normalized(kCoulombIndex, kCoulombIndex) = 1.0;
        }
        const Eigen::SelfAdjointEigenSolver<Matrix4> eigen(normalized);
        if (!(eigen.eigenvalues()[0] > kMinInformationEigenvalue)) {
            std::string which;
            for (int p = 0; p < kGlobalSize; ++p) {
                if (std::abs(eigen.eigenvectors()(p, 0)) > 0.3) {
                    which += (which.empty() ? "" : " and ") + std::string(kParameterNames[p]);
                }
            }
            refuse(RefusalReason::too_little_excitation,
                   "the log cannot tell " + which +
                       " apart (the Jacobian of the fit is rank-deficient): the force needs "
                       "content above and below the mechanical corner b/(2 pi m), and the handle "
                       "must reverse direction for Coulomb friction to show apart from a "
                       "constant offset");
        }
        // The inverse through the scaled matrix (well conditioned: its eigenvalues passed
        // the check above); a held F_c has no variance.
        const Eigen::LLT<Matrix4> factor(normalized);
        Matrix4 inverse = factor.solve(Matrix4::Identity());
        if (factor.info() != Eigen::Success || !inverse.allFinite()) {
            refuse(RefusalReason::too_little_excitation,
                   "the information matrix of the fit is singular: the log cannot tell m, b, "
                   "F_c and F_0 apart");
        }
        if (coulomb_held) {
            inverse.row(kCoulombIndex).setZero();
            inverse.col(kCoulombIndex).setZero();
        }
        return scale.cwiseInverse().asDiagonal() * inverse * scale.cwiseInverse().asDiagonal();
    }

    const AxisData& data_;
    double unit_m_;
    // Read by every block (SegmentResidual); set by solve().
    HuberScale huber_;
    double huber_scale_ = kFirstPassScale;
    std::array<double, kGlobalSize> global_{};
    std::vector<Segment> segments_;
    std::unique_ptr<ceres::Problem> problem_;
    ceres::Solver::Options options_;
    std::size_t samples_ = 0;
    int iterations_ = 0;
};

AxisParameters std_errors(const Matrix4& c, double mass, double damping) {
    // m = e^{log m}: SE(m) = m SE(log m), to first order (the delta method).
    return {mass * std::sqrt(c(0, 0)), damping * std::sqrt(c(1, 1)), std::sqrt(c(2, 2)),
            std::sqrt(c(3, 3))};
}

/// Refuses a fit dominated by stick-slip, or whose standard errors say the log did not
/// determine it.
void check_precision(const IdentifiedAxis& fit, const AxisData& data,
                     const IdentificationOptions& options) {
    const double limit = options.max_relative_std_error;
    const AxisParameters& e = fit.estimate;
    const AxisParameters& se = fit.std_error;
    if (fit.stuck_fraction > options.max_stuck_fraction) {
        const double rms = detail::force_rms(data);
        refuse(RefusalReason::too_little_excitation,
               "the handle sat still, held by Coulomb friction (F_c = " + format(e.coulomb_n) +
                   " N), after " + percent(fit.stuck_fraction) + " of the periods (allowed " +
                   percent(options.max_stuck_fraction) +
                   "): stick-slip dominates the run, and force noise at each breakaway biases "
                   "the fit; raise the excitation (its RMS is " +
                   format(rms) + " N, " + format(rms / std::max(e.coulomb_n, 1e-300), 2) +
                   " F_c; 2.5 F_c or more keeps the handle moving)");
    }
    const double corner_hz = e.damping_n_s_per_m / (2.0 * std::numbers::pi * e.mass_kg);
    const auto explain = [&](const std::string& what, double value, double error,
                             const std::string& unit, const std::string& advice) {
        refuse(RefusalReason::too_little_excitation,
               "too little excitation to identify the " + what + ": " + format(value) + " ± " +
                   format(error) + " " + unit + " (relative standard error " +
                   percent(error / value) + ", allowed " + percent(limit) + "). " +
                   percent(detail::force_power_above(data, corner_hz)) +
                   " of the force's variance lies above the mechanical corner b/(2 pi m) = " +
                   format(corner_hz, 3) + " Hz; " + advice +
                   (options.delay_s > 0.0
                        ? std::string()
                        : ". Or the model misses the loop delay: a device whose forces act "
                          "after a delay (a serial or USB link) needs it (--delay; haptic-tune "
                          "diag measures it)"));
    };
    if (!(se.mass_kg <= limit * e.mass_kg)) {
        explain("mass m", e.mass_kg, se.mass_kg, "kg",
                "the mass shows above the corner: add force content there, raise the "
                "amplitude, or record longer");
    }
    if (!(se.damping_n_s_per_m <= limit * e.damping_n_s_per_m)) {
        explain("damping b", e.damping_n_s_per_m, se.damping_n_s_per_m, "N s/m",
                "the damping shows below the corner: add force content there, raise the "
                "amplitude, or record longer");
    }
    const double friction_limit = limit * detail::force_rms(data);
    if (!(se.coulomb_n <= friction_limit && se.offset_n <= friction_limit)) {
        refuse(RefusalReason::too_little_excitation,
               "too little excitation to tell Coulomb friction from the force offset: F_c = " +
                   format(e.coulomb_n) + " ± " + format(se.coulomb_n) +
                   " N, F_0 = " + format(e.offset_n) + " ± " + format(se.offset_n) +
                   " N (allowed standard error " + format(friction_limit) + " N, " +
                   percent(limit) + " of the force's RMS; correlation " +
                   format(fit.correlation[2][3], 3) +
                   "): the handle must reverse direction often, at speeds well above the "
                   "stiction region");
    }
}

}  // namespace

std::string_view to_string(RefusalReason reason) {
    switch (reason) {
        case RefusalReason::missing_column:
            return "missing_column";
        case RefusalReason::too_short:
            return "too_short";
        case RefusalReason::non_uniform_time:
            return "non_uniform_time";
        case RefusalReason::faults:
            return "faults";
        case RefusalReason::saturated:
            return "saturated";
        case RefusalReason::too_little_excitation:
            return "too_little_excitation";
        case RefusalReason::fit_failed:
            return "fit_failed";
    }
    return "unknown";
}

void IdentificationOptions::validate() const {
    if (!(std::isfinite(segment_s) && segment_s > 0.0))
        input::reject_out_of_range("identification option segment_s", segment_s, "> 0 s");
    if (resolution_m && !(std::isfinite(*resolution_m) && *resolution_m > 0.0)) {
        input::reject_out_of_range("identification option resolution_m", *resolution_m, "> 0 m");
    }
    if (!(std::isfinite(delay_s) && delay_s >= 0.0)) {
        input::reject_out_of_range("identification option delay_s", delay_s,
                                   ">= 0 s (and under 10 of the log's periods)");
    }
    if (force_limit_n && !(std::isfinite(*force_limit_n) && *force_limit_n > 0.0)) {
        input::reject_out_of_range("identification option force_limit_n", *force_limit_n, "> 0 N");
    }
    if (!(min_duration_s >= 0.0)) {
        input::reject_out_of_range("identification option min_duration_s", min_duration_s,
                                   ">= 0 s");
    }
    if (!(max_saturated_fraction >= 0.0 && max_saturated_fraction <= 1.0)) {
        input::reject_out_of_range("identification option max_saturated_fraction",
                                   max_saturated_fraction, "0 .. 1");
    }
    if (!(max_masked_fraction >= 0.0 && max_masked_fraction <= 1.0)) {
        input::reject_out_of_range("identification option max_masked_fraction", max_masked_fraction,
                                   "0 .. 1");
    }
    if (!(max_stuck_fraction >= 0.0 && max_stuck_fraction <= 1.0)) {
        input::reject_out_of_range("identification option max_stuck_fraction", max_stuck_fraction,
                                   "0 .. 1");
    }
    if (!(max_relative_std_error > 0.0)) {
        input::reject_out_of_range("identification option max_relative_std_error",
                                   max_relative_std_error, "> 0 (inf: no check)");
    }
    if (max_iterations < 1)
        input::reject_out_of_range("identification option max_iterations", max_iterations, ">= 1");
}

IdentifiedAxis identify_axis(const TelemetryLog& log, int axis,
                             const IdentificationOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    options.validate();
    const AxisData data = detail::prepare_axis(log, axis, options);
    const double q = data.resolution_m;
    const double unit_m = q > 0.0 ? q : kUnquantisedUnitM;
    const std::size_t target_samples = std::max<std::size_t>(
        detail::kMinSegmentSamples,
        static_cast<std::size_t>(std::lround(options.segment_s / data.period_s)));
    const std::vector<SegmentRange> ranges = detail::make_segments(data, target_samples);
    OutputErrorFit fit(data, ranges, detail::starting_guess(data, ranges), unit_m,
                       options.max_iterations);

    // Pass 1 from the starting guess with a wide loss; its residuals give the noise scale.
    fit.solve_states();
    fit.solve(kFirstPassScale, fit.tolerance(kFirstPassStepInStdErrors));
    const double quantisation_sigma = q > 0.0 ? 1.0 / std::sqrt(12.0) : 0.0;  // in units of q
    const double huber_scale = kHuberK * std::max(fit.robust_sigma(), quantisation_sigma);
    if (!(huber_scale > 0.0)) {
        refuse(RefusalReason::fit_failed,
               "the model reproduces the positions exactly: the log is not a run of a "
               "physical device");
    }
    // Pass 2 with the final scale.
    ceres::Solver::Summary summary = fit.solve(huber_scale, fit.tolerance(kFinalStepInStdErrors));
    Uncertainty uncertainty = fit.uncertainty();
    double coulomb_std_error = std::sqrt(uncertainty.clustered(kCoulombIndex, kCoulombIndex));
    bool coulomb_held = false;
    if (fit.global()[kCoulombIndex] < 0.0) {
        // Negative friction is not physical: the device has none the log can see. Refit with
        // F_c = 0; its standard error stays that of the free fit (how far from 0 it could be).
        fit.hold_coulomb_at_zero();
        summary = fit.solve(huber_scale, fit.tolerance(kFinalStepInStdErrors));
        uncertainty = fit.uncertainty();
        coulomb_held = true;
    }
    const std::array<double, kGlobalSize>& global = fit.global();
    for (const auto& [index, range, name] :
         {std::tuple{0, kMassRangeKg, "mass m (kg)"},
          std::tuple{1, kDampingRangeNsPerM, "damping b (N s/m)"}}) {
        const double value = std::exp(global[index]);
        if (value < 1.001 * range[0] || value > 0.999 * range[1]) {
            refuse(RefusalReason::too_little_excitation,
                   std::string("the fit ran the ") + name + " to the edge of its range [" +
                       format(range[0]) + ", " + format(range[1]) + "] (" + format(value) +
                       "): the log does not determine it");
        }
    }

    IdentifiedAxis result;
    result.axis = axis;
    const double mass = std::exp(global[0]);
    const double damping = std::exp(global[1]);
    result.estimate = {mass, damping, global[2], global[3]};
    result.std_error = std_errors(uncertainty.clustered, mass, damping);
    result.std_error_independent = std_errors(uncertainty.independent, mass, damping);
    if (coulomb_held) result.std_error.coulomb_n = coulomb_std_error;
    for (int i = 0; i < kGlobalSize; ++i) {
        for (int j = 0; j < kGlobalSize; ++j) {
            const double scale =
                std::sqrt(uncertainty.clustered(i, i) * uncertainty.clustered(j, j));
            result.correlation[i][j] = scale > 0.0 ? uncertainty.clustered(i, j) / scale : 0.0;
        }
    }
    result.residual_rms_m = fit.residual_rms_m();
    result.stuck_fraction = fit.stuck_fraction();
    result.residual_rms_counts =
        q > 0.0 ? result.residual_rms_m / q : std::numeric_limits<double>::quiet_NaN();
    result.resolution_m = q;
    result.resolution_estimated = data.resolution_estimated;
    result.delay_s = options.delay_s;
    result.rate_hz = 1.0 / data.period_s;
    result.duration_s = data.duration_s;
    result.samples = fit.samples();
    result.masked_samples = data.masked_count;
    result.segments = fit.segments();
    result.gaps = data.gaps;
    result.report.iterations = fit.iterations();
    result.report.converged = summary.termination_type == ceres::CONVERGENCE;
    result.report.termination = summary.message;
    result.report.huber_scale_m = huber_scale * unit_m;
    result.report.parameters = fit.parameters();
    result.report.coulomb_held_at_zero = coulomb_held;
    check_precision(result, data, options);
    result.report.solve_time_s = seconds_since(start);
    return result;
}

std::vector<IdentifiedAxis> identify_all_axes(const TelemetryLog& log,
                                              const IdentificationOptions& options) {
    std::vector<IdentifiedAxis> axes;
    axes.reserve(static_cast<std::size_t>(log.axes));
    for (int axis = 0; axis < log.axes; ++axis) axes.push_back(identify_axis(log, axis, options));
    return axes;
}

}  // namespace hapticd::tune
