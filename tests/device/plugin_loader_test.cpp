// The device plugin loader: the sim plugin by name and by path, and every refusal with the
// message that says why (wrong ABI, missing entry, null create, dlopen error, not found).
#include "hapticd/device/plugin_loader.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>

#include "hapticd/device/plugin_abi.hpp"

namespace hapticd::device {
namespace {

/// Sets HAPTICD_PLUGIN_PATH for one test and restores it afterwards.
class PluginPath {
  public:
    explicit PluginPath(const char* value) {
        if (const char* old = std::getenv("HAPTICD_PLUGIN_PATH")) saved_ = old, had_ = true;
        if (value != nullptr) {
            setenv("HAPTICD_PLUGIN_PATH", value, 1);
        } else {
            unsetenv("HAPTICD_PLUGIN_PATH");
        }
    }
    ~PluginPath() {
        if (had_) {
            setenv("HAPTICD_PLUGIN_PATH", saved_.c_str(), 1);
        } else {
            unsetenv("HAPTICD_PLUGIN_PATH");
        }
    }

  private:
    std::string saved_;
    bool had_ = false;
};

std::string load_error(const std::string& name_or_path) {
    try {
        load_device(name_or_path);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    ADD_FAILURE() << "loading '" << name_or_path << "' did not fail";
    return {};
}

void expect_working_sim(Device& device) {
    DeviceConfig config;
    config.axes = 2;
    config.lockstep = true;
    config.plugin_table_toml = "mass = 0.2\ninitial_position = [0.01, 0.0]";
    device.open(config);
    const DeviceInfo info = device.info();
    EXPECT_EQ(info.name, "sim");
    EXPECT_EQ(info.axes, 2);
    EXPECT_TRUE(info.lockstep);
    Sample sample;
    ASSERT_EQ(device.read(sample), IoResult::ok);
    EXPECT_EQ(sample.encoder_counts[0], 1000);
    Command command;
    command.enable = true;
    command.force_n = {20.0, 20.0, 0.0};  // x(T) ~ F T²/(2m) = 50 µm: 5 counts
    EXPECT_EQ(device.write(command), IoResult::ok);
    ASSERT_EQ(device.read(sample), IoResult::ok);
    EXPECT_EQ(sample.sequence, 1u);
    EXPECT_EQ(sample.encoder_counts[1], 4);  // floor(4.98): x(T) = (F/b)(T - τ(1 - e^{-T/τ}))
    device.close();
}

TEST(DevicePluginLoader, LoadsTheSimByNameFromTheBuildTree) {
    PluginPath path(nullptr);
    DeviceHandle device = load_device("sim");
    ASSERT_NE(device, nullptr);
    expect_working_sim(*device);
}

TEST(DevicePluginLoader, LoadsTheSimByPath) {
    DeviceHandle device = load_device(HAPTICD_TEST_SIM_PLUGIN);
    ASSERT_NE(device, nullptr);
    expect_working_sim(*device);
}

TEST(DevicePluginLoader, ConfigErrorsFromThePluginArriveAsRuntimeErrors) {
    DeviceHandle device = load_device("sim");
    DeviceConfig config;
    config.source = "bench.toml";
    config.plugin_table_toml = "mass = -1";
    try {
        device->open(config);
        FAIL() << "bad mass accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("bench.toml:1: [device.sim] mass = -1"),
                  std::string::npos)
            << e.what();
    }
}

TEST(DevicePluginLoader, TwoDevicesFromOnePluginAreIndependent) {
    DeviceHandle a = load_device("sim");
    DeviceHandle b = load_device("sim");
    EXPECT_NE(a.get(), b.get());
    a.reset();  // the library stays open for b
    expect_working_sim(*b);
}

TEST(DevicePluginLoader, WrongAbiVersionSaysBothNumbers) {
    const std::string e = load_error(HAPTICD_TEST_PLUGIN_DIR "/hapticd-device-badabi.so");
    EXPECT_NE(e.find("hapticd-device-badabi.so"), std::string::npos) << e;
    EXPECT_NE(e.find("ABI version 999"), std::string::npos) << e;
    EXPECT_NE(e.find("version " + std::to_string(kDeviceAbiVersion)), std::string::npos) << e;
}

TEST(DevicePluginLoader, MissingEntrySymbolIsNamed) {
    const std::string e = load_error(HAPTICD_TEST_PLUGIN_DIR "/hapticd-device-noentry.so");
    EXPECT_NE(e.find("does not export the entry symbol 'hapticd_device_plugin_entry'"),
              std::string::npos)
        << e;
}

TEST(DevicePluginLoader, NullCreateIsRefused) {
    const std::string e = load_error(HAPTICD_TEST_PLUGIN_DIR "/hapticd-device-nullcreate.so");
    EXPECT_NE(e.find("create() returned a null device"), std::string::npos) << e;
}

TEST(DevicePluginLoader, DlopenErrorTextIsPassedOn) {
    const std::string fake = ::testing::TempDir() + "/hapticd-device-fake.so";
    std::ofstream(fake) << "not an ELF file\n";
    const std::string e = load_error(fake);
    EXPECT_NE(e.find("dlopen failed"), std::string::npos) << e;
    EXPECT_NE(e.find(fake), std::string::npos) << e;
    EXPECT_NE(load_error("/nonexistent/dir/hapticd-device-x.so").find("dlopen failed"),
              std::string::npos);
}

TEST(DevicePluginLoader, NotFoundListsEveryPlaceSearched) {
    PluginPath path("/nonexistent/a::/nonexistent/b");
    const std::string e = load_error("nosuch");
    EXPECT_NE(e.find("device plugin 'nosuch' not found"), std::string::npos) << e;
    EXPECT_NE(e.find("/nonexistent/a/libhapticd-device-nosuch.so"), std::string::npos) << e;
    EXPECT_NE(e.find("/nonexistent/a/hapticd-device-nosuch.so"), std::string::npos) << e;
    EXPECT_NE(e.find("/nonexistent/b/hapticd-device-nosuch.so"), std::string::npos) << e;
    EXPECT_NE(e.find(HAPTICD_TEST_BUILD_PLUGIN_DIR "/hapticd-device-nosuch.so"), std::string::npos)
        << e;
    // A build tree's executable looks in its own build tree only, not in an installation.
    const std::string_view any_plugin_dir = "hapticd/plugins/libhapticd-device-nosuch.so";
    EXPECT_EQ(e.find(any_plugin_dir), e.rfind(any_plugin_dir)) << e;
    EXPECT_NE(e.find("HAPTICD_PLUGIN_PATH"), std::string::npos) << e;
}

TEST(DevicePluginLoader, SearchPathPutsTheEnvironmentFirst) {
    PluginPath path("/x:/y");
    const auto dirs = plugin_search_path();
    ASSERT_EQ(dirs.size(), 3u);
    EXPECT_EQ(dirs[0], "/x");
    EXPECT_EQ(dirs[1], "/y");
    EXPECT_EQ(dirs[2], HAPTICD_TEST_BUILD_PLUGIN_DIR);
    EXPECT_EQ(plugin_file_names("sim"),
              (std::vector<std::string>{"libhapticd-device-sim.so", "hapticd-device-sim.so"}));
}

TEST(DevicePluginLoader, NamesAreFoundOnTheEnvironmentPath) {
    PluginPath path(HAPTICD_TEST_PLUGIN_DIR);
    EXPECT_NE(load_error("badabi").find("ABI version 999"), std::string::npos);
    EXPECT_NE(load_error("nullcreate").find("null device"), std::string::npos);
}

TEST(DevicePluginLoader, ListsPluginsWithTheirProblems) {
    PluginPath path(HAPTICD_TEST_PLUGIN_DIR);
    const auto listings = list_plugins();
    auto find = [&](const std::string& name) -> const PluginListing* {
        for (const auto& l : listings) {
            if (l.name == name && !l.shadowed) return &l;
        }
        return nullptr;
    };
    const PluginListing* sim = find("sim");
    ASSERT_NE(sim, nullptr);
    EXPECT_EQ(sim->error, "");
    EXPECT_EQ(sim->abi_version, kDeviceAbiVersion);
    EXPECT_NE(sim->description.find("simulated"), std::string::npos);
    const PluginListing* bad = find("badabi");
    ASSERT_NE(bad, nullptr);
    EXPECT_EQ(bad->abi_version, 999u);
    EXPECT_NE(bad->error.find("ABI version 999"), std::string::npos);
    const PluginListing* noentry = find("noentry");
    ASSERT_NE(noentry, nullptr);
    EXPECT_NE(noentry->error.find("entry symbol"), std::string::npos);
    // nullcreate is only found unusable when create() runs; its descriptor is fine.
    ASSERT_NE(find("nullcreate"), nullptr);
}

}  // namespace
}  // namespace hapticd::device
