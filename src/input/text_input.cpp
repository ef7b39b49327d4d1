#include "hapticd/input/text_input.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <vector>

namespace hapticd::input {
namespace {

std::string mib(std::size_t bytes) {
    if (bytes >= (std::size_t{1} << 20) && bytes % (std::size_t{1} << 20) == 0) {
        return std::to_string(bytes >> 20) + " MiB";
    }
    return std::to_string(bytes) + " bytes";
}

/// A lexical walk of TOML text: strings and comments skipped, key parts and the nesting of
/// arrays and inline tables counted.
class TomlShape {
  public:
    TomlShape(std::string_view text, std::string_view source) : text_(text), source_(source) {}

    std::string error() {
        at_line_start_ = true;
        while (i_ < text_.size()) {
            const char c = text_[i_];
            if (c == '\n') {
                ++line_;
                ++i_;
                if (brackets_.empty()) at_line_start_ = true, in_key_ = false, parts_ = 1;
                continue;
            }
            if (c == ' ' || c == '\t' || c == '\r') {
                ++i_;
                continue;
            }
            if (c == '#') {
                while (i_ < text_.size() && text_[i_] != '\n') ++i_;
                continue;
            }
            if (at_line_start_) {
                at_line_start_ = false;
                if (c == '[') {  // a table header, [a.b] or [[a.b]]
                    in_header_ = true;
                    parts_ = 1;
                    ++i_;
                    if (i_ < text_.size() && text_[i_] == '[') ++i_;
                    continue;
                }
                in_key_ = true;
                parts_ = 1;
            }
            if (c == '"' || c == '\'') {
                if (!skip_string()) return at("a string that never ends");
                continue;
            }
            if (in_header_) {
                if (c == '.' && ++parts_ > kMaxTomlNesting) return too_many_parts();
                if (c == ']') in_header_ = false;
                ++i_;
                continue;
            }
            if (in_key_) {
                if (c == '.' && ++parts_ > kMaxTomlNesting) return too_many_parts();
                if (c == '=') in_key_ = false;
                ++i_;
                continue;
            }
            if (c == '[' || c == '{') {
                brackets_.push_back(c);
                if (static_cast<int>(brackets_.size()) > kMaxTomlNesting) {
                    return at("arrays and inline tables nested " +
                              std::to_string(brackets_.size()) + " deep (allowed at most " +
                              std::to_string(kMaxTomlNesting) + ")");
                }
                if (c == '{') in_key_ = true, parts_ = 1;
            } else if ((c == ']' || c == '}') && !brackets_.empty()) {
                brackets_.pop_back();
            } else if (c == ',' && !brackets_.empty() && brackets_.back() == '{') {
                in_key_ = true, parts_ = 1;
            }
            ++i_;
        }
        return "";
    }

  private:
    std::string at(const std::string& what) const {
        return std::string(source_) + ":" + std::to_string(line_) + ": " + what;
    }
    std::string too_many_parts() const {
        return at("a key of more than " + std::to_string(kMaxTomlNesting) +
                  " dotted parts (allowed at most " + std::to_string(kMaxTomlNesting) + ")");
    }

    /// Skips a basic, literal or multi-line string starting at i_; false if it never ends.
    bool skip_string() {
        const char quote = text_[i_];
        const bool multi = text_.substr(i_, 3) == std::string(3, quote);
        i_ += multi ? 3 : 1;
        while (i_ < text_.size()) {
            const char c = text_[i_];
            if (c == '\\' && quote == '"') {
                if (i_ + 1 < text_.size() && text_[i_ + 1] == '\n') ++line_;
                i_ += 2;
                continue;
            }
            if (c == '\n') {
                if (!multi) return true;  // toml++ reports it; the shape is fine
                ++line_;
            }
            if (c == quote && (!multi || text_.substr(i_, 3) == std::string(3, quote))) {
                i_ += multi ? 3 : 1;
                // A closing run of up to two extra quotes belongs to the string.
                while (multi && i_ < text_.size() && text_[i_] == quote) ++i_;
                return true;
            }
            ++i_;
        }
        return false;
    }

    std::string_view text_;
    std::string_view source_;
    std::size_t i_ = 0;
    int line_ = 1;
    bool at_line_start_ = true;
    bool in_header_ = false;
    bool in_key_ = false;
    int parts_ = 1;
    std::vector<char> brackets_;
};

}  // namespace

std::string read_text_file(const std::string& path, std::string_view what, std::size_t max_bytes,
                           const FileCheck& check) {
    if (path.empty()) throw ConfigError(std::string(what) + ": the path is empty");
    const auto cannot = [&](const std::string& why) {
        return ConfigError(path + ": cannot read " + std::string(what) + ": " + why);
    };
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw cannot(std::strerror(errno));
    const auto close_fd = [fd] { ::close(fd); };
    struct stat st {};
    try {
        if (::fstat(fd, &st) != 0) throw cannot(std::strerror(errno));
        if (S_ISDIR(st.st_mode)) throw cannot("it is a directory");
        if (check) {
            if (const std::string why = check(st); !why.empty()) throw cannot(why);
        }
        // Read as usual from here on: a pipe's writer is given the time it takes.
        const int flags = ::fcntl(fd, F_GETFL);
        if (flags < 0 || ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
            throw cannot(std::strerror(errno));
        }
        std::string text;
        std::array<char, 65536> chunk{};
        for (;;) {
            const ssize_t n = ::read(fd, chunk.data(), chunk.size());
            if (n < 0 && errno == EINTR) continue;
            if (n < 0) throw cannot(std::strerror(errno));
            if (n == 0) break;
            text.append(chunk.data(), static_cast<std::size_t>(n));
            if (text.size() > max_bytes) {
                throw ConfigError(path + ": " + std::string(what) + " is larger than " +
                                  mib(max_bytes) + " (allowed at most " + mib(max_bytes) +
                                  "): not a hapticd file");
            }
        }
        close_fd();
        return text;
    } catch (...) {
        close_fd();
        throw;
    }
}

std::string regular_file_only(const struct stat& status) {
    if (S_ISREG(status.st_mode)) return {};
    const char* kind = S_ISFIFO(status.st_mode)   ? "a FIFO"
                       : S_ISCHR(status.st_mode)  ? "a character device"
                       : S_ISBLK(status.st_mode)  ? "a block device"
                       : S_ISSOCK(status.st_mode) ? "a socket"
                                                  : "not a regular file";
    return std::string("it is ") + kind + ": allowed a regular file";
}

std::string toml_shape_error(std::string_view text, std::string_view source,
                             std::size_t max_bytes) {
    if (text.size() > max_bytes) {
        return std::string(source) + ": " + std::to_string(text.size()) +
               " bytes is too large (allowed at most " + mib(max_bytes) + ")";
    }
    return TomlShape(text, source).error();
}

}  // namespace hapticd::input
