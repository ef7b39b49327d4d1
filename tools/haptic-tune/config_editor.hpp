// Edits values in a hapticd TOML config as text, keeping everything else byte for byte:
// comments, blank lines, key order, the alignment of trailing comments (haptic-tune autotune
// writes [device.model] and [coupling] this way; docs/autotune.md, "What is written").
//
// The editor splices at toml++'s source regions: a key that exists gets its value's own
// region replaced, wherever and however the file sets it ([device.model] mass = ..., a dotted
// key, an inline table); a missing key is added after the last value of its table, which
// must have a [table] header of its own; a missing table is appended. The result is checked
// by parsing both texts: every edited key must read back with its new value and every other
// value must be unchanged, else ConfigEditError says which key and why.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "hapticd/input/input_error.hpp"

namespace hapticd::daemon {

class ConfigEditError : public input::InputError {
  public:
    explicit ConfigEditError(const std::string& message) : InputError(message) {}
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

/// write_config_with_backup failed, or the config may not be replaced; the message names
/// the file and the reason, and says the config was not changed.
class ConfigWriteError : public input::InputError {
  public:
    explicit ConfigWriteError(const std::string& message) : InputError(message) {}
};

/// A config path and the file it names, resolved through symlinks.
struct ConfigTarget {
    std::string path;    ///< as given
    std::string target;  ///< std::filesystem::canonical(path): the file read and replaced
    unsigned mode = 0;   ///< its permission bits (st_mode & 07777)
    /// "PATH", or "PATH (TARGET)" when they differ.
    std::string describe() const;
};

/// Resolves `path` and refuses (ConfigWriteError naming it, with its mode) a config that may
/// not be replaced: not a regular file; a mode without the owner's write bit (0444), also
/// for root: the mode bits, not access(2); or not writable by this user.
ConfigTarget check_config_writable(const std::string& path);

/// "0644".
std::string file_mode_text(unsigned mode);

struct WrittenConfig {
    std::string target;  ///< the file replaced (the config resolved through symlinks)
    std::string backup;  ///< TARGET.bak, or TARGET.bak.N when that exists
};

/// Replaces the file `path` resolves to (a symlink to it stays a symlink) with `text`,
/// after backing up `original`, which must still be its content (else nothing is written:
/// an edit made meanwhile is not lost). check_config_writable() first. The backup is
/// created exclusively (O_CREAT | O_EXCL | O_NOFOLLOW) beside the target as TARGET.bak, or
/// TARGET.bak.1, .2, ... when that exists: never through a planted symlink, never over an
/// older backup. The new text goes to a temporary created exclusively in the target's
/// directory (mkostemp, never a predictable name), given the target's mode (and, as root,
/// its owner), fsynced and renamed over the target. Both copies get the config's mode and
/// owner. On failure the config is unchanged, the temporary and the backup are removed, and
/// ConfigWriteError names the file and the reason.
WrittenConfig write_config_with_backup(const std::string& path, std::string_view original,
                                       std::string_view text);

}  // namespace hapticd::daemon
