// socket_hammer: every kind of client the control socket must survive, at once and as fast
// as they go, for bench/socket_abuse.sh (docs/benchmarks.md, "The servo under socket
// abuse"). Not a test: it reports what it did, and the daemon's summary says whether the
// servo noticed.
//
//   socket_hammer SOCKET SECONDS
//
// One thread each (and `busy` sixteen times):
//   flood    connects, sends status requests without reading a reply until the daemon
//            hangs up on it, then connects again
//   garbage  lines that are not JSON, unknown requests, other versions, and lines past the
//            4096-byte limit (each of those ends in a disconnect), again and again
//   churn    connect and close, connect and half-close after one request, connect and
//            never send (held open until the next round)
//   poll     the well-behaved client: status, read the reply, at once again
//   busy     sixteen clients that hold a place each and keep a request going (status after
//            status): every place the daemon serves is taken
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

void flood(const std::string& path, std::atomic<long>& disconnects) {
    std::string burst;
    for (int i = 0; i < 200; ++i) burst += kStatus;
    while (!done) {
        const int fd = connect_to(path);
        if (fd < 0) continue;
        while (!done && send_all(fd, burst)) {
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

double percentile(std::vector<double> values, double p) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const auto index =
        static_cast<std::size_t>(std::lround(p * static_cast<double>(values.size() - 1)));
    return values[std::min(index, values.size() - 1)];
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: socket_hammer SOCKET SECONDS\n");
        return 2;
    }
    const std::string path = argv[1];
    char* end = nullptr;
    const double seconds = std::strtod(argv[2], &end);
    if (end == argv[2] || *end != '\0' || !(seconds > 0.0) || seconds > 3600.0) {
        std::fprintf(stderr, "socket_hammer: SECONDS \"%s\": must be > 0 and <= 3600\n", argv[2]);
        return 2;
    }
    std::atomic<long> flood_disconnects{0}, garbage_disconnects{0}, churn_rounds{0}, replies{0};
    std::vector<std::thread> threads;
    threads.emplace_back(flood, path, std::ref(flood_disconnects));
    threads.emplace_back(garbage, path, std::ref(garbage_disconnects));
    threads.emplace_back(churn, path, std::ref(churn_rounds));
    threads.emplace_back(poll_status, path, std::ref(replies));
    std::atomic<long> busy_replies{0};
    for (int i = 0; i < 16; ++i) threads.emplace_back(poll_status, path, std::ref(busy_replies));
    std::vector<double> disarm_ms;
    long disarm_failed = 0;
    threads.emplace_back(disarm_probe, path, std::ref(disarm_ms), std::ref(disarm_failed));
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    done = true;
    for (std::thread& t : threads) t.join();
    std::printf(
        "socket_hammer: disarm: %zu carried out, %ld failed; latency p50 %.2f ms, p99 %.2f ms, "
        "max %.2f ms\n",
        disarm_ms.size(), disarm_failed, percentile(disarm_ms, 0.5), percentile(disarm_ms, 0.99),
        percentile(disarm_ms, 1.0));
    std::printf(
        "socket_hammer: %.0f s: %ld status replies to the polite client (%.0f/s), %ld flooders "
        "and %ld garbage senders disconnected, %ld connect/half-close/idle rounds\n",
        seconds, replies.load(), static_cast<double>(replies.load()) / seconds,
        flood_disconnects.load(), garbage_disconnects.load(), churn_rounds.load());
    return 0;
}
