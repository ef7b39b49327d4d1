// socket_hammer: every kind of client the control socket must survive, as fast as they go,
// for bench/socket_abuse.sh (docs/benchmarks.md, "The servo under socket abuse"). Not a test:
// it reports what it did, and the daemon's summary says whether the servo noticed.
//
//   socket_hammer SOCKET SECONDS [STORM]
//
// STORM (default all) picks the clients; the disarm probe runs with every storm:
//   all      every one below at once (busy in place of streams: sixteen places in all)
//   flood    connects, sends status requests without reading a reply until the daemon
//            hangs up on it, then connects again
//   garbage  lines that are not JSON, unknown requests, other versions, and lines past the
//            4096-byte limit (each of those ends in a disconnect), again and again
//   connect  churn: connect and close, connect and half-close after one request, connect
//            and never send (held open until the next round); and a thread that connects
//            and closes without pause
//   poll     the well-behaved client: status, read the reply, at once again
//   busy     sixteen clients that hold a place each and keep a request going (status after
//            status): every place the daemon serves is taken
//   streams  sixteen subscribers at 100 Hz that read every event (sixteen `hapticctl stream`)
//   slow     eight subscribers at 100 Hz that never read, and eight slow readers (200 status
//            requests at once, then one reply read every 50 ms)
// and always:
//   disarm   the operator: every 50 ms a new connection, one disarm, its reply; the time from
//            the connect to the reply is the disarm's latency (issue 28: the stop always
//            gets through), printed as percentiles with the number that failed
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "hapticd/servo/nearest_rank.hpp"

namespace {

std::atomic<bool> done{false};

int connect_to(const std::string& path) {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::strncpy(address.sun_path, path.c_str(), sizeof(address.sun_path) - 1);
    if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
        ::close(fd);
        return -1;
    }
    return fd;
}

bool send_all(int fd, const std::string& bytes) {
    for (std::size_t sent = 0; sent < bytes.size();) {
        const ssize_t n =
            ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n < 0 && errno == EAGAIN) {
            pollfd p{.fd = fd, .events = POLLOUT, .revents = 0};
            if (::poll(&p, 1, 100) < 0 || done) return false;
            continue;
        }
        if (n <= 0) return false;
        sent += static_cast<std::size_t>(n);
    }
    return true;
}

// Reads whatever is there within `ms`; false when the peer closed.
bool drain(int fd, int ms) {
    char buffer[65536];
    pollfd p{.fd = fd, .events = POLLIN, .revents = 0};
    if (::poll(&p, 1, ms) <= 0) return true;
    return ::recv(fd, buffer, sizeof(buffer), MSG_DONTWAIT) > 0;
}

const std::string kStatus = "{\"v\":1,\"request\":\"status\"}\n";
/// 200 status requests at once: a flooder's and a slow reader's.
const std::string kStatusBurst = [] {
    std::string burst;
    for (int i = 0; i < 200; ++i) burst += kStatus;
    return burst;
}();

void flood(const std::string& path, std::atomic<long>& disconnects) {
    while (!done) {
        const int fd = connect_to(path);
        if (fd < 0) continue;
        while (!done && send_all(fd, kStatusBurst)) {
        }
        ::close(fd);
        ++disconnects;
    }
}

void garbage(const std::string& path, std::atomic<long>& disconnects) {
    const std::string bad =
        "{]\n{\"v\":1,\"request\":\"self-destruct\"}\n"
        "{\"v\":9,\"request\":\"status\"}\n[1,2,3]\n";
    const std::string oversized = std::string(10000, 'x') + "\n";
    while (!done) {
        const int fd = connect_to(path);
        if (fd < 0) continue;
        for (int i = 0; i < 20 && !done && send_all(fd, bad); ++i) drain(fd, 0);
        send_all(fd, oversized);
        while (!done && drain(fd, 100)) {
        }
        ::close(fd);
        ++disconnects;
    }
}

