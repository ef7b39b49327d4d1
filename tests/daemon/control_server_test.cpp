// The control socket's server against hostile and careless clients (docs/control.md,
// "Limits"): every row of that table, with a handler that counts what reached it.
#include "hapticd/daemon/control_server.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "scratch_dir.hpp"
#include "unix_client.hpp"

namespace hapticd::daemon::control {
namespace {

using hapticd::testing::ScratchDir;
using hapticd::testing::UnixClient;

// A server whose handler answers status with the number of requests it has seen.
struct Served {
    explicit Served(const std::string& path, Limits limits = {})
        : server(std::make_unique<ControlServer>(path, limits, /*group=*/"")) {
        server->start([this](const Request& request, const Peer& peer) {
            const int n = ++requests;
            last_peer_pid = peer.pid;
            return Answer{.reply = ok_reply(request.id, {{"seen", n}}),
                          .journal = request.kind == RequestKind::status
                                         ? std::string()
                                         : "changed by pid " + std::to_string(peer.pid)};
        });
    }
    std::atomic<int> requests{0};
    std::atomic<pid_t> last_peer_pid{0};
    std::unique_ptr<ControlServer> server;
};

nlohmann::json reply_of(UnixClient& client) {
    const auto line = client.line();
    if (!line) return nullptr;
    return nlohmann::json::parse(*line);
}

bool any_message_has(const std::vector<std::string>& messages, const std::string& text) {
    for (const std::string& m : messages) {
        if (m.find(text) != std::string::npos) return true;
    }
    return false;
}

const std::string kStatus = R"({"v":1,"id":1,"request":"status"})"
                            "\n";

TEST(DaemonControlServer, AnswersEachRequestInOrderAndKnowsWhoAsked) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"));
    UnixClient client(dir.file("c.sock"));
    ASSERT_TRUE(client.send(R"({"v":1,"id":1,"request":"status"})"
                            "\n"
                            R"({"v":1,"id":2,"request":"arm"})"
                            "\r\n\n"));
    const nlohmann::json first = reply_of(client);
    const nlohmann::json second = reply_of(client);
    EXPECT_EQ(first["id"], 1);
    EXPECT_EQ(first["seen"], 1);
    EXPECT_EQ(second["id"], 2);
    EXPECT_EQ(second["seen"], 2);
    EXPECT_EQ(served.last_peer_pid.load(), ::getpid());
    const std::vector<std::string> messages = served.server->take_messages();
    EXPECT_TRUE(any_message_has(messages, "client connected: pid " + std::to_string(::getpid()) +
                                              " uid " + std::to_string(::getuid())));
    EXPECT_TRUE(any_message_has(messages, "changed by pid " + std::to_string(::getpid())));
    EXPECT_TRUE(served.server->take_messages().empty());  // taken once
}

TEST(DaemonControlServer, ABadLineGetsAnErrorAndTheConnectionStays) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"));
    UnixClient client(dir.file("c.sock"));
    ASSERT_TRUE(
        client.send("not json\n"
                    R"({"v":1,"id":5,"request":"fly"})"
                    "\n" +
                    kStatus));
    const nlohmann::json garbage = reply_of(client);
    EXPECT_EQ(garbage["ok"], false);
    EXPECT_NE(garbage["error"].get<std::string>().find("is not JSON"), std::string::npos);
    const nlohmann::json unknown = reply_of(client);
    EXPECT_EQ(unknown["ok"], false);
    EXPECT_EQ(unknown["id"], 5);
    EXPECT_NE(unknown["error"].get<std::string>().find("\"fly\""), std::string::npos);
    const nlohmann::json status = reply_of(client);
    EXPECT_EQ(status["ok"], true);
    EXPECT_EQ(served.requests.load(), 1);  // the bad lines never reached the handler
}

