#include "hapticd/device/plugin_loader.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "hapticd/device/plugin_abi.hpp"
#include "hapticd/install/plugin_files.hpp"

namespace hapticd::device {
namespace {

constexpr std::string_view kKind = "device";
constexpr std::string_view kFilePrefix = "hapticd-device-";
constexpr std::string_view kFileSuffix = ".so";

std::string dl_error_text() {
    const char* text = dlerror();
    return text != nullptr ? text : "unknown dynamic-loader error";
}

/// The descriptor of an opened library, after the ABI check; empty `error` on success.
const hapticd_device_plugin* entry_of(void* library, std::string& error) {
    dlerror();
    void* symbol = dlsym(library, HAPTICD_DEVICE_PLUGIN_ENTRY_SYMBOL);
    if (symbol == nullptr) {
        error = std::string("it does not export the entry symbol '") +
                HAPTICD_DEVICE_PLUGIN_ENTRY_SYMBOL + "' (" + dl_error_text() + ")";
        return nullptr;
    }
    using EntryFunction = const hapticd_device_plugin* (*)();
    const auto entry = reinterpret_cast<EntryFunction>(symbol);
    const hapticd_device_plugin* plugin = entry();
    if (plugin == nullptr) {
        error = std::string("its entry '") + HAPTICD_DEVICE_PLUGIN_ENTRY_SYMBOL +
                "' returned a null descriptor";
        return nullptr;
    }
    // abi_version is the first member in every ABI version: read it before anything else.
    if (plugin->abi_version != kDeviceAbiVersion) {
        error = "it was built for device plugin ABI version " +
                std::to_string(plugin->abi_version) + ", but this hapticd speaks version " +
                std::to_string(kDeviceAbiVersion) + "; rebuild the plugin against this hapticd";
        return nullptr;
    }
    if (plugin->create == nullptr || plugin->destroy == nullptr ||
        plugin->check_config == nullptr) {
        error = "its descriptor has a null create, destroy or check_config function";
        return nullptr;
    }
    return plugin;
}

[[noreturn]] void fail(std::string_view what, const std::string& path, const std::string& why) {
    throw std::runtime_error("device plugin '" + std::string(what) + "' (" + path +
                             ") cannot be used: " + why);
}

/// An opened library and its descriptor, after the ABI check.
struct LoadedPlugin {
    std::shared_ptr<void> library;
    const hapticd_device_plugin* plugin = nullptr;
    std::string path;
};

LoadedPlugin open_plugin(std::string_view what, const std::string& path) {
    std::string error;
    std::shared_ptr<void> library = install::open_plugin_library(path, error);
    if (!library) fail(what, path, "dlopen failed: " + error);
    const hapticd_device_plugin* plugin = entry_of(library.get(), error);
    if (plugin == nullptr) fail(what, path, error);
    return {std::move(library), plugin, path};
}

/// The plugin `name_or_path` found (install/plugin_files.hpp), opened and checked.
LoadedPlugin find_plugin(std::string_view name_or_path) {
    return open_plugin(name_or_path, install::find_plugin_file(kKind, name_or_path));
}

}  // namespace

DeviceHandle load_device(std::string_view name_or_path) {
    LoadedPlugin loaded = find_plugin(name_or_path);
    const hapticd_device_plugin* plugin = loaded.plugin;
    const std::string& path = loaded.path;
    const std::string_view what = name_or_path;
    Device* device = nullptr;
    try {
        device = plugin->create();
    } catch (const std::exception& e) {
        fail(what, path, std::string("create() threw: ") + e.what());
    }
    if (device == nullptr) fail(what, path, "create() returned a null device");
    return DeviceHandle(device, PluginDeleter(plugin->destroy, std::move(loaded.library)));
}

std::optional<std::string> check_plugin_config(std::string_view name_or_path,
                                               const DeviceConfig& config, std::size_t capacity) {
    const LoadedPlugin loaded = find_plugin(name_or_path);
    // The message is written into our buffer, so nothing of the plugin's outlives it.
    std::string message(std::max<std::size_t>(capacity, 1), '\0');
    if (loaded.plugin->check_config(&config, message.data(), message.size())) return std::nullopt;
    message.resize(std::strlen(message.c_str()));
    return message;
}

void PluginDeleter::operator()(Device* device) const noexcept {
    if (device != nullptr && destroy_ != nullptr) destroy_(device);
    // library_ is released after this, when the unique_ptr's deleter itself is destroyed.
}

std::vector<PluginListing> list_plugins() {
    std::vector<PluginListing> listings;
    std::vector<std::string> seen_names;
    for (const std::string& dir : install::plugin_search_path()) {
        std::error_code ec;
        std::vector<std::string> files;
        for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
            const std::string file = entry.path().filename().string();
            std::string_view stem(file);
            if (stem.starts_with("lib")) stem.remove_prefix(3);
            if (!stem.starts_with(kFilePrefix) || !stem.ends_with(kFileSuffix)) continue;
            files.push_back(file);
        }
        std::sort(files.begin(), files.end());
        for (const std::string& file : files) {
            PluginListing listing;
            listing.path = dir + "/" + file;
            std::string_view stem(file);
            if (stem.starts_with("lib")) stem.remove_prefix(3);
            stem.remove_prefix(kFilePrefix.size());
            stem.remove_suffix(kFileSuffix.size());
            listing.name = std::string(stem);
            std::string error;
            if (std::shared_ptr<void> library = install::open_plugin_library(listing.path, error)) {
                if (const hapticd_device_plugin* plugin = entry_of(library.get(), error)) {
                    if (plugin->name != nullptr) listing.name = plugin->name;
                    if (plugin->description != nullptr) listing.description = plugin->description;
                }
                // The version is reported even when it is the wrong one.
                if (void* symbol = dlsym(library.get(), HAPTICD_DEVICE_PLUGIN_ENTRY_SYMBOL)) {
                    using EntryFunction = const hapticd_device_plugin* (*)();
                    if (const auto* p = reinterpret_cast<EntryFunction>(symbol)(); p != nullptr) {
                        listing.abi_version = p->abi_version;
                    }
                }
            } else {
                error = "dlopen failed: " + error;
            }
            listing.error = error;
            listing.shadowed =
                std::find(seen_names.begin(), seen_names.end(), listing.name) != seen_names.end();
            seen_names.push_back(listing.name);
            listings.push_back(std::move(listing));
        }
    }
    return listings;
}

}  // namespace hapticd::device
