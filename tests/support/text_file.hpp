// Reading a file a test wrote or a program under test wrote: all of it, or line by line.
#pragma once

#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace hapticd::testing {

/// The whole file, byte for byte; empty when it cannot be read.
inline std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
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