TEST(DaemonControlServer, AnOversizedLineIsRefusedThenDisconnected) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"));
    {
        UnixClient client(dir.file("c.sock"));
        const std::string huge =
            R"({"v":1,"request":"status","pad":")" + std::string(kMaxRequestBytes, 'x') + "\"}\n";
        client.send(huge);  // may fail part-way once the server has hung up
        const nlohmann::json reply = reply_of(client);
        ASSERT_FALSE(reply.is_null());
        EXPECT_EQ(reply["ok"], false);
        EXPECT_NE(reply["error"].get<std::string>().find("at most 4096"), std::string::npos)
            << reply.dump();
        EXPECT_TRUE(client.closed_by_peer());
    }
    {  // No newline at all: refused at 4096 bytes, not buffered without end.
        UnixClient client(dir.file("c.sock"));
        client.send(std::string(3 * kMaxRequestBytes, '{'));
        const nlohmann::json reply = reply_of(client);
        ASSERT_FALSE(reply.is_null());
        EXPECT_NE(reply["error"].get<std::string>().find("without its newline"), std::string::npos);
        EXPECT_TRUE(client.closed_by_peer());
    }
    EXPECT_EQ(served.requests.load(), 0);
    UnixClient after(dir.file("c.sock"));  // the server serves on
    after.send(kStatus);
    EXPECT_EQ(reply_of(after)["ok"], true);
}

TEST(DaemonControlServer, AClientThatFloodsAndNeverReadsIsDisconnected) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"), Limits{.max_clients = 16, .max_unread_reply_bytes = 4096});
    UnixClient flooder(dir.file("c.sock"));
    // Requests until the server hangs up: its replies fill the socket's buffer, then its own
    // bounded one.
    std::string burst;
    for (int i = 0; i < 1000; ++i) burst += kStatus;
    bool gone = false;
    for (int round = 0; round < 10000 && !gone; ++round) gone = !flooder.send(burst);
    EXPECT_TRUE(gone) << "the server never disconnected a client that reads nothing";
    EXPECT_TRUE(any_message_has(served.server->take_messages(), "bytes of replies unread"));
    UnixClient polite(dir.file("c.sock"));
    polite.send(kStatus);
    EXPECT_EQ(reply_of(polite)["ok"], true);
}

// A client that reads may send many requests at once: replies the socket has taken are not
// "unread", whatever the burst's total.
TEST(DaemonControlServer, ABurstFromAClientThatReadsIsAnsweredWhole) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"), Limits{.max_clients = 16, .max_unread_reply_bytes = 4096});
    UnixClient client(dir.file("c.sock"));
    std::string burst;
    for (int i = 0; i < 300; ++i) burst += kStatus;  // replies: ~10 kB, past the 4 kB limit
    ASSERT_TRUE(client.send(burst));
    for (int i = 1; i <= 300; ++i) {
        const nlohmann::json reply = reply_of(client);
        ASSERT_FALSE(reply.is_null()) << "reply " << i << " never came";
        EXPECT_EQ(reply["seen"], i);
    }
    EXPECT_FALSE(any_message_has(served.server->take_messages(), "unread"));
}

TEST(DaemonControlServer, OneClientTooManyIsToldSoAndTheOthersStay) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"), Limits{.max_clients = 3});
    std::vector<std::unique_ptr<UnixClient>> clients;
    for (int i = 0; i < 3; ++i) {
        clients.push_back(std::make_unique<UnixClient>(dir.file("c.sock")));
        clients.back()->send(kStatus);
        ASSERT_EQ(reply_of(*clients.back())["ok"], true);  // accepted and served
    }
    UnixClient extra(dir.file("c.sock"));
    const nlohmann::json refusal = reply_of(extra);
    ASSERT_FALSE(refusal.is_null());
    EXPECT_EQ(refusal["ok"], false);
    EXPECT_NE(refusal["error"].get<std::string>().find("too many clients"), std::string::npos);
    EXPECT_TRUE(extra.closed_by_peer());
    for (auto& client : clients) {
        client->send(kStatus);
        EXPECT_EQ(reply_of(*client)["ok"], true);
    }
    clients.pop_back();  // a place comes free
    for (int attempt = 0; attempt < 100; ++attempt) {
        UnixClient again(dir.file("c.sock"));
        again.send(kStatus);
        if (reply_of(again)["ok"] == true) return;
        ::usleep(10'000);  // the server may not have seen the close yet
    }
    ADD_FAILURE() << "no place came free after a client left";
}

