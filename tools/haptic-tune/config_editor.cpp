// Value edits in a TOML config that keep the rest of the text (config_editor.hpp).
#include "config_editor.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <toml++/toml.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "hapticd/input/range.hpp"
#include "hapticd/input/text_input.hpp"

namespace hapticd::daemon {
namespace {

/// Byte offsets of toml++'s source positions (1-based lines, 1-based columns counted in
/// code points), and of line ends, in the text the document was parsed from.
class TextPositions {
  public:
    explicit TextPositions(std::string_view text) : text_(text) {
        for (std::size_t i = 0; i < text.size(); ++i) {
            if (text[i] == '\n') line_starts_.push_back(i + 1);
        }
    }
    [[nodiscard]] std::size_t offset(const toml::source_position& position) const {
        std::size_t at = line_starts_.at(position.line - 1);
        for (toml::source_index column = 1; column < position.column && at < text_.size();
             ++column) {
            ++at;  // one code point: a lead byte and its continuation bytes
            while (at < text_.size() && (static_cast<unsigned char>(text_[at]) & 0xC0U) == 0x80U) {
                ++at;
            }
        }
        return at;
    }
    /// Where the line holding `offset` ends: its newline, or the end of the text.
    [[nodiscard]] std::size_t line_end(std::size_t offset) const {
        const std::size_t end = text_.find('\n', offset);
        return end == std::string_view::npos ? text_.size() : end;
    }
    /// The line that begins at line `line` (1-based), without its newline.
    [[nodiscard]] std::string_view line(toml::source_index line) const {
        const std::size_t begin = line_starts_.at(line - 1);
        return text_.substr(begin, line_end(begin) - begin);
    }

