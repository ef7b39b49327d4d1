// Bounds on the text files every reader parses (docs/architecture.md §2.3: a dotted key of
// 35,000 parts overflowed the stack inside toml++, and --config /dev/zero read until memory ran
// out).
#include "hapticd/input/text_input.hpp"

#include <gtest/gtest.h>

#include <string>

#include "scratch_dir.hpp"

namespace hapticd::input {
namespace {

std::string dotted_key(int parts) {
    std::string key = "a";
    for (int i = 1; i < parts; ++i) key += ".a";
    return key;
}

TEST(TomlShape, RealFilesPass) {
    EXPECT_EQ(toml_shape_error("[servo]\nrate_hz = 1000.0 # Hz\n[device.sim.faults]\n"
                               "stale_at = 0.75\npush = { to = 0.005, start = 1.0 }\n"
                               "normal = [-1.0, 0.5]\n[[wall]]\noffset = 1.5e-3\n",
                               "lab.toml"),
              "");
    // Dots inside strings, comments and values are not key parts.
    EXPECT_EQ(toml_shape_error("name = \"" + dotted_key(100) + "\"\n# " + dotted_key(100) +
                                   "\nx = '" + dotted_key(100) + "'\n",
                               "lab.toml"),
              "");
    EXPECT_EQ(toml_shape_error("\"" + dotted_key(100) + "\" = 1\n", "lab.toml"), "");
    EXPECT_EQ(toml_shape_error("s = \"\"\"\n" + dotted_key(100) + " = 1\n\"\"\"\n", "lab.toml"),
              "");
    EXPECT_EQ(toml_shape_error(dotted_key(32) + " = 1\n[" + dotted_key(32) + "]\n", "lab.toml"),
              "");
}

TEST(TomlShape, ADeepDottedKeyIsRefusedWithTheLineAndTheLimit) {
    EXPECT_EQ(toml_shape_error("[servo]\n" + dotted_key(35000) + " = 1\n", "lab.toml"),
              "lab.toml:2: a key of more than 32 dotted parts (allowed at most 32)");
    EXPECT_EQ(toml_shape_error("\n[" + dotted_key(33) + "]\n", "scene.toml"),
              "scene.toml:2: a key of more than 32 dotted parts (allowed at most 32)");
    EXPECT_EQ(toml_shape_error("x = { " + dotted_key(40) + " = 1 }\n", "lab.toml"),
              "lab.toml:1: a key of more than 32 dotted parts (allowed at most 32)");
}

TEST(TomlShape, DeepNestingIsRefused) {
    EXPECT_EQ(
        toml_shape_error("x = " + std::string(33, '[') + std::string(33, ']') + "\n", "lab.toml"),
        "lab.toml:1: arrays and inline tables nested 33 deep (allowed at most 32)");
    EXPECT_EQ(
        toml_shape_error("x = " + std::string(32, '[') + std::string(32, ']') + "\n", "lab.toml"),
        "");
}

TEST(TomlShape, TooLargeIsRefused) {
    EXPECT_EQ(toml_shape_error(std::string(101, '#'), "big.toml", 100),
              "big.toml: 101 bytes is too large (allowed at most 100 bytes)");
}

TEST(ReadTextFile, ReadsAFileAndRefusesDevicesThatNeverEnd) {
    const hapticd::testing::ScratchDir dir;
    const std::string path = dir.write("lab.toml", "[servo]\nrate_hz = 1000.0\n");
    EXPECT_EQ(read_text_file(path, "the config file"), "[servo]\nrate_hz = 1000.0\n");
    try {
        (void)read_text_file("/dev/zero", "the config file");
        FAIL() << "read /dev/zero to its end";
    } catch (const ConfigError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "/dev/zero: the config file is larger than 4 MiB (allowed at most 4 MiB): "
                  "not a hapticd file");
    }
    EXPECT_THROW((void)read_text_file("/nonexistent/x.toml", "the scene file"), ConfigError);
    EXPECT_THROW((void)read_text_file("/tmp", "the scene file"), ConfigError);
    EXPECT_THROW((void)read_text_file("", "the scene file"), ConfigError);
}

}  // namespace
}  // namespace hapticd::input
