// Deliberately broken device plugins for plugin_loader_test.cpp, one source built three ways:
//   HAPTICD_TEST_PLUGIN_BAD_ABI      exports the entry with abi_version 999
//   HAPTICD_TEST_PLUGIN_NULL_CREATE  a correct descriptor whose create() returns nullptr
//   HAPTICD_TEST_PLUGIN_NO_ENTRY     exports no entry symbol at all
#include "hapticd/device/plugin_abi.hpp"

#if defined(HAPTICD_TEST_PLUGIN_NO_ENTRY)

extern "C" __attribute__((visibility("default"))) int hapticd_not_a_device_plugin(void) {
    return 42;
}

#elif defined(HAPTICD_TEST_PLUGIN_BAD_ABI)

// Written out by hand: HAPTICD_DEVICE_PLUGIN always says this build's kDeviceAbiVersion.
namespace {
hapticd::device::Device* create_nothing() { return nullptr; }
void destroy_nothing(hapticd::device::Device*) {}
constexpr hapticd_device_plugin kPlugin{999, "badabi", "a broken plugin for tests", &create_nothing,
                                        &destroy_nothing};
}  // namespace

extern "C" __attribute__((visibility("default"))) const hapticd_device_plugin*
hapticd_device_plugin_entry(void) {
    return &kPlugin;
}

#else

HAPTICD_DEVICE_PLUGIN("nullcreate", "a broken plugin for tests", nullptr);

#endif
