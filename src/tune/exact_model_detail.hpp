// The exact model's building blocks that the exact admittance loop shares with it
// (exact_model.cpp keeps them in its anonymous namespace; these forward to them).
// Internal to hapticd_tune.
#pragma once

#include <Eigen/Dense>
#include <utility>
#include <vector>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/tune/exact_model.hpp"

namespace hapticd::tune::detail {

/// Continuous device (10) with the operator attached, ds/dt = A s + B F_d. States: [x_d, v_d],
/// then [x_i, v_i] for every mass hung off the handle (the two-mass grasp's hand, the
/// multi-mode grasp's absorbers).
void operator_plant(const theory::DeviceModel& device, const OperatorModel& human,
                    Eigen::MatrixXd& a, Eigen::VectorXd& b);

/// e^{A t} and ∫_0^t e^{Aτ} dτ B.
std::pair<Eigen::MatrixXd, Eigen::VectorXd> zoh_sample(const Eigen::MatrixXd& a,
                                                       const Eigen::VectorXd& b, double t);

/// Throws std::invalid_argument naming a non-physical or unused operator field.
void validate_operator(const OperatorModel& human);

/// n points from lo to hi, equally spaced in log(value): the sweeps' grids.
std::vector<double> log_grid(double lo, double hi, int n);

/// Parlett-Reinsch balancing by powers of two (exact: it changes no eigenvalue).
void balance_loop(Eigen::MatrixXd& loop);

/// The closed loop's poles from its matrix's eigenvalues: the spectral radius (stable below
/// 1) and the dominant pole's frequency for the period `period_s`.
ClosedLoopPoles poles_from_eigenvalues(const Eigen::Ref<const Eigen::VectorXcd>& eigenvalues,
                                       double period_s);

}  // namespace hapticd::tune::detail
