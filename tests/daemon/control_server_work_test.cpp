// The control socket's server (docs/control.md, "Limits"): slow work on the worker, idle
// and stalled clients, descriptors running out, subscribers, and the socket file itself.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstring>
#include <fstream>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "scratch_dir.hpp"
#include "socket_server_fixture.hpp"
#include "unix_client.hpp"

namespace hapticd::daemon::control_socket {
namespace {

using hapticd::testing::ScratchDir;

// A server whose `coupling` requests are slow work (Answer::later) that waits until the test
// lets it go; status answers at once.
struct SlowServed {
    explicit SlowServed(const std::string& path)
        : server(std::make_unique<SocketServer>(path, Limits{}, /*group=*/"")) {
        server->start([this](const Request& request, const Peer&) {
            if (request.kind != RequestKind::coupling) {
                return Answer{.reply = ok_reply(request.id, {{"quick", true}})};
            }
            return Answer{.later = [this, id = request.id] {
                ++started;
                while (!release.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
                return Answer{.reply = ok_reply(id, {{"slow", true}}), .journal = "slow done"};
            }};
        });
    }
    ~SlowServed() {
        release = true;
        server.reset();
    }
    std::atomic<bool> release{false};
    std::atomic<int> started{0};
    std::unique_ptr<SocketServer> server;
};

const std::string kCoupling = R"({"v":1,"id":7,"request":"coupling","stiffness":100})"
                              "\n";

bool wait_for(const std::function<bool()>& done) {
    for (int i = 0; i < 2000 && !done(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return done();
}

// Slow work runs off the server's thread: others are served meanwhile, another client's slow
// request waits its turn, and the slow client's next request is answered after its own.
TEST(DaemonControlServer, SlowWorkKeepsTheOthersServedAndTheRepliesInOrder) {
    const ScratchDir dir;
    SlowServed served(dir.file("c.sock"));
    UnixClient slow(dir.file("c.sock"));
    ASSERT_TRUE(slow.send(kCoupling + kStatus));  // pipelined behind the slow one
    ASSERT_TRUE(wait_for([&] { return served.started.load() == 1; }));
    UnixClient other(dir.file("c.sock"));
    for (int i = 0; i < 20; ++i) {
        other.send(kStatus);
        ASSERT_EQ(reply_of(other)["quick"], true) << "the server waited for the slow work";
    }
    other.send(kCoupling);                                               // queued behind the first
    EXPECT_FALSE(slow.line(std::chrono::milliseconds(50)).has_value());  // nothing yet
    EXPECT_FALSE(other.line(std::chrono::milliseconds(10)).has_value());
    EXPECT_EQ(served.started.load(), 1);
    served.release = true;
    const nlohmann::json first = reply_of(slow);
    const nlohmann::json second = reply_of(slow);
    EXPECT_EQ(first["slow"], true);
    EXPECT_EQ(first["id"], 7);
    EXPECT_EQ(second["quick"], true);
    const nlohmann::json turn = reply_of(other);
    EXPECT_EQ(turn["slow"], true) << turn.dump();
    EXPECT_EQ(served.started.load(), 2);
    EXPECT_TRUE(any_message_has(served.server->take_messages(), "slow done"));
}

// A client that sends its requests and closes at once: they are carried out all the same, a
// slow one included, and the server does not spin on the hung-up socket meanwhile.
TEST(DaemonControlServer, RequestsSentJustBeforeAHangUpAreCarriedOut) {
    const ScratchDir dir;
    SlowServed served(dir.file("c.sock"));
    {
        UnixClient quick(dir.file("c.sock"));
        quick.send(R"({"v":1,"request":"arm"})"
                   "\n");
    }
    {
        UnixClient slow(dir.file("c.sock"));
        slow.send(kCoupling + kCoupling);
    }
    ASSERT_TRUE(wait_for([&] { return served.started.load() == 1; }));
    served.release = true;
    ASSERT_TRUE(wait_for([&] { return served.started.load() == 2; }))
        << "the request after the slow one was dropped with the connection";
    UnixClient after(dir.file("c.sock"));
    after.send(kStatus);
    EXPECT_EQ(reply_of(after)["quick"], true);
}

// A client that leaves while its slow work runs: the work's answer is dropped, nothing breaks,
// and the worker takes the next job.
TEST(DaemonControlServer, AClientThatLeavesDuringSlowWorkFreesTheWorker) {
    const ScratchDir dir;
    SlowServed served(dir.file("c.sock"));
    {
        UnixClient leaver(dir.file("c.sock"));
        leaver.send(kCoupling);
        ASSERT_TRUE(wait_for([&] { return served.started.load() == 1; }));
    }
    served.release = true;
    UnixClient next(dir.file("c.sock"));
    bool answered = false;
    for (int attempt = 0; attempt < 200 && !answered; ++attempt) {
        next.send(kCoupling);
        const nlohmann::json reply = reply_of(next);
        answered = reply["ok"] == true && reply["slow"] == true;
    }
    EXPECT_TRUE(answered);
    EXPECT_EQ(served.started.load(), 2);
}

// A client holds a place among max_clients only while it asks: silence, or a line trickled
// without its end, is closed after Limits::idle with a reply that says so.
TEST(DaemonControlServer, AnIdleClientIsToldAndClosed) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"), Limits{.idle = std::chrono::milliseconds(300)});
    UnixClient silent(dir.file("c.sock"));
    UnixClient trickler(dir.file("c.sock"));
    UnixClient talker(dir.file("c.sock"));
    trickler.send(R"({"v":1,)");
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < 8; ++i) {  // 0.4 s of requests, a request each 50 ms
        talker.send(kStatus);
        ASSERT_EQ(reply_of(talker)["ok"], true);
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    for (UnixClient* client : {&silent, &trickler}) {
        const nlohmann::json told = reply_of(*client);
        ASSERT_FALSE(told.is_null());
        EXPECT_EQ(told["ok"], false);
        EXPECT_NE(told["error"].get<std::string>().find("no request for 300 ms"), std::string::npos)
            << told.dump();
        EXPECT_TRUE(client->closed_by_peer());
    }
    EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(300));
    talker.send(kStatus);  // the one that asks stays
    EXPECT_EQ(reply_of(talker)["ok"], true);
    EXPECT_TRUE(any_message_has(served.server->take_messages(), "idle for 300 ms"));
}

// A client that stops reading is closed once it has taken nothing for Limits::stalled_reader,
// even while its replies are below the byte limit.
TEST(DaemonControlServer, AReaderThatStallsIsClosed) {
    const ScratchDir dir;
    // A byte limit out of reach: only the deadline can close it.
    Served served(dir.file("c.sock"), Limits{.max_clients = 16,
                                             .max_unread_reply_bytes = std::size_t{1} << 30,
                                             .stalled_reader = std::chrono::milliseconds(200)});
    UnixClient stalled(dir.file("c.sock"));
    std::string burst;
    for (int i = 0; i < 20000; ++i) burst += kStatus;  // more replies than the socket holds
    bool gone = false;
    for (int round = 0; round < 200 && !gone; ++round) {
        gone = !stalled.send(burst);
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    EXPECT_TRUE(gone) << "the server never closed a client that took no replies";
    EXPECT_TRUE(any_message_has(served.server->take_messages(), "it took none of its"));
}

// More journal lines than the queue holds: the last line counts the ones dropped.
TEST(DaemonControlServer, DroppedJournalLinesAreCounted) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"));
    for (int i = 0; i < 300; ++i) {
        UnixClient client(dir.file("c.sock"));
        client.send(R"({"v":1,"request":"arm"})"
                    "\n");
        ASSERT_EQ(reply_of(client)["ok"], true);
    }
    const std::vector<std::string> messages = served.server->take_messages();
    ASSERT_EQ(messages.size(), 257u);
    EXPECT_NE(messages.back().find("more messages for the journal dropped"), std::string::npos)
        << messages.back();
    // 300 connects (10 written: the rate limit of their kind) and 300 arms: 310 lines, 256
    // kept.
    EXPECT_EQ(messages.back().rfind("control: 54 more", 0), 0u) << messages.back();
}

// Out of file descriptors, accept() fails with EMFILE while the connection waits: the server
// says so once a second, without spinning, and serves the client once a descriptor is free.
TEST(DaemonControlServer, OutOfDescriptorsPausesAcceptingAndThenServes) {
    const ScratchDir dir;
    Served served(dir.file("c.sock"));
    {
        // Both of the server's threads have run before the table is full: a sanitizer's
        // first check of a thread's start needs descriptors of its own (UBSan's vptr check
        // opens a pipe), and would fail for want of them, not for anything the server did.
        UnixClient warm(dir.file("c.sock"));
        warm.send(kStatus + kCoupling);
        ASSERT_EQ(reply_of(warm)["ok"], true);
        ASSERT_EQ(reply_of(warm)["worked"], true);
    }
    rlimit limit{};
    ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &limit), 0);
    const rlimit low{.rlim_cur = 256, .rlim_max = limit.rlim_max};
    ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &low), 0);
    const int client_fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    ASSERT_GE(client_fd, 0);
    std::vector<int> filler;
    for (int fd; (fd = ::dup(client_fd)) >= 0;) filler.push_back(fd);  // the table is full
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    const std::string path = dir.file("c.sock");
    std::strncpy(address.sun_path, path.c_str(), sizeof(address.sun_path) - 1);
    ASSERT_EQ(::connect(client_fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)),
              0);
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    for (const int fd : filler) ::close(fd);
    ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &limit), 0);
    const std::vector<std::string> paused = served.server->take_messages();
    int said = 0;
    for (const std::string& m : paused)
        said += m.find("accept(): Too many open files") != std::string::npos;
    EXPECT_GE(said, 1);
    EXPECT_LE(said, 3) << "accept() failed in a loop";
    const std::string request = kStatus;
    ASSERT_EQ(::send(client_fd, request.data(), request.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(request.size()));
    pollfd ready{.fd = client_fd, .events = POLLIN, .revents = 0};
    ASSERT_EQ(::poll(&ready, 1, 3000), 1) << "the waiting client was never served";
    char reply[256] = {};
    ASSERT_GT(::recv(client_fd, reply, sizeof(reply) - 1, 0), 0);
    EXPECT_NE(std::string(reply).find("\"ok\":true"), std::string::npos) << reply;
    ::close(client_fd);
}

