// The `sim` plugin's entry point (plugin_abi.hpp).
#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/device/sim/sim_device.hpp"

namespace {

hapticd::device::Device* create_sim() { return new hapticd::device::sim::SimDevice(); }
void destroy_sim(hapticd::device::Device* device) { delete device; }

constexpr hapticd_device_plugin kSimPlugin{
    hapticd::device::kDeviceAbiVersion,
    "sim",
    "simulated device: mass-damper (10) per axis with a passive human model, exact ZOH, "
    "encoder quantisation, loop delay, fault injection; lockstep or realtime clock",
    &create_sim,
    &destroy_sim,
};

}  // namespace

extern "C" __attribute__((visibility("default"))) const hapticd_device_plugin*
hapticd_device_plugin_entry(void) {
    return &kSimPlugin;
}