void churn(const std::string& path, std::atomic<long>& rounds) {
    int held = -1;
    while (!done) {
        if (const int fd = connect_to(path); fd >= 0) ::close(fd);
        if (const int fd = connect_to(path); fd >= 0) {
            send_all(fd, kStatus);
            ::shutdown(fd, SHUT_WR);
            while (!done && drain(fd, 100)) {
            }
            ::close(fd);
        }
        if (held >= 0) ::close(held);
        held = connect_to(path);  // silent until the next round
        ++rounds;
    }
    if (held >= 0) ::close(held);
}

// Reads into `pending` until it holds a whole line; false when none came within `ms` of a
// read, or the peer closed.
bool read_line(int fd, std::string& pending, int ms) {
    char buffer[65536];
    while (pending.find('\n') == std::string::npos) {
        pollfd p{.fd = fd, .events = POLLIN, .revents = 0};
        if (::poll(&p, 1, ms) <= 0) return false;
        const ssize_t got = ::recv(fd, buffer, sizeof(buffer), 0);
        if (got <= 0) return false;
        pending.append(buffer, static_cast<std::size_t>(got));
    }
    return true;
}

void poll_status(const std::string& path, std::atomic<long>& replies) {
    while (!done) {
        const int fd = connect_to(path);
        if (fd < 0) continue;
        std::string pending;
        while (!done && send_all(fd, kStatus)) {
            if (!read_line(fd, pending, 1000)) break;
            const std::size_t end = pending.find('\n');
            pending.erase(0, end + 1);
            ++replies;
        }
        ::close(fd);
    }
}

const std::string kSubscribe = "{\"v\":1,\"request\":\"subscribe\",\"rate_hz\":100}\n";

// Sends `request` on a new connection, then reads its lines one by one, `pause` after each,
// counting them; again when the daemon closes it. Pause 0 and a subscribe is `hapticctl
// stream`; a burst of requests and 50 ms is a slow reader.
void reader(const std::string& path, const std::string& request, std::chrono::milliseconds pause,
            std::atomic<long>& lines) {
    while (!done) {
        const int fd = connect_to(path);
        if (fd < 0) continue;
        std::string pending;
        if (send_all(fd, request)) {
            while (!done && read_line(fd, pending, 1000)) {
                pending.erase(0, pending.find('\n') + 1);
                ++lines;
                if (pause.count() > 0) std::this_thread::sleep_for(pause);
            }
        }
        ::close(fd);
    }
}

// A subscriber that never reads: the daemon must close it when its replies pile up.
void unread_stream(const std::string& path, std::atomic<long>& disconnects) {
    while (!done) {
        const int fd = connect_to(path);
        if (fd < 0) continue;
        if (send_all(fd, kSubscribe)) {
            pollfd p{.fd = fd, .events = POLLRDHUP, .revents = 0};
            while (!done && ::poll(&p, 1, 50) == 0) {
            }
        }
        ::close(fd);
        ++disconnects;
    }
}

// Connects and closes without pause, saying nothing.
void connect_storm(const std::string& path, std::atomic<long>& connects) {
    while (!done) {
        if (const int fd = connect_to(path); fd >= 0) ::close(fd);
        ++connects;
    }
}

// One disarm every 50 ms, each on a connection of its own, timed from the connect to the
// reply. A disarm that got no reply within 2 s, or whose reply was a refusal, failed.
void disarm_probe(const std::string& path, std::vector<double>& latencies_ms, long& failed) {
    const std::string disarm = "{\"v\":1,\"request\":\"disarm\"}\n";
    while (!done) {
        const auto start = std::chrono::steady_clock::now();
        const int fd = connect_to(path);
        std::string reply;
        if (fd >= 0 && send_all(fd, disarm)) (void)read_line(fd, reply, 2000);
        if (fd >= 0) ::close(fd);
        if (reply.find("\"ok\":true") != std::string::npos) {
            latencies_ms.push_back(
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                    .count());
        } else {
            ++failed;
        }
        std::this_thread::sleep_until(start + std::chrono::milliseconds(50));
    }
}

struct Counts {
    std::atomic<long> flood_disconnects{0}, garbage_disconnects{0}, churn_rounds{0}, connects{0};
    std::atomic<long> replies{0}, busy_replies{0}, events{0}, unread_disconnects{0},
        slow_replies{0};
};

