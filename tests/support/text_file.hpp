// Reading a file a test wrote or a program under test wrote: all of it, or line by line.
#pragma once

#include <algorithm>
#include <cstddef>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace hapticd::testing {

/// The whole file, byte for byte; empty when it cannot be read. Read through the stream
/// buffer in blocks, not a character at a time: a daemon's log can grow by tens of MB/s
/// while a test reads it, and under ASan the per-character iterator reads about 40 MB/s.
inline std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return {};
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

/// Whether the file holds at least `count` newlines, reading only as far as it must (the
/// start of a log that may be growing faster than the whole of it could be read).
inline bool has_lines(const std::string& path, std::size_t count) {
    std::ifstream in(path, std::ios::binary);
    char block[65536];
    std::size_t seen = 0;
    while (seen < count && in.read(block, sizeof block).gcount() > 0) {
        const auto end = block + in.gcount();
        seen += static_cast<std::size_t>(std::count(block, end, '\n'));
    }
    return seen >= count;
}

/// The lines of `text`, without their newlines.
inline std::vector<std::string> lines_of_text(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

/// The lines of the file at `path`.
inline std::vector<std::string> lines_of_file(const std::string& path) {
    return lines_of_text(read_file(path));
}

}  // namespace hapticd::testing
