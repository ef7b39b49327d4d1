#include "hapticd/device/sim/sim_config.hpp"

namespace hapticd::device::sim {

double PushProfile::set_point_m(double t_s) const noexcept {
    if (is_fixed() || t_s <= start_s) return from_m;
    const double span_m = to_m - from_m;
    double t = t_s - start_s;
    if (t < ramp_s) return from_m + span_m * (t / ramp_s);  // ramp out
    t -= ramp_s;
    if (t < hold_s) return to_m;  // hold
    t -= hold_s;
    if (t < ramp_s) return to_m - span_m * (t / ramp_s);  // ramp back
    return from_m;
}

}  // namespace hapticd::device::sim
