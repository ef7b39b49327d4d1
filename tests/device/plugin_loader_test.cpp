// The device plugin loader: the sim plugin by name and by path, and every refusal with the
// message that says why (wrong ABI, missing entry, null create, dlopen error, not found);
// check_config() through the loader and through the C entry itself (the message cut to the
// buffer, never past it).
#include "hapticd/device/plugin_loader.hpp"

#include <dlfcn.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/install/plugin_files.hpp"
#include "scratch_dir.hpp"

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
    EXPECT_FALSE(device.link_quality().counted);  // across the ABI: the sim counts no link
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

TEST(DevicePluginLoader, CheckConfigGivesOpensMessageWithoutOpening) {
    DeviceConfig config;
    config.source = "bench.toml";
    config.plugin_table_toml = "mass = 0.2\ncoulomb = -1";
    const std::optional<std::string> refusal = check_plugin_config("sim", config);
    ASSERT_TRUE(refusal.has_value());
    EXPECT_NE(refusal->find("bench.toml:2: [device.sim] coulomb = -1 is out of range"),
              std::string::npos)
        << *refusal;
    // The same text open() gives for the same table.
    DeviceHandle device = load_device("sim");
    try {
        device->open(config);
        FAIL() << "bad coulomb accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_EQ(*refusal, e.what());
    }
    config.plugin_table_toml = "mass = 0.2\ncoulomb = 0.1";
    EXPECT_EQ(check_plugin_config("sim", config), std::nullopt);
    config.axes = 4;  // open()'s checks of DeviceConfig's own fields too
    EXPECT_NE(check_plugin_config(HAPTICD_TEST_SIM_PLUGIN, config).value_or("").find("device.axes"),
              std::string::npos);
}

TEST(DevicePluginLoader, CheckConfigOfAnUnloadablePluginThrowsLikeLoad) {
    PluginPath path(HAPTICD_TEST_PLUGIN_DIR);
    try {
        check_plugin_config("badabi", DeviceConfig{});
        FAIL() << "a plugin of another ABI was asked to check a table";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("ABI version 999"), std::string::npos) << e.what();
    }
    EXPECT_THROW(check_plugin_config("nosuch", DeviceConfig{}), std::runtime_error);
}

/// The nullcreate test plugin refuses any table with the table's own text as its message.
std::optional<std::string> echo(const std::string& text, std::size_t capacity) {
    DeviceConfig config;
    config.plugin_table_toml = text;
    return check_plugin_config(HAPTICD_TEST_PLUGIN_DIR "/hapticd-device-nullcreate.so", config,
                               capacity);
}

TEST(DevicePluginLoader, CheckConfigMessageIsCutToTheBuffer) {
    EXPECT_EQ(echo("", 64), std::nullopt);
    EXPECT_EQ(echo("short", 64), "short");
    EXPECT_EQ(echo("exactly9!", 10), "exactly9!");
    EXPECT_EQ(echo("exactly10!", 10), "exactly10");
    // Never in the middle of a UTF-8 character: "é" is two bytes (4 and 5).
    EXPECT_EQ(echo("abcd\xC3\xA9"
                   "fg",
                   6),
              "abcd");
    EXPECT_EQ(echo("abcd\xC3\xA9"
                   "fg",
                   7),
              "abcd\xC3\xA9");
    // A message longer than the loader's own buffer.
    const std::string huge(3 * kCheckMessageCapacity, 'x');
    EXPECT_EQ(echo(huge, kCheckMessageCapacity), huge.substr(0, kCheckMessageCapacity - 1));
    // Not a std::exception: still a message, no exception across the C ABI.
    EXPECT_NE(echo("throw 42", 256).value_or("").find("not a std::exception"), std::string::npos);
}

TEST(DevicePluginLoader, CheckConfigEntryWritesNothingPastItsCapacity) {
    void* library = dlopen(HAPTICD_TEST_PLUGIN_DIR "/hapticd-device-nullcreate.so", RTLD_NOW);
    ASSERT_NE(library, nullptr) << dlerror();
    using Entry = const hapticd_device_plugin* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(library, HAPTICD_DEVICE_PLUGIN_ENTRY_SYMBOL));
    ASSERT_NE(entry, nullptr);
    const hapticd_device_plugin* plugin = entry();
    ASSERT_NE(plugin->check_config, nullptr);
    DeviceConfig config;
    config.plugin_table_toml = std::string(100, 'm');
    std::array<char, 32> buffer{};
    buffer.fill('#');
    EXPECT_FALSE(plugin->check_config(&config, buffer.data(), 8));
    EXPECT_EQ(std::string(buffer.data()), "mmmmmmm");
    for (std::size_t i = 8; i < buffer.size(); ++i) EXPECT_EQ(buffer[i], '#') << i;
    buffer.fill('#');
    EXPECT_FALSE(plugin->check_config(&config, buffer.data(), 0));  // room for nothing
    EXPECT_EQ(buffer[0], '#');
    EXPECT_FALSE(plugin->check_config(nullptr, buffer.data(), buffer.size()));
    EXPECT_NE(std::string(buffer.data()).find("was given no"), std::string::npos);
    config.plugin_table_toml.clear();
    EXPECT_TRUE(plugin->check_config(&config, buffer.data(), buffer.size()));
    dlclose(library);
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
    const hapticd::testing::ScratchDir dir;
    const std::string fake = dir.write("hapticd-device-fake.so", "not an ELF file\n");
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
    const auto dirs = install::plugin_search_path();
    ASSERT_EQ(dirs.size(), 3u);
    EXPECT_EQ(dirs[0], "/x");
    EXPECT_EQ(dirs[1], "/y");
    EXPECT_EQ(dirs[2], HAPTICD_TEST_BUILD_PLUGIN_DIR);
    EXPECT_EQ(install::plugin_file_names("device", "sim"),
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
