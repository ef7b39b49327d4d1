// The device plugin ABI: every plugin is a shared object exporting one C symbol,
//
//     extern "C" const hapticd_device_plugin* hapticd_device_plugin_entry(void);
//
// which returns a static descriptor. The loader (plugin_loader.hpp) checks abi_version
// before it touches anything else, so a plugin built against another ABI is refused with
// a clear message rather than crashing. A plugin defines the entry with one line,
// HAPTICD_DEVICE_PLUGIN (below). Bump kDeviceAbiVersion whenever the descriptor, Device,
// Sample, Command, DeviceInfo, DeviceConfig or LinkQuality change layout or meaning: the layout
// asserts at the end of this file fail the build on a change of layout until the version is bumped
// and the new layout recorded.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <string>
#include <string_view>
#include <type_traits>

#include "hapticd/device/device.hpp"

extern "C" {

struct hapticd_device_plugin {
    std::uint32_t abi_version;                  ///< must equal hapticd::device::kDeviceAbiVersion
    const char* name;                           ///< the plugin's name, e.g. "sim"
    const char* description;                    ///< one line for `hapticd --list-plugins`
    hapticd::device::Device* (*create)();       ///< a new, unopened device
    void (*destroy)(hapticd::device::Device*);  ///< deletes what create() returned
    /// Checks `config` (its [device.<plugin>] table, axes and rate) exactly as open() reads
    /// it, without opening anything. True: open() would accept the table. False: open()
    /// would refuse it, and `message` (of `capacity` bytes, capacity > 0) holds open()'s
    /// message, NUL-terminated, cut at a UTF-8 character boundary when it does not fit.
    /// Throws nothing (ABI version 4 on).
    bool (*check_config)(const hapticd::device::DeviceConfig* config, char* message,
                         std::size_t capacity);
};

/// The one symbol a plugin exports.
const hapticd_device_plugin* hapticd_device_plugin_entry(void);
}

#define HAPTICD_DEVICE_PLUGIN_ENTRY_SYMBOL "hapticd_device_plugin_entry"

/// Defines a plugin's entry point: the descriptor of a plugin called `name` (a string
/// literal, e.g. "sim") with a one-line `description`, built for this kDeviceAbiVersion,
/// whose check_config() runs `check` (a function `void check(const DeviceConfig&)` that
/// reads the table as open() does and throws open()'s exception when it is bad), whose
/// create() returns the expression after them (a new, unopened device) and whose destroy()
/// deletes it. Once, at file scope, in one source file of the plugin:
///
///     HAPTICD_DEVICE_PLUGIN("sim", "simulated device: ...", check_sim_table,
///                           new hapticd::device::sim::SimDevice());
#define HAPTICD_DEVICE_PLUGIN(name, description, check, ...)                                       \
    extern "C" __attribute__((visibility("default"))) const hapticd_device_plugin*                 \
    hapticd_device_plugin_entry(void) {                                                            \
        static constexpr hapticd_device_plugin kPlugin{                                            \
            ::hapticd::device::kDeviceAbiVersion,                                                  \
            name,                                                                                  \
            description,                                                                           \
            []() -> ::hapticd::device::Device* { return __VA_ARGS__; },                            \
            [](::hapticd::device::Device* device) { delete device; },                              \
            [](const ::hapticd::device::DeviceConfig* config, char* message,                       \
               std::size_t capacity) noexcept -> bool {                                            \
                return ::hapticd::device::plugin_abi::run_check(check, config, message, capacity); \
            }};                                                                                    \
        return &kPlugin;                                                                           \
    }                                                                                              \
    static_assert(true, "HAPTICD_DEVICE_PLUGIN(...) ends with a semicolon")

