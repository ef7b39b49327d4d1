// Bounds on every text file hapticd and haptic-tune read before a parser sees it
// (docs/architecture.md §7.10): a config or scene must not exhaust memory (`--config /dev/zero`
// read until it ran out) or the stack (toml++ 3.3 recurses once per part of a dotted key: one key
// of 35,000 parts overflowed it). The checks are lexical and cheap; parse_document
// (table_reader.hpp) runs them before every parse.
#pragma once

#include <sys/stat.h>

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

#include "hapticd/input/config_error.hpp"

namespace hapticd::input {

/// The largest config, scene, operator class or plugin table accepted: far above any real
/// one (the largest example is a few kB), far below what would strain a lab PC.
inline constexpr std::size_t kMaxTomlBytes = std::size_t{4} << 20;  // 4 MiB
/// The most parts of one key (`a.b.c = 1`, `[a.b.c]`) and the deepest nesting of arrays and
/// inline tables: real files use 3 and 2.
inline constexpr int kMaxTomlNesting = 32;

/// Checks an opened file's status before it is read: why it is refused, or "" when it is not.
using FileCheck = std::function<std::string(const struct stat&)>;

/// The whole of a file, read in chunks and refused past `max_bytes` (a device such as
/// /dev/zero, or a huge file, is never read further). The open does not wait (O_NONBLOCK: a
/// FIFO nobody writes to does not hang the reader at the open); `check`, given the opened
/// file's status, may refuse it before a byte is read (a client's file: regular_file_only).
/// `what` names it in messages, e.g. "the config file". Throws ConfigError naming the path
/// (and the limit).
std::string read_text_file(const std::string& path, std::string_view what,
                           std::size_t max_bytes = kMaxTomlBytes, const FileCheck& check = {});

/// A FileCheck that refuses anything but a regular file (a FIFO, a device, a socket), which
/// may block the reader or never end: for what a client names.
std::string regular_file_only(const struct stat& status);

/// "" when `text` is within the bounds above; otherwise "SOURCE:LINE: ..." naming what is too
/// large or too deep and the limit. Strings and comments are skipped as TOML defines them.
std::string toml_shape_error(std::string_view text, std::string_view source,
                             std::size_t max_bytes = kMaxTomlBytes);

}  // namespace hapticd::input
