// The `sim` plugin's entry point (plugin_abi.hpp).
#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/device/sim/sim_config.hpp"
#include "hapticd/device/sim/sim_device.hpp"

namespace {

/// [device.sim] as SimDevice::open() reads it (parse_sim_config), and nothing opened.
void check_sim_table(const hapticd::device::DeviceConfig& config) {
    (void)hapticd::device::sim::parse_sim_config(config);
}

}  // namespace

HAPTICD_DEVICE_PLUGIN("sim",
                      "simulated device: mass-damper (10) per axis with a passive human model, "
                      "exact ZOH, encoder quantisation, loop delay, fault injection; lockstep or "
                      "realtime clock",
                      check_sim_table, new hapticd::device::sim::SimDevice());
