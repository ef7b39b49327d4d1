// What hapticctl prints from a daemon's replies reaches the operator's terminal: a scene's
// name, a path or a refusal is shown with its control characters written out, so that no
// reply can clear the screen, move the cursor or fake a state (issue 28: a scene named with
// escape sequences made other operators' `hapticctl status` show "state disabled" while the
// daemon ran). The daemon here is a SocketServer whose handler replies what a hostile
// scene file or client would have made it say.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "hapticd/daemon/control_protocol.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "socket/requests.hpp"
#include "socket/server.hpp"

namespace hapticd::daemon::control_socket {
namespace {

using hapticd::testing::CommandResult;
using hapticd::testing::run_command;
using hapticd::testing::ScratchDir;
using hapticd::testing::shell_quote;

const std::string kClearAndFake = "\x1b[2J\x1b[Hstate     running";

// The daemon's own status body, with what a hostile scene file and device could put in it.
nlohmann::json hostile_status() {
    RunFacts facts;
    facts.device = "sim device\r\x1b]0;owned\x07";
    facts.config_path = "/etc/hapticd/lab0.toml";
    nlohmann::json status = status_body(servo::StatusSnapshot{}, facts);
    status["scene"] = {{"name", kClearAndFake},
                       {"source",
                        "/tmp/s.toml\xc2\x9b"
                        "2J"}};
    return status;
}

TEST(HapticctlOutput, ADaemonsStringsReachTheTerminalWithTheirControlCharactersWrittenOut) {
    const ScratchDir dir;
    const std::string socket = dir.file("hostile.sock");
    SocketServer server(socket, Limits{}, /*group=*/"");
    server.start([](const Request& request, const Peer&) {
        if (request.kind == RequestKind::status) {
            return Answer{.reply = ok_reply(request.id, {{"status", hostile_status()}})};
        }
        return Answer{.reply = error_reply(request.id, "refused: \x1b[31mFAULT\x1b[0m\nline two")};
    });
    const std::string ctl = shell_quote(HAPTICCTL_BIN) + " --socket " + shell_quote(socket);

    const CommandResult status = run_command(ctl + " status");
    ASSERT_EQ(status.exit_code, 0) << status.err;
    EXPECT_EQ(status.out.find('\x1b'), std::string::npos) << status.out;
    EXPECT_EQ(status.out.find('\r'), std::string::npos) << status.out;
    EXPECT_EQ(status.out.find('\x07'), std::string::npos) << status.out;
    EXPECT_EQ(status.out.find("\xc2\x9b"), std::string::npos) << status.out;
    EXPECT_NE(status.out.find("\\x1b[2J\\x1b[Hstate     running"), std::string::npos) << status.out;
    EXPECT_NE(status.out.find("\\x0d\\x1b]0;owned\\x07"), std::string::npos) << status.out;
    EXPECT_NE(status.out.find("/tmp/s.toml\\u009b2J"), std::string::npos) << status.out;
    EXPECT_NE(status.out.find("state     disabled"), std::string::npos) << status.out;  // its own

    // A refusal goes to stderr the same way; its lines are the daemon's one line.
    const CommandResult refused = run_command(ctl + " arm");
    EXPECT_EQ(refused.exit_code, 1);
    EXPECT_EQ(refused.err, "hapticctl: refused: \\x1b[31mFAULT\\x1b[0m\nline two\n");

    // --json is JSON, whose strings escape control characters already: unchanged.
    const CommandResult json = run_command(ctl + " status --json");
    ASSERT_EQ(json.exit_code, 0) << json.err;
    EXPECT_EQ(nlohmann::json::parse(json.out)["scene"]["name"], kClearAndFake);
}

}  // namespace
}  // namespace hapticd::daemon::control_socket
