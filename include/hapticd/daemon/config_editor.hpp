// Edits values in a hapticd TOML config as text, keeping everything else byte for byte:
// comments, blank lines, key order, the alignment of trailing comments (haptic-tune autotune
// writes [device.model] and [coupling] this way; issue 5).
//
// A key that exists in its table ([device.model] mass = ...) gets its value replaced in
// place; a missing key is added after the table's last key; a missing table is appended.
// The result is checked by parsing both texts: every edited key must read back with its new
// value and every other value must be unchanged, else ConfigEditError says which key and
// why (e.g. the file sets the table with dotted keys or an inline table, which the editor
// does not rewrite).
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace hapticd::daemon {

class ConfigEditError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

using ConfigValue = std::variant<double, std::string, bool>;

struct ConfigEdit {
    std::string table;  ///< "device.model", "coupling"
    std::string key;    ///< "mass"
    ConfigValue value;
};

/// One changed key, for the "what changed" report.
struct ConfigChange {
    std::string table;
    std::string key;
    std::string old_text;  ///< the value as the file had it; empty if the key was added
    std::string new_text;  ///< as written
};

struct EditedConfig {
    std::string text;
    std::vector<ConfigChange> changes;
};

/// Applies `edits` to `text` (`source` names it in errors). Throws ConfigEditError.
EditedConfig edit_config_text(std::string_view text, const std::vector<ConfigEdit>& edits,
                              const std::string& source);

/// A number as the editor writes it: the shortest form that reads back exactly (%.17g
/// trimmed), with a ".0" so that TOML reads a float.
std::string format_config_number(double value);

/// Writes `text` to `path` atomically (a temporary file renamed over it), after copying the
/// current file to `backup_path`. Throws std::runtime_error naming the file on failure.
void write_config_with_backup(const std::string& path, const std::string& text,
                              const std::string& backup_path);

}  // namespace hapticd::daemon
