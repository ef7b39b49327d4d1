// A fresh temporary directory per test (under $TMPDIR, else /tmp): every file a test writes
// or has a program write, e.g. the config, the scene, the telemetry log and the summary of
// one hapticd run. Removed when the test passes; kept (and its path printed) when it fails,
// so that the files can be looked at, or always with HAPTICD_HIL_KEEP=1. The one place the
// tests make temporary files: a test that needs one takes a ScratchDir and a file() in it.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

namespace hapticd::testing {

class ScratchDir {
  public:
    ScratchDir() {
        const char* tmp = std::getenv("TMPDIR");
        std::string pattern =
            std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/hapticd-test-XXXXXX";
        if (mkdtemp(pattern.data()) == nullptr) {
            throw std::runtime_error("mkdtemp failed for " + pattern);
        }
        path_ = pattern;
    }
    ~ScratchDir() {
        const char* keep = std::getenv("HAPTICD_HIL_KEEP");
        if (::testing::Test::HasFailure() || (keep != nullptr && std::string(keep) == "1")) {
            std::cerr << "kept the test's files in " << path_.string() << "\n";
            return;
        }
        std::error_code ignored;
        std::filesystem::remove_all(path_, ignored);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;

    const std::filesystem::path& path() const { return path_; }
    std::string file(const std::string& name) const { return (path_ / name).string(); }

    /// Writes `text` to the file `name` in this directory; returns its path.
    std::string write(const std::string& name, const std::string& text) const {
        std::string target = file(name);
        std::ofstream out(target);
        out << text;
        out.close();
        if (!out) throw std::runtime_error("cannot write " + target);
        return target;
    }

  private:
    std::filesystem::path path_;
};

}  // namespace hapticd::testing