  private:
    std::string_view text_;
    std::vector<std::size_t> line_starts_{0};
};

/// One change to the text: `length` bytes at `at` become `text`. `order` keeps the edits'
/// order among insertions at one place.
struct Splice {
    std::size_t at = 0;
    std::size_t length = 0;
    std::string text;
    std::size_t order = 0;
};

/// True when the table's source region begins at its own header, "[TABLE]": a key may be
/// added after its keys. Not for an inline table, a table that dotted keys made, or one made
/// by a header of a sub-table.
bool has_own_header(const toml::table& table, const TextPositions& positions,
                    const std::string& name) {
    if (table.is_inline() || table.source().begin.line == 0) return false;
    std::string header;
    for (const char c : positions.line(table.source().begin.line)) {
        if (c == '#') break;
        if (c != ' ' && c != '\t') header += c;
    }
    return header == "[" + name + "]";
}

std::string value_text(const ConfigValue& value) {
    if (const auto* number = std::get_if<double>(&value)) return format_config_number(*number);
    if (const auto* flag = std::get_if<bool>(&value)) return *flag ? "true" : "false";
    std::string quoted = "\"";
    for (const char c : std::get<std::string>(value)) {
        if (c == '"' || c == '\\') quoted += '\\';
        quoted += c;
    }
    return quoted + "\"";
}

/// Every leaf of a parsed document as "dotted.key" -> its printed value.
void flatten(const toml::table& table, const std::string& prefix,
             std::map<std::string, std::string>& out) {
    for (const auto& [key, node] : table) {
        const std::string name = prefix + std::string(key.str());
        if (const auto* sub = node.as_table()) {
            flatten(*sub, name + ".", out);
        } else {
            std::ostringstream s;
            node.visit([&s](const auto& v) { s << v; });
            out[name] = s.str();
        }
    }
}

toml::table parse(std::string_view text, const std::string& source, const char* which) {
    if (const std::string e = input::toml_shape_error(text, source); !e.empty()) {
        throw ConfigEditError(e);
    }
    try {
        return toml::parse(text, source);
    } catch (const toml::parse_error& e) {
        std::ostringstream m;
        m << source << ": " << which << " is not valid TOML: " << e.description() << " (line "
          << e.source().begin.line << ")";
        throw ConfigEditError(m.str());
    }
}

}  // namespace

std::string format_config_number(double value) {
    std::string text = input::exact_number(value);
    if (std::isfinite(value) && text.find_first_of(".e") == std::string::npos) text += ".0";
    return text;
}

EditedConfig edit_config_text(std::string_view text, const std::vector<ConfigEdit>& edits,
                              const std::string& source) {
    const toml::table before = parse(text, source, "the config");
    const TextPositions positions(text);
    EditedConfig result;
    std::vector<Splice> splices;
    // Keys of tables the file lacks, appended at its end, each table once.
    std::vector<std::pair<std::string, std::string>> appended;  // table, its lines

    for (std::size_t order = 0; order < edits.size(); ++order) {
        const ConfigEdit& edit = edits[order];
        const std::string new_value = value_text(edit.value);
        const toml::table* table = before.at_path(edit.table).as_table();
        const toml::node* node = table != nullptr ? table->get(edit.key) : nullptr;
        if (node != nullptr && !node->is_table() && !node->is_array_of_tables()) {
            // The value's own source region: replaced, whatever the line holds around it.
            const std::size_t begin = positions.offset(node->source().begin);
            const std::size_t end = positions.offset(node->source().end);
            const std::string old_value(text.substr(begin, end - begin));
            // A trailing comment keeps its column when the new value fits before it.
            std::size_t gap = 0;
            while (end + gap < text.size() && (text[end + gap] == ' ' || text[end + gap] == '\t')) {
                ++gap;
            }
            std::string padding(text.substr(end, gap));
            if (end + gap < text.size() && text[end + gap] == '#') {
                const long width = static_cast<long>(gap) - (static_cast<long>(new_value.size()) -
                                                             static_cast<long>(old_value.size()));
                padding = std::string(static_cast<std::size_t>(std::max(1L, width)), ' ');
            }
            splices.push_back({begin, end - begin + gap, new_value + padding, order});
            result.changes.push_back({edit.table, edit.key, old_value, new_value});
            continue;
        }
        const std::string line = edit.key + " = " + new_value + "\n";
        if (table == nullptr) {
            auto found = std::find_if(appended.begin(), appended.end(),
                                      [&](const auto& entry) { return entry.first == edit.table; });
            if (found == appended.end()) {
                appended.emplace_back(edit.table, "\n[" + edit.table + "]\n");
                found = appended.end() - 1;
            }
            found->second += line;
        } else if (node == nullptr && has_own_header(*table, positions, edit.table)) {
            // After the line of the table's last value (a multi-line array's last line), or
            // after its header when it has none.
            std::size_t after = positions.line_end(positions.offset(table->source().begin));
            for (const auto& [key, value] : *table) {
                if (value.is_table() || value.is_array_of_tables()) continue;
                after = std::max(after, positions.line_end(positions.offset(value.source().end)));
            }
            const bool at_end = after == text.size();
            splices.push_back({at_end ? after : after + 1, 0, (at_end ? "\n" : "") + line, order});
        } else {
            throw ConfigEditError(source + ": could not set " + edit.table + "." + edit.key +
                                  " by editing the text: [" + edit.table +
                                  "] is not a table with a header of its own (an inline table, "
                                  "dotted keys, or a sub-table's header?); write it as a [" +
                                  edit.table + "] with one key per line, or set it by hand");
        }
        result.changes.push_back({edit.table, edit.key, "", new_value});
    }
    std::sort(splices.begin(), splices.end(), [](const Splice& a, const Splice& b) {
        return a.at != b.at ? a.at > b.at : a.order > b.order;
    });
    result.text = std::string(text);
    for (const Splice& splice : splices) result.text.replace(splice.at, splice.length, splice.text);
    if (!appended.empty() && !result.text.empty() && result.text.back() != '\n') {
        result.text += '\n';
    }
    for (const auto& [name, lines] : appended) result.text += lines;

    // The check: edited keys read back, nothing else moved.
    std::string edited_keys;
    for (const ConfigEdit& edit : edits) {
        edited_keys += (edited_keys.empty() ? "" : ", ") + edit.table + "." + edit.key;
    }
    toml::table after;
    try {
        after = toml::parse(result.text, source);
    } catch (const toml::parse_error& e) {
        throw ConfigEditError(source + ": could not set " + edited_keys +
                              " by editing the text: the result would not be valid TOML (" +
                              std::string(e.description()) + "); set it by hand");
    }
    std::map<std::string, std::string> old_values;
    std::map<std::string, std::string> new_values;
    flatten(before, "", old_values);
    flatten(after, "", new_values);
    std::map<std::string, std::string> expected = old_values;
    for (const ConfigEdit& edit : edits) {
        toml::table probe;
        const std::string name = edit.table + "." + edit.key;
        std::ostringstream printed;
        std::visit(
            [&](const auto& v) {
                probe.insert("v", v);
                probe["v"].visit([&printed](const auto& x) { printed << x; });
            },
            edit.value);
        expected[name] = printed.str();
    }
    for (const auto& [name, value] : expected) {
        const auto found = new_values.find(name);
        if (found == new_values.end() || found->second != value) {
            throw ConfigEditError(source + ": could not set " + name +
                                  " by editing the text: it does not read back as written; set it "
                                  "by hand");
        }
    }
    if (new_values.size() != expected.size()) {
        throw ConfigEditError(source +
                              ": editing the text would have changed other keys; "
                              "nothing was written");
    }
    return result;
}

namespace {

namespace fs = std::filesystem;

std::string errno_text() { return std::strerror(errno); }

/// Closes the descriptor it holds.
class FileDescriptor {
  public:
    explicit FileDescriptor(int fd) : fd_(fd) {}
    ~FileDescriptor() {
        if (fd_ >= 0) ::close(fd_);
    }
    FileDescriptor(const FileDescriptor&) = delete;
    FileDescriptor& operator=(const FileDescriptor&) = delete;
    int get() const { return fd_; }
    /// close(2), with its error (some filesystems report a failed write-back only here).
    bool close() {
        const int fd = fd_;
        fd_ = -1;
        return ::close(fd) == 0;
    }