TEST(DaemonControlServer, AHalfClosedClientGetsItsRepliesThenTheClose) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"));
    UnixClient client(dir.file("c.sock"));
    client.send(kStatus + kStatus + R"({"v":1,"request":"status"})");  // the last has no newline
    client.shutdown_sending();
    EXPECT_EQ(reply_of(client)["ok"], true);
    EXPECT_EQ(reply_of(client)["ok"], true);
    EXPECT_TRUE(client.closed_by_peer());
    EXPECT_FALSE(client.line().has_value());  // the unfinished line is not answered
    EXPECT_EQ(served.requests.load(), 2);
}

TEST(DaemonControlServer, ASilentClientCostsNothingAndOthersAreServed) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"));
    UnixClient silent(dir.file("c.sock"));
    UnixClient talker(dir.file("c.sock"));
    for (int i = 0; i < 100; ++i) {
        talker.send(kStatus);
        ASSERT_EQ(reply_of(talker)["ok"], true);
    }
    EXPECT_FALSE(silent.line(std::chrono::milliseconds(50)).has_value());
}

TEST(DaemonControlServer, TheSocketIsMode0660AndGoesWithTheServer) {
    const ScratchDir dir;
    const std::string path = dir.file("c.sock");
    {
        Served served(path);
        struct stat st {};
        ASSERT_EQ(::lstat(path.c_str(), &st), 0);
        EXPECT_TRUE(S_ISSOCK(st.st_mode));
        EXPECT_EQ(st.st_mode & 0777, 0660u);
    }
    EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(DaemonControlServer, AStaleSocketIsReplacedALiveOneAndOtherFilesRefused) {
    const ScratchDir dir;
    const std::string path = dir.file("c.sock");
    {  // A socket file whose listener is gone (a daemon that died): bound, never served.
        const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
        sockaddr_un address{};
        address.sun_family = AF_UNIX;
        std::strncpy(address.sun_path, path.c_str(), sizeof(address.sun_path) - 1);
        ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
        ::close(fd);
    }
    Served served(path);
    UnixClient client(path);
    client.send(kStatus);
    EXPECT_EQ(reply_of(client)["ok"], true);
    try {
        ControlServer second(path, {}, "");
        ADD_FAILURE() << "a second server on a live socket was not refused";
    } catch (const ControlSocketError& e) {
        EXPECT_NE(std::string(e.what()).find("is in use: another hapticd answers on it"),
                  std::string::npos)
            << e.what();
    }
    client.send(kStatus);  // the first still serves
    EXPECT_EQ(reply_of(client)["ok"], true);

    const std::string file = dir.file("plain");
    std::ofstream(file) << "not a socket\n";
    try {
        ControlServer on_file(file, {}, "");
        ADD_FAILURE() << "a server on a regular file was not refused";
    } catch (const ControlSocketError& e) {
        EXPECT_NE(std::string(e.what()).find("exists and is not a socket"), std::string::npos);
    }
    EXPECT_TRUE(std::filesystem::exists(file));  // and it is left alone
    const std::string long_path = dir.file(std::string(200, 'p'));
    try {
        ControlServer too_long(long_path, {}, "");
        ADD_FAILURE() << "a path longer than sun_path was not refused";
    } catch (const ControlSocketError& e) {
        EXPECT_NE(std::string(e.what()).find("a path of 1 to 107 bytes"), std::string::npos)
            << e.what();
    }
}

TEST(DaemonControlServer, AMissingGroupIsSaidOnceAndTheSocketStillServes) {
    const ScratchDir dir;
    ControlServer server(dir.file("c.sock"), {}, "no-such-group-hapticd-test");
    server.start([](const Request& r, const Peer&) { return Answer{.reply = ok_reply(r.id)}; });
    const std::vector<std::string> messages = server.take_messages();
    EXPECT_TRUE(any_message_has(messages, "no group \"no-such-group-hapticd-test\""));
    UnixClient client(dir.file("c.sock"));
    client.send(kStatus);
    EXPECT_EQ(reply_of(client)["ok"], true);
}

}  // namespace
}  // namespace hapticd::daemon::control
