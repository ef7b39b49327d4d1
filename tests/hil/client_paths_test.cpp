// What a client may have a running hapticd read and write (docs/control.md, "Paths and strings"),
// tried as a careless or hostile client would (issue 28, items 7, 8, 11, 14): a recording or a log
// only as a new file in the daemon's outputs directory, whatever '..' the path holds; a scene
// only from a regular file, read without blocking, and one the client could read itself, so
// that a refusal never quotes a file the client may not read.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "control_daemon.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd::testing {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// hapticctl as user nobody (uid 65534, no groups), as a non-root operator; empty when the
// tests do not run as root.
std::string as_nobody() {
    if (::geteuid() != 0 || !fs::exists("/usr/bin/setpriv")) return {};
    return "/usr/bin/setpriv --reuid=65534 --regid=65534 --clear-groups ";
}

// A daemon whose socket and directory an unprivileged client reaches (the group hapticd's
// part, which the tests' machine may not have).
struct OpenDaemon {
    explicit OpenDaemon(const ScratchDir& dir) : daemon(dir, "lab") {
        fs::permissions(dir.path(),
                        fs::perms::owner_all | fs::perms::group_exec | fs::perms::others_exec);
        EXPECT_TRUE(daemon.process.wait_for_socket(daemon.socket)) << daemon.process.messages();
        ::chmod(daemon.socket.c_str(), 0666);
    }
    CommandResult ctl(const std::string& arguments, const std::string& prefix = "") const {
        return run_command(prefix + shell_quote(HAPTICCTL_BIN) + " --socket " +
                           shell_quote(daemon.socket) + " " + arguments);
    }
    Daemon daemon;
};

TEST(HilClientPaths, ARecordingGoesOnlyInTheOutputsDirectoryWhateverThePathHolds) {
    const ScratchDir dir;
    OpenDaemon d(dir);
    fs::create_directory(dir.file("private"));
    fs::permissions(dir.file("private"), fs::perms::owner_all);
    // Through '..' into a 0700 directory, and onto another instance's socket path: refused,
    // and nothing is made (the second made that instance refuse to start, and the unit did
    // not restart it).
    const std::string other_socket = dir.file("private/lab1.sock");
    for (const std::string& path :
         {dir.file("lab-summary.json/../private/x.csv"), dir.file("private/x.csv"), other_socket}) {
        SCOPED_TRACE(path);
        const CommandResult r = d.ctl("record start " + shell_quote(path));
        EXPECT_EQ(r.exit_code, 1);
        EXPECT_NE(r.err.find("allowed a file name alone (take1.csv), or an absolute path to a "
                             "file directly in " +
                             dir.path().string()),
                  std::string::npos)
            << r.err;
    }
    EXPECT_TRUE(fs::is_empty(dir.file("private")));

    // A name alone goes to the outputs directory, from any working directory, and hapticctl
    // says where.
    const CommandResult named =
        run_command("cd / && " + shell_quote(HAPTICCTL_BIN) + " --socket " +
                    shell_quote(d.daemon.socket) + " record start take1.csv");
    ASSERT_EQ(named.exit_code, 0) << named.err;
    EXPECT_NE(named.out.find("recording to " + dir.file("take1.csv") + " from tick "),
              std::string::npos)
        << named.out;
    EXPECT_EQ(d.ctl("record stop").exit_code, 0);
    // link/../x is x beside link, as the shell means it (not beside the link's target).
    fs::create_directory_symlink(dir.file("private"), dir.file("link"));
    const CommandResult shell = run_command(
        "cd " + shell_quote(dir.path().string()) + " && " + shell_quote(HAPTICCTL_BIN) +
        " --socket " + shell_quote(d.daemon.socket) + " record start link/../take2.csv");
    ASSERT_EQ(shell.exit_code, 0) << shell.err;
    EXPECT_NE(shell.out.find("recording to " + dir.file("take2.csv")), std::string::npos)
        << shell.out;
    EXPECT_EQ(d.ctl("record stop").exit_code, 0);
    EXPECT_TRUE(fs::is_empty(dir.file("private")));
    EXPECT_EQ(d.daemon.process.stop(), 0) << d.daemon.process.messages();
}

TEST(HilClientPaths, AFifoIsRefusedAtOnceAndTheDaemonStaysServedAndStoppable) {
    const ScratchDir dir;
    OpenDaemon d(dir);
    const std::string fifo = dir.file("scene.fifo");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    const auto asked = std::chrono::steady_clock::now();
    const CommandResult r = d.ctl("scene " + shell_quote(fifo));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find(fifo + ": cannot read the scene file: it is a FIFO: allowed a regular "
                                "file"),
              std::string::npos)
        << r.err;
    EXPECT_LT(std::chrono::steady_clock::now() - asked, 30s);  // not the socket's timeout
    EXPECT_EQ(status_of(d.daemon.socket)["scene"]["name"], "demo-wall");
    EXPECT_EQ(d.daemon.process.stop(), 0) << d.daemon.process.messages();  // SIGTERM ends it
}

TEST(HilClientPaths, AClientLoadsOnlyASceneItCouldReadAndNoRefusalQuotesAnother) {
    const std::string nobody = as_nobody();
    if (nobody.empty()) GTEST_SKIP() << "needs root and setpriv, to be a client of another uid";
    const ScratchDir dir;
    OpenDaemon d(dir);
    // Root's alone: a TOML file with a secret, not a scene.
    const std::string secret = dir.write("secret.toml", "api_token = \"s3cret-7f2a\"\n");
    ::chmod(secret.c_str(), 0600);
    const CommandResult refused = d.ctl("scene " + shell_quote(secret), nobody);
    EXPECT_EQ(refused.exit_code, 1);
    EXPECT_NE(refused.err.find("the client (uid 65534) may not read it itself (mode 0600, owner "
                               "uid 0, group gid 0): a client loads only a scene it could read"),
              std::string::npos)
        << refused.err;
    EXPECT_EQ(refused.err.find("s3cret"), std::string::npos) << refused.err;
    EXPECT_EQ(d.daemon.process.messages().find("s3cret"), std::string::npos);
    // Root may read it, and is told what is wrong with it.
    const CommandResult as_root = d.ctl("scene " + shell_quote(secret));
    EXPECT_EQ(as_root.exit_code, 1);
    EXPECT_NE(as_root.err.find("api_token"), std::string::npos) << as_root.err;
    // A scene anyone may read loads for nobody too.
    const std::string open_scene =
        dir.write("open.toml",
                  "[scene]\nname = \"open\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\n"
                  "offset = -0.02\nstiffness = 1000.0\n");
    ::chmod(open_scene.c_str(), 0644);
    const CommandResult loaded = d.ctl("scene " + shell_quote(open_scene), nobody);
    EXPECT_EQ(loaded.exit_code, 0) << loaded.err;
    EXPECT_EQ(d.daemon.process.stop(), 0) << d.daemon.process.messages();
}

}  // namespace
}  // namespace hapticd::testing
