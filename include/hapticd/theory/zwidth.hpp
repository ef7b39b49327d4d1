// Z-width, the range of impedances the interface can present to the operator,
// (23)-(26) for the impedance display and (39)-(43) for the admittance display.
#pragma once

#include "hapticd/theory/admittance.hpp"
#include "hapticd/theory/benchmark.hpp"

namespace hapticd::theory {

// The impedance display's model is a LoopModel: its hold term and the loop's delay, which
// enters through H (Z_max = Z_dI + Z_cI H e^{-jdθ}). The admittance display's models have
// no delay term.

/// (23): Z_P = Z_dI + Z_cI H Z_e / (Z_cI + Z_e), the impedance felt for environment Z_e.
Complex perceived_impedance(const DeviceModel& device, const SpringDamperCoupling& coupling,
                            const LoopModel& model, Complex environment_impedance, double theta,
                            double sample_period_s);

/// (24): Z_min = Z_dI (free space, Z_e -> 0).
Complex impedance_display_zmin(const DeviceModel& device, const LoopModel& model, double theta,
                               double sample_period_s);

/// (25): Z_max = Z_dI + Z_cI H (rigid environment, Z_e -> ∞).
Complex impedance_display_zmax(const DeviceModel& device, const SpringDamperCoupling& coupling,
                               const LoopModel& model, double theta, double sample_period_s);

/// (39): Y_P = 1/Z_dA + T Y_e / (1 + Z_cA Y_e), the admittance felt for environment Y_e.
Complex perceived_admittance(const DeviceModel& device, const PiVelocityLoop& loop,
                             const MassDamperCoupling& coupling, HoldModel model,
                             Complex environment_admittance, double theta, double sample_period_s);

/// (42): Z_min = Z_cA / (T + Z_cA/Z_dA) = 1/Y_max (Y_e -> ∞, free motion).
Complex admittance_display_zmin(const DeviceModel& device, const PiVelocityLoop& loop,
                                const MassDamperCoupling& coupling, HoldModel model, double theta,
                                double sample_period_s);

/// (43): Z_max = Z_dA (Y_e -> 0, rigid constraint).
Complex admittance_display_zmax(const DeviceModel& device, const PiVelocityLoop& loop,
                                HoldModel model, double theta, double sample_period_s);

}  // namespace hapticd::theory