// A server whose subscribers get a counter as their event; `subscribe` and `unsubscribe` answer
// as the daemon's handler does.
struct Streaming {
    explicit Streaming(const std::string& path, Limits limits = {}, std::size_t padding = 0)
        : server(std::make_unique<SocketServer>(path, limits, /*group=*/"")) {
        server->start(
            [](const Request& request, const Peer&) {
                if (request.kind == RequestKind::subscribe) {
                    return Answer{.reply = ok_reply(request.id), .subscribe_hz = request.rate_hz};
                }
                if (request.kind == RequestKind::unsubscribe) {
                    return Answer{.reply = ok_reply(request.id), .subscribe_hz = 0.0};
                }
                return Answer{.reply = ok_reply(request.id, {{"quick", true}})};
            },
            [this, padding] {
                return event_line("telemetry",
                                  {{"n", ++events}, {"pad", std::string(padding, 'p')}});
            });
    }
    std::atomic<int> events{0};
    std::unique_ptr<SocketServer> server;
};

// Events come at the rate asked, keep coming though the subscriber sends nothing for longer
// than the idle limit, interleave with replies, and stop at unsubscribe.
TEST(DaemonControlServer, ASubscriberGetsEventsAtItsRateUntilItUnsubscribes) {
    const ScratchDir dir;
    Streaming served(dir.file("c.sock"), Limits{.idle = std::chrono::milliseconds(200)});
    UnixClient client(dir.file("c.sock"));
    client.send(R"({"v":1,"id":1,"request":"subscribe","rate_hz":50})"
                "\n");
    EXPECT_EQ(reply_of(client)["id"], 1);
    const auto start = std::chrono::steady_clock::now();
    int events = 0;
    int last = 0;
    while (std::chrono::steady_clock::now() - start < std::chrono::milliseconds(600)) {
        const nlohmann::json event = reply_of(client);
        ASSERT_FALSE(event.is_null()) << "the stream stopped after " << events << " events";
        ASSERT_EQ(event["event"], "telemetry");
        EXPECT_GT(event["n"].get<int>(), last);
        last = event["n"].get<int>();
        ++events;
    }
    // 50 Hz for 0.6 s: 30, give or take a scheduler's wakes on a shared machine.
    EXPECT_GE(events, 20);
    EXPECT_LE(events, 36);
    client.send(R"({"v":1,"id":2,"request":"status"})"
                "\n"
                R"({"v":1,"id":3,"request":"unsubscribe"})"
                "\n");
    bool status_seen = false;
    bool unsubscribed = false;
    while (!unsubscribed) {
        const nlohmann::json line = reply_of(client);
        ASSERT_FALSE(line.is_null());
        if (line.contains("event")) continue;  // on their way before the unsubscribe
        if (line["id"] == 2) status_seen = line["quick"] == true;
        if (line["id"] == 3) unsubscribed = true;
    }
    EXPECT_TRUE(status_seen);
    EXPECT_FALSE(client.line(std::chrono::milliseconds(100)).has_value());  // no more events
}

