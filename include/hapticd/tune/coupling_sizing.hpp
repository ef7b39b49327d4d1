// Sizing the virtual coupling from (21) (impedance display) or (37) (admittance display)
// with Ceres. The formulation is documented in docs/sizing.md.
//
// Both conditions have the same shape: a coupling immittance of the family
//     W(z) = β + α T z/(z - 1)
// must satisfy Re(1/W) >= r(θ) at every frequency up to Nyquist.
//   impedance display (21): W = Z_cI (16), α = k_c, β = b_c, r = right side of (21);
//     with the damper's velocity filter, W = β B(z) + α T z/(z - 1) (velocity_filter.hpp);
//   admittance display (37): W = Y_cA (32), α = 1/m_c, β = 1/b_c, r = right side of (37)
// (the duality of Table I maps one onto the other). Performance wants α as large as
// possible (stiffest coupling, or lightest coupling mass).
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

#include "hapticd/input/input_error.hpp"
#include "hapticd/servo/rate.hpp"
#include "hapticd/theory/admittance.hpp"
#include "hapticd/theory/benchmark.hpp"

namespace hapticd::tune {

/// The requested coupling cannot satisfy the condition; what() says why.
class InfeasibleCoupling : public input::InputError {
  public:
    explicit InfeasibleCoupling(const std::string& message) : InputError(message, "infeasible") {}
};

/// How a sizing result was obtained (in the spirit of ceres::Solver::Summary).
struct SizingReport {
    std::string method;          ///< "tangency", "saddle", "dc-limit", "nyquist", "bracket"
    int ceres_iterations = 0;    ///< trust-region iterations of the final Ceres solve
    double solver_time_s = 0.0;  ///< wall time of the whole sizing, verification included
    int verify_points = 0;       ///< dense-grid points the answer was verified on
};

struct ImpedanceSizingRequest {
    theory::DeviceModel device;
    double rate_hz = servo::kDefaultRateHz;
    theory::LoopModel model{theory::HoldModel::passive};
    /// b_c to size k_c for; nullopt asks for the best (k_c, b_c) pair.
    std::optional<double> coupling_damping_n_s_per_m = 0.0;
    /// The damper's velocity filter, f_c (Hz; 0: none, else 1 Hz..rate/2): W = b_c B(z) +
    /// k_c T z/(z - 1) with B of theory/velocity_filter.hpp. The result's coupling carries it.
    double velocity_filter_hz = 0.0;
};

struct ImpedanceSizing {
    theory::SpringDamperCoupling coupling;
    /// Frequency where (21) holds with equality; 0 when it binds in the limit f -> 0.
    double binding_frequency_hz = 0.0;
    /// Smallest margin of (21) on the dense verification grid (>= 0 up to rounding).
    double verified_worst_margin = 0.0;
    SizingReport report;
};

/// The largest k_c (and with no b_c given, the b_c that allows it) such that (21) holds
/// at every frequency up to Nyquist. Throws std::invalid_argument for non-physical
/// input and InfeasibleCoupling when no k_c >= 0 works for the given b_c.
ImpedanceSizing size_impedance_coupling(const ImpedanceSizingRequest& request);

struct AdmittanceSizingRequest {
    theory::DeviceModel device;
    theory::PiVelocityLoop loop;
    double rate_hz = servo::kDefaultRateHz;
    theory::HoldModel model = theory::HoldModel::encoder;
    /// b_c to size m_c for (+inf for a pure mass); nullopt asks for the best pair.
    std::optional<double> coupling_damping_n_s_per_m;
};

struct AdmittanceSizing {
    theory::MassDamperCoupling coupling;
    double binding_frequency_hz = 0.0;
    double verified_worst_margin = 0.0;
    SizingReport report;
};

/// The smallest m_c (and with no b_c given, the b_c that allows it) such that (37) holds
/// at every frequency up to Nyquist. Throws InfeasibleCoupling, explaining why, when
/// (35) fails (the velocity loop is not passive at some frequency) or b_c is too small.
AdmittanceSizing size_admittance_coupling(const AdmittanceSizingRequest& request);

}  // namespace hapticd::tune
