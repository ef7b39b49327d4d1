// The `sim` plugin's entry point (plugin_abi.hpp).
#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/device/sim/sim_device.hpp"

HAPTICD_DEVICE_PLUGIN("sim",
                      "simulated device: mass-damper (10) per axis with a passive human model, "
                      "exact ZOH, encoder quantisation, loop delay, fault injection; lockstep or "
                      "realtime clock",
                      new hapticd::device::sim::SimDevice());