TEST(DaemonControlServer, ASubscriberThatDoesNotReadIsClosed) {
    const ScratchDir dir;
    // 4 kB events at 100 Hz: the deaf one's socket buffer fills within a second.
    Streaming served(dir.file("c.sock"),
                     Limits{.max_clients = 16,
                            .max_unread_reply_bytes = std::size_t{16} * 1024,
                            .stalled_reader = std::chrono::milliseconds(300)},
                     4000);
    UnixClient reader(dir.file("c.sock"));
    UnixClient deaf(dir.file("c.sock"));
    for (UnixClient* client : {&reader, &deaf}) {
        client->send(R"({"v":1,"request":"subscribe","rate_hz":100})"
                     "\n");
    }
    int read = 0;
    bool deaf_closed = false;
    const auto start = std::chrono::steady_clock::now();
    while (!deaf_closed && std::chrono::steady_clock::now() - start < std::chrono::seconds(10)) {
        ASSERT_TRUE(reader.line().has_value()) << "the reading subscriber lost its stream";
        ++read;
        deaf_closed = any_message_has(served.server->take_messages(), "bytes of events unread");
    }
    EXPECT_TRUE(deaf_closed) << "a subscriber that reads nothing was never closed";
    EXPECT_GT(read, 10);
    EXPECT_TRUE(deaf.closed_by_peer(std::chrono::milliseconds(100)));     // after what it was sent
    for (int i = 0; i < 10; ++i) ASSERT_TRUE(reader.line().has_value());  // the reader goes on
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
        SocketServer second(path, {}, "");
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
        SocketServer on_file(file, {}, "");
        ADD_FAILURE() << "a server on a regular file was not refused";
    } catch (const ControlSocketError& e) {
        EXPECT_NE(std::string(e.what()).find("exists and is not a socket"), std::string::npos);
    }
    EXPECT_TRUE(std::filesystem::exists(file));  // and it is left alone
    const std::string long_path = dir.file(std::string(200, 'p'));
    try {
        SocketServer too_long(long_path, {}, "");
        ADD_FAILURE() << "a path longer than sun_path was not refused";
    } catch (const ControlSocketError& e) {
        EXPECT_NE(std::string(e.what()).find("a path of 1 to 107 bytes"), std::string::npos)
            << e.what();
    }
}

TEST(DaemonControlServer, AMissingGroupIsSaidOnceAndTheSocketStillServes) {
    const ScratchDir dir;
    SocketServer server(dir.file("c.sock"), {}, "no-such-group-hapticd-test");
    server.start([](const Request& r, const Peer&) { return Answer{.reply = ok_reply(r.id)}; });
    const std::vector<std::string> messages = server.take_messages();
    EXPECT_TRUE(any_message_has(messages, "no group \"no-such-group-hapticd-test\""));
    UnixClient client(dir.file("c.sock"));
    client.send(kStatus);
    EXPECT_EQ(reply_of(client)["ok"], true);
}

}  // namespace
}  // namespace hapticd::daemon::control_socket