namespace hapticd::device {

inline constexpr std::uint32_t kDeviceAbiVersion = 5;

/// The plugin's side of check_config(), compiled into each plugin by HAPTICD_DEVICE_PLUGIN.
namespace plugin_abi {

/// Copies `text` into `message` (`capacity` bytes), NUL-terminated; cut, when it does not
/// fit, before the UTF-8 character that would not fit whole. Nothing when capacity is 0.
inline void copy_message(std::string_view text, char* message, std::size_t capacity) noexcept {
    if (message == nullptr || capacity == 0) return;
    std::size_t size = text.size();
    if (size >= capacity) {
        size = capacity - 1;
        // Back to the first byte of the character at the cut (continuation bytes: 10xxxxxx).
        while (size > 0 && (static_cast<unsigned char>(text[size]) & 0xC0u) == 0x80u) --size;
    }
    std::memcpy(message, text.data(), size);
    message[size] = '\0';
}

/// Runs `check` on `*config`: true when it returns; false with its message when it throws.
/// No exception leaves (what a plugin throws must not cross the C ABI).
inline bool run_check(void (*check)(const DeviceConfig&), const DeviceConfig* config, char* message,
                      std::size_t capacity) noexcept {
    try {
        if (config == nullptr) {
            copy_message("check_config() was given no config", message, capacity);
            return false;
        }
        check(*config);
        return true;
    } catch (const std::exception& e) {
        copy_message(e.what(), message, capacity);
    } catch (...) {
        constexpr std::string_view kWhat =
            ": the plugin's check of its table threw something that is not a std::exception";
        try {
            copy_message(config->source + std::string(kWhat), message, capacity);
        } catch (...) {  // no memory for the source's name
            copy_message(kWhat.substr(2), message, capacity);
        }
    }
    return false;
}

}  // namespace plugin_abi

// The layout of ABI version 5: size, alignment and offset in bytes of every type and field
// that crosses the plugin boundary, on the LP64 Linux targets with libstdc++ that hapticd
// builds on (x86_64, aarch64). The daemon and every plugin compile these asserts, so a
// plugin built where a type lays out otherwise (another std::string ABI, say) fails to build.
// A failing assert means that a type changed: bump kDeviceAbiVersion, then write the new
// figures here under the new number. The figures of a released version never change.
// (Device's virtual functions cross too: their signatures are asserted; their order, which
// the vtable depends on, only a reviewer can see: open, info, read, write, close,
// link_quality after the destructor's entries.)
#if defined(__LP64__) && defined(__GLIBCXX__)

static_assert(kDeviceAbiVersion == 5,
              "plugin_abi.hpp: the layout figures below are device plugin ABI version 5's; "
              "write the new version's figures and its number");

#define HAPTICD_ABI_LAYOUT(expression, figure)                                           \
    static_assert((expression) == (figure),                                              \
                  "the device plugin ABI changed: " #expression " is no longer " #figure \
                  "; bump kDeviceAbiVersion (plugin_abi.hpp) and record the new layout")
/// `type::field` is a `...` (the field's type) at `offset`.
#define HAPTICD_ABI_FIELD(type, field, offset, ...)                                             \
    static_assert(std::is_same_v<decltype(type::field), __VA_ARGS__>,                           \
                  "the device plugin ABI changed: " #type "::" #field                           \
                  " is no longer a " #__VA_ARGS__ "; bump kDeviceAbiVersion (plugin_abi.hpp)"); \
    HAPTICD_ABI_LAYOUT(offsetof(type, field), offset)
/// Device::function is a virtual function of this signature (a pointer-to-member type).
#define HAPTICD_ABI_VIRTUAL(function, ...)                                  \
    static_assert(std::is_same_v<decltype(&Device::function), __VA_ARGS__>, \
                  "the device plugin ABI changed: Device::" #function       \
                  " is no longer " #__VA_ARGS__ "; bump kDeviceAbiVersion (plugin_abi.hpp)")

HAPTICD_ABI_LAYOUT(sizeof(std::string), 32);
HAPTICD_ABI_LAYOUT(servo::kMaxAxes, 3);

HAPTICD_ABI_LAYOUT(sizeof(hapticd_device_plugin), 48);
HAPTICD_ABI_LAYOUT(alignof(hapticd_device_plugin), 8);
HAPTICD_ABI_FIELD(hapticd_device_plugin, abi_version, 0, std::uint32_t);
HAPTICD_ABI_FIELD(hapticd_device_plugin, name, 8, const char*);
HAPTICD_ABI_FIELD(hapticd_device_plugin, description, 16, const char*);
HAPTICD_ABI_FIELD(hapticd_device_plugin, create, 24, Device* (*)());
HAPTICD_ABI_FIELD(hapticd_device_plugin, destroy, 32, void (*)(Device*));
HAPTICD_ABI_FIELD(hapticd_device_plugin, check_config, 40,
                  bool (*)(const DeviceConfig*, char*, std::size_t));

HAPTICD_ABI_LAYOUT(sizeof(Sample), 72);
HAPTICD_ABI_LAYOUT(alignof(Sample), 8);
HAPTICD_ABI_FIELD(Sample, encoder_counts, 0, std::array<std::int64_t, 3>);
HAPTICD_ABI_FIELD(Sample, device_time_s, 24, double);
HAPTICD_ABI_FIELD(Sample, sequence, 32, std::uint64_t);
HAPTICD_ABI_FIELD(Sample, status, 40, std::uint32_t);
HAPTICD_ABI_FIELD(Sample, applied_write, 48, std::uint64_t);
HAPTICD_ABI_FIELD(Sample, applied_time_s, 56, double);
HAPTICD_ABI_FIELD(Sample, applied, 64, servo::AppliedReport);

HAPTICD_ABI_LAYOUT(sizeof(Command), 32);
HAPTICD_ABI_LAYOUT(alignof(Command), 8);
HAPTICD_ABI_FIELD(Command, force_n, 0, std::array<double, 3>);
HAPTICD_ABI_FIELD(Command, enable, 24, bool);

HAPTICD_ABI_LAYOUT(sizeof(DeviceInfo), 96);
HAPTICD_ABI_LAYOUT(alignof(DeviceInfo), 8);
HAPTICD_ABI_FIELD(DeviceInfo, axes, 0, int);
HAPTICD_ABI_FIELD(DeviceInfo, counts_per_meter, 8, double);
HAPTICD_ABI_FIELD(DeviceInfo, force_limit_n, 16, double);
HAPTICD_ABI_FIELD(DeviceInfo, paces_loop, 24, bool);
HAPTICD_ABI_FIELD(DeviceInfo, lockstep, 25, bool);
HAPTICD_ABI_FIELD(DeviceInfo, samples_at_read, 26, bool);
HAPTICD_ABI_FIELD(DeviceInfo, protocol_version, 28, int);
HAPTICD_ABI_FIELD(DeviceInfo, name, 32, std::string);
HAPTICD_ABI_FIELD(DeviceInfo, serial, 64, std::string);

HAPTICD_ABI_LAYOUT(sizeof(DeviceConfig), 120);
HAPTICD_ABI_LAYOUT(alignof(DeviceConfig), 8);
HAPTICD_ABI_FIELD(DeviceConfig, axes, 0, int);
HAPTICD_ABI_FIELD(DeviceConfig, rate_hz, 8, double);
HAPTICD_ABI_FIELD(DeviceConfig, lockstep, 16, bool);
HAPTICD_ABI_FIELD(DeviceConfig, plugin_table_toml, 24, std::string);
HAPTICD_ABI_FIELD(DeviceConfig, plugin_table_path, 56, std::string);
HAPTICD_ABI_FIELD(DeviceConfig, source, 88, std::string);

HAPTICD_ABI_LAYOUT(sizeof(LinkQuality), 120);
HAPTICD_ABI_LAYOUT(alignof(LinkQuality), 8);
HAPTICD_ABI_LAYOUT(std::is_trivially_copyable_v<LinkQuality>, true);
HAPTICD_ABI_FIELD(LinkQuality, counted, 0, bool);
HAPTICD_ABI_FIELD(LinkQuality, frames_sent, 8, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, frames_received, 16, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, bad_frames, 24, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, transfer_errors, 32, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, reply_timeouts, 40, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, missed_samples, 48, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, late, 56, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, duplicate, 64, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, device_errors, 72, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, disconnects, 80, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, reconnects, 88, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, wrong_session, 96, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, unexpected, 104, std::uint64_t);
HAPTICD_ABI_FIELD(LinkQuality, out_of_step, 112, std::uint64_t);

// The enumerations: their size and the values that cross.
HAPTICD_ABI_LAYOUT(sizeof(IoResult), 4);
HAPTICD_ABI_LAYOUT(static_cast<int>(IoResult::ok), 0);
HAPTICD_ABI_LAYOUT(static_cast<int>(IoResult::timeout), 1);
HAPTICD_ABI_LAYOUT(static_cast<int>(IoResult::disconnected), 2);
HAPTICD_ABI_LAYOUT(static_cast<int>(IoResult::error), 3);
HAPTICD_ABI_LAYOUT(sizeof(servo::AppliedReport), 1);
HAPTICD_ABI_LAYOUT(static_cast<int>(servo::AppliedReport::unsupported), 0);
HAPTICD_ABI_LAYOUT(static_cast<int>(servo::AppliedReport::none), 1);
HAPTICD_ABI_LAYOUT(static_cast<int>(servo::AppliedReport::reported), 2);
HAPTICD_ABI_LAYOUT(static_cast<int>(servo::AppliedReport::bad_command), 3);
HAPTICD_ABI_LAYOUT(static_cast<int>(servo::AppliedReport::bad_time), 4);
HAPTICD_ABI_LAYOUT(servo::kStatusDisconnected, 1u << 0);
HAPTICD_ABI_LAYOUT(servo::kStatusStale, 1u << 1);
HAPTICD_ABI_LAYOUT(servo::kStatusJump, 1u << 2);
HAPTICD_ABI_LAYOUT(servo::kStatusLate, 1u << 3);
HAPTICD_ABI_LAYOUT(servo::kStatusDropped, 1u << 4);
HAPTICD_ABI_LAYOUT(servo::kStatusDeviceFault, 1u << 5);

// Device: one vtable pointer and no data; the signatures of its virtual functions.
HAPTICD_ABI_LAYOUT(sizeof(Device), 8);
HAPTICD_ABI_LAYOUT(alignof(Device), 8);
HAPTICD_ABI_LAYOUT(std::has_virtual_destructor_v<Device>, true);
HAPTICD_ABI_VIRTUAL(open, void (Device::*)(const DeviceConfig&));
HAPTICD_ABI_VIRTUAL(info, DeviceInfo (Device::*)() const);
HAPTICD_ABI_VIRTUAL(read, IoResult (Device::*)(Sample&) noexcept);
HAPTICD_ABI_VIRTUAL(write, IoResult (Device::*)(const Command&) noexcept);
HAPTICD_ABI_VIRTUAL(close, void (Device::*)() noexcept);
HAPTICD_ABI_VIRTUAL(link_quality, LinkQuality (Device::*)() const noexcept);

#undef HAPTICD_ABI_VIRTUAL
#undef HAPTICD_ABI_FIELD
#undef HAPTICD_ABI_LAYOUT

#endif  // LP64 with libstdc++

}  // namespace hapticd::device