  private:
    int fd_;
};

/// Writes all of `data`; false (errno set) on failure.
bool write_all(int fd, std::string_view data) {
    while (!data.empty()) {
        const ssize_t n = ::write(fd, data.data(), data.size());
        if (n < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        data.remove_prefix(static_cast<std::size_t>(n));
    }
    return true;
}

/// Reads to the end; false (errno set) on failure.
bool read_all(int fd, std::string& out) {
    std::array<char, 65536> buffer{};
    for (;;) {
        const ssize_t n = ::read(fd, buffer.data(), buffer.size());
        if (n < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        if (n == 0) return true;
        out.append(buffer.data(), static_cast<std::size_t>(n));
    }
}

/// Writes `data` to a file we created (`fd`), gives it the config's owner (as root; an
/// unprivileged user keeps the config's group when a member of it) and then its mode, and
/// syncs it. Throws ConfigWriteError naming `what`.
void fill_new_file(int fd, std::string_view data, const struct stat& config,
                   const std::string& what) {
    const auto fail = [&](const std::string& step) {
        throw ConfigWriteError("could not " + step + " " + what + ": " + errno_text() +
                               "; the config was not changed");
    };
    if (!write_all(fd, data)) fail("write");
    if (::geteuid() == 0) {
        if (::fchown(fd, config.st_uid, config.st_gid) != 0) fail("give the config's owner to");
    } else if (config.st_gid != ::getegid()) {
        (void)!::fchown(fd, static_cast<uid_t>(-1), config.st_gid);  // best effort
    }
    if (::fchmod(fd, config.st_mode & 07777) != 0) fail("give the config's mode to");
    if (::fsync(fd) != 0) fail("sync");
}

}  // namespace

std::string file_mode_text(unsigned mode) {
    char text[8];
    std::snprintf(text, sizeof text, "%04o", mode & 07777U);
    return text;
}

ConfigTarget check_config_writable(const std::string& path) {
    ConfigTarget out;
    out.path = path;
    std::error_code error;
    const fs::path target = fs::canonical(path, error);
    if (error) {
        throw ConfigWriteError("cannot resolve " + path + ": " + error.message() +
                               "; nothing was written");
    }
    out.target = target.string();
    const std::string named = out.describe();
    struct stat st {};
    if (::stat(out.target.c_str(), &st) != 0) {
        throw ConfigWriteError("cannot stat " + named + ": " + errno_text() +
                               "; nothing was written");
    }
    out.mode = st.st_mode & 07777U;
    if (!S_ISREG(st.st_mode)) {
        throw ConfigWriteError(named + " is not a regular file; nothing was written");
    }
    // The owner's write bit, not access(2): root may write anything, but a config its owner
    // made read-only is a statement, and root honours it too.
    if ((st.st_mode & S_IWUSR) == 0) {
        throw ConfigWriteError(named + " is not writable: its mode " + file_mode_text(out.mode) +
                               " has no owner write bit (honoured as root too); nothing was "
                               "written (chmod u+w " +
                               out.target + " to allow it)");
    }
    // And this user may write it (the group and other bits, ACLs, a read-only mount).
    if (::faccessat(AT_FDCWD, out.target.c_str(), W_OK, AT_EACCESS) != 0) {
        throw ConfigWriteError(named + " is not writable: " + errno_text() + " (mode " +
                               file_mode_text(out.mode) + ", owner uid " +
                               std::to_string(st.st_uid) + "); nothing was written");
    }
    return out;
}

std::string ConfigTarget::describe() const {
    return target.empty() || target == path ? path : path + " (" + target + ")";
}

WrittenConfig write_config_with_backup(const std::string& path, std::string_view original,
                                       std::string_view text) {
    const ConfigTarget config = check_config_writable(path);
    const std::string named = config.describe();
    WrittenConfig written;
    written.target = config.target;

    // What is replaced must be what was read: an edit made in the meantime is not lost.
    struct stat st {};
    {
        FileDescriptor current(::open(config.target.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC));
        std::string now;
        if (current.get() < 0 || ::fstat(current.get(), &st) != 0 ||
            !read_all(current.get(), now)) {
            throw ConfigWriteError("cannot read " + named + ": " + errno_text() +
                                   "; the config was not changed");
        }
        if (now != original) {
            throw ConfigWriteError(named +
                                   " changed since it was read (edited meanwhile?); the config "
                                   "was not changed: run again");
        }
    }

    // The backup, beside the file it copies, created exclusively (O_EXCL: never through a
    // planted symlink, never over an older backup): TARGET.bak, else TARGET.bak.1, .2, ...
    for (int n = 0; n < 1000 && written.backup.empty(); ++n) {
        const std::string name = config.target + ".bak" + (n == 0 ? "" : "." + std::to_string(n));
        FileDescriptor backup(
            ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600));
        if (backup.get() < 0) {
            if (errno == EEXIST) continue;
            throw ConfigWriteError("cannot create the backup " + name + ": " + errno_text() +
                                   "; the config was not changed");
        }
        try {
            fill_new_file(backup.get(), original, st, "the backup " + name);
            if (!backup.close()) {
                throw ConfigWriteError("could not write the backup " + name + ": " + errno_text() +
                                       "; the config was not changed");
            }
        } catch (const ConfigWriteError&) {
            ::unlink(name.c_str());
            throw;
        }
        written.backup = name;
    }
    if (written.backup.empty()) {
        throw ConfigWriteError(config.target + ".bak through " + config.target +
                               ".bak.999 all exist; remove old backups; the config was not "
                               "changed");
    }

    // The new text: a temporary created exclusively beside the target (mkstemp: a fresh name,
    // O_CREAT | O_EXCL, never a predictable one), with the config's owner and mode, synced,
    // then renamed over the target. A symlink to the config stays a symlink.
    const std::string directory = fs::path(config.target).parent_path().string();
    std::string temporary = directory + "/.haptic-tune-autotune-XXXXXX";
    FileDescriptor out(::mkostemp(temporary.data(), O_CLOEXEC));
    try {
        if (out.get() < 0) {
            throw ConfigWriteError("cannot create a temporary file in " + directory +
                                   " for the new config: " + errno_text() +
                                   "; the config was not changed");
        }
        try {
            fill_new_file(out.get(), text, st,
                          "the new config " + named + " (to " + temporary + ")");
            if (!out.close()) {
                throw ConfigWriteError("could not write the new config " + named + " (to " +
                                       temporary + "): " + errno_text() +
                                       "; the config was not changed");
            }
            if (::rename(temporary.c_str(), config.target.c_str()) != 0) {
                throw ConfigWriteError("could not replace " + named + ": " + errno_text() +
                                       "; the config was not changed");
            }
        } catch (const ConfigWriteError&) {
            ::unlink(temporary.c_str());
            throw;
        }
    } catch (const ConfigWriteError&) {
        ::unlink(written.backup.c_str());  // the config is the original: the backup is redundant
        throw;
    }
    // The rename, to disk.
    FileDescriptor folder(::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
    if (folder.get() >= 0) (void)::fsync(folder.get());
    return written;
}

}  // namespace hapticd::daemon
