// The one base of bad input: every error that means it is an InputError with its kind, and
// with_context adds where the input was for without changing its kind.
#include "hapticd/input/input_error.hpp"

#include <gtest/gtest.h>

#include <string>

#include "hapticd/input/config_error.hpp"
#include "hapticd/input/text_input.hpp"

namespace hapticd::input {
namespace {

TEST(InputError, ExitsTwoAndNamesItsKind) {
    EXPECT_EQ(InputError::kExitCode, 2);
    const InputError plain("bad --rate");
    EXPECT_EQ(plain.kind(), "error");
    EXPECT_STREQ(plain.what(), "bad --rate");
    const ConfigError config("lab.toml:3: [servo] rate_hz: value 5 is out of range");
    EXPECT_EQ(config.kind(), "config error");
    const InputError& as_base = config;  // caught as the base, it keeps its kind
    EXPECT_EQ(as_base.kind(), "config error");
}

TEST(InputError, WithContextWrapsTheMessageAndKeepsTheKind) {
    const ConfigError config("lab.toml: no such file");
    const InputError wrapped =
        with_context("the config does not load: ", config, "; nothing was written");
    EXPECT_STREQ(wrapped.what(),
                 "the config does not load: lab.toml: no such file; nothing was written");
    EXPECT_EQ(wrapped.kind(), "config error");
    EXPECT_STREQ(with_context("", config).what(), config.what());
}

TEST(InputError, AReaderRefusalIsCaughtAsTheBase) {
    try {
        (void)read_text_file("/nonexistent/hapticd-input-error-test.toml", "the config file");
        FAIL() << "an unreadable file was read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/hapticd-input-error-test.toml"),
                  std::string::npos);
    }
}

}  // namespace
}  // namespace hapticd::input
