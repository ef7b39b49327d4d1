// Reads the parts of a hapticd TOML config that describe a design: the device model, the
// servo rate and the coupling gains. Values are checked for type and range; an error names
// the file, the key, the value and the allowed range.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

namespace hapticd::tools {

class ConfigError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

struct DeviceFile {
    std::optional<double> mass_kg;                     ///< [device.model] mass
    std::optional<double> damping_n_s_per_m;           ///< [device.model] damping
    std::optional<double> rate_hz;                     ///< [servo] rate_hz
    std::optional<double> coupling_stiffness_n_per_m;  ///< [coupling] stiffness
    std::optional<double> coupling_damping_n_s_per_m;  ///< [coupling] damping
    std::optional<double> velocity_filter_hz;          ///< [coupling] velocity_filter
    std::optional<double> delay_s;                     ///< [device.model] delay
};

/// Throws ConfigError for unreadable TOML, wrong types, out-of-range values and unknown
/// keys in the [device.model] and [coupling] tables.
DeviceFile read_device_file(const std::string& path);

}  // namespace hapticd::tools