const char* const kStorms[] = {"all",  "flood", "garbage", "connect",
                               "poll", "busy",  "streams", "slow"};

bool is_storm(const std::string& name) {
    return std::any_of(std::begin(kStorms), std::end(kStorms),
                       [&](const char* storm) { return name == storm; });
}

void start_storm(const std::string& storm, const std::string& path, Counts& counts,
                 std::vector<std::thread>& threads) {
    const bool all = storm == "all";
    if (all || storm == "flood")
        threads.emplace_back(flood, path, std::ref(counts.flood_disconnects));
    if (all || storm == "garbage") {
        threads.emplace_back(garbage, path, std::ref(counts.garbage_disconnects));
    }
    if (all || storm == "connect") {
        threads.emplace_back(churn, path, std::ref(counts.churn_rounds));
        threads.emplace_back(connect_storm, path, std::ref(counts.connects));
    }
    if (all || storm == "poll") threads.emplace_back(poll_status, path, std::ref(counts.replies));
    if (all || storm == "busy") {
        for (int i = 0; i < 16; ++i) {
            threads.emplace_back(poll_status, path, std::ref(counts.busy_replies));
        }
    }
    if (storm == "streams") {
        for (int i = 0; i < 16; ++i) {
            threads.emplace_back(reader, path, kSubscribe, std::chrono::milliseconds(0),
                                 std::ref(counts.events));
        }
    }
    if (all || storm == "slow") {
        for (int i = 0; i < 8; ++i) {
            threads.emplace_back(unread_stream, path, std::ref(counts.unread_disconnects));
            threads.emplace_back(reader, path, kStatusBurst, std::chrono::milliseconds(50),
                                 std::ref(counts.slow_replies));
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3 && argc != 4) {
        std::fprintf(stderr, "usage: socket_hammer SOCKET SECONDS [STORM]\n");
        return 2;
    }
    const std::string path = argv[1];
    char* end = nullptr;
    const double seconds = std::strtod(argv[2], &end);
    if (end == argv[2] || *end != '\0' || !(seconds > 0.0) || seconds > 3600.0) {
        std::fprintf(stderr, "socket_hammer: SECONDS \"%s\": must be > 0 and <= 3600\n", argv[2]);
        return 2;
    }
    const std::string storm = argc == 4 ? argv[3] : "all";
    if (!is_storm(storm)) {
        std::fprintf(stderr,
                     "socket_hammer: STORM \"%s\": must be all, flood, garbage, connect, poll, "
                     "busy, streams or slow\n",
                     storm.c_str());
        return 2;
    }
    Counts counts;
    std::vector<std::thread> threads;
    start_storm(storm, path, counts, threads);
    std::vector<double> disarm_ms;
    long disarm_failed = 0;
    threads.emplace_back(disarm_probe, path, std::ref(disarm_ms), std::ref(disarm_failed));
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    done = true;
    for (std::thread& t : threads) t.join();
    std::printf(
        "socket_hammer: %s: disarm: %zu carried out, %ld failed; latency p50 %.2f ms, p99 %.2f "
        "ms, max %.2f ms\n",
        storm.c_str(), disarm_ms.size(), disarm_failed, hapticd::servo::quantile(disarm_ms, 0.5),
        hapticd::servo::quantile(disarm_ms, 0.99), hapticd::servo::quantile(disarm_ms, 1.0));
    std::printf(
        "socket_hammer: %s: %.1f s: %ld status replies to the polite client, %ld to the busy "
        "clients, %ld to slow readers; %ld stream events; disconnected %ld flooders, %ld garbage "
        "senders, %ld unread streams; %ld churn rounds, %ld bare connects\n",
        storm.c_str(), seconds, counts.replies.load(), counts.busy_replies.load(),
        counts.slow_replies.load(), counts.events.load(), counts.flood_disconnects.load(),
        counts.garbage_disconnects.load(), counts.unread_disconnects.load(),
        counts.churn_rounds.load(), counts.connects.load());
    return 0;
}
