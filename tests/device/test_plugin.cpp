// Deliberately broken device plugins for plugin_loader_test.cpp, one source built three ways:
//   HAPTICD_TEST_PLUGIN_BAD_ABI      exports the entry with abi_version 999
//   HAPTICD_TEST_PLUGIN_NULL_CREATE  a correct descriptor whose create() returns nullptr, and
//                                    whose check_config() refuses any non-empty table with
//                                    the table's own text as its message ("throw 42": throws
//                                    an int), so that tests choose the message
//   HAPTICD_TEST_PLUGIN_NO_ENTRY     exports no entry symbol at all
#include <stdexcept>

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
bool check_nothing(const hapticd::device::DeviceConfig*, char*, std::size_t) { return true; }
constexpr hapticd_device_plugin kPlugin{
    999, "badabi", "a broken plugin for tests", &create_nothing, &destroy_nothing, &check_nothing};
}  // namespace

extern "C" __attribute__((visibility("default"))) const hapticd_device_plugin*
hapticd_device_plugin_entry(void) {
    return &kPlugin;
}

#else

namespace {

void check_echo(const hapticd::device::DeviceConfig& config) {
    if (config.plugin_table_toml == "throw 42") throw 42;
    if (!config.plugin_table_toml.empty()) throw std::runtime_error(config.plugin_table_toml);
}

}  // namespace

HAPTICD_DEVICE_PLUGIN("nullcreate", "a broken plugin for tests", check_echo, nullptr);

#endif
