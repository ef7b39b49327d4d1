// hapticctl: the operator's command line for a running hapticd (docs/control.md).
//
//   hapticctl [-i NAME | --socket PATH] status [--json] | watch [--count N] | arm | disarm |
//             reset | coupling K [B] | stream [--rate HZ] [--count N] |
//             record start FILE | record stop | scene FILE | identify [FILE] [--no-wait]
//
// Exit status: 0 done; 1 the daemon refused, or could not be reached; 2 bad usage.
#include <sys/stat.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <thread>

#include "control_connection.hpp"
#include "hapticd/daemon/exit_code.hpp"
#include "hapticd/input/printable.hpp"
#include "hapticd/install/version.hpp"
#include "parse_command_line.hpp"
#include "status_text.hpp"

namespace {

/// A gain: a finite number >= 0 (CLI11's NonNegativeNumber lets inf through, and names the
/// range up to DBL_MAX). Refused while the command line is read: exit 2, no daemon asked.
CLI::Validator finite_non_negative() {
    return {
        [](const std::string& text) -> std::string {
            double value = 0.0;
            if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value) || value < 0.0) {
                return "\"" + text + "\" is not a finite number >= 0";
            }
            return {};
        },
        "NUMBER >= 0"};
}

/// A FILE argument: not empty (an empty path is no file, and not "the default"). Refused
/// while the command line is read: exit 2, no daemon asked.
CLI::Validator non_empty_path(const std::string& what) {
    return {[what](const std::string& path) {
                return path.empty() ? "the path is empty: " + what : std::string();
            },
            "FILE"};
}

/// --socket PATH: what a Unix socket address holds, 1 to 107 bytes.
CLI::Validator socket_path_length() {
    return {[](const std::string& path) -> std::string {
                if (!path.empty() &&
                    path.size() <= hapticd::daemon::control_socket::kMaxSocketPathBytes)
                    return {};
                return "\"" + path.substr(0, 40) + (path.size() > 40 ? "...\"" : "\"") + " is " +
                       std::to_string(path.size()) + " bytes: a socket path is 1 to " +
                       std::to_string(hapticd::daemon::control_socket::kMaxSocketPathBytes) +
                       " bytes";
            },
            "PATH"};
}

using hapticd::ctl::ConnectionError;
using hapticd::ctl::ControlConnection;
using hapticd::daemon::control_socket::RequestKind;

volatile std::sig_atomic_t interrupted = 0;

extern "C" void on_interrupt(int /*signal*/) { interrupted = 1; }

// An instance name as systemd's template units take it: no path, no spaces.
std::optional<std::string> bad_instance_name(const std::string& name) {
    if (name.empty() || name.size() > 64) return "must be 1 to 64 characters";
    for (const char c : name) {
        const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                        (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.' || c == '@' ||
                        c == ':';
        if (!ok) return "may hold only letters, digits and - _ . @ :";
    }
    if (name == "." || name == "..") return "is not an instance name";
    return std::nullopt;
}

// The reply's status object; a refusal or a reply without one is an error.
nlohmann::json status_of(ControlConnection& daemon) {
    const nlohmann::json reply = daemon.request(RequestKind::status);
    if (!reply.at("ok").get<bool>()) throw ConnectionError(reply.value("error", "refused"));
    if (!reply.contains("status") || !reply["status"].is_object()) {
        throw ConnectionError("the status reply has no status object");
    }
    return reply["status"];
}

// arm, disarm, reset: the request, then the state it led to (the servo takes a request at
// its next tick: a status shortly after shows it).
int change_state(ControlConnection& daemon, RequestKind kind) {
    const nlohmann::json reply = daemon.request(kind);
    if (!reply.at("ok").get<bool>()) {
        std::cerr << "hapticctl: " << reply.value("error", std::string("refused")) << "\n";
        return hapticd::daemon::kExitFault;
    }
    const std::string before = reply.value("state_before", std::string());
    std::string state = before;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    const auto settled = [&] {
        switch (kind) {
            case RequestKind::arm:
                return state == "arming" || state == "running";
            case RequestKind::disarm:
                return state == "disabled";
            case RequestKind::reset:
                return state != "fault";
            case RequestKind::status:
            case RequestKind::coupling:
            case RequestKind::subscribe:
            case RequestKind::unsubscribe:
            case RequestKind::record_start:
            case RequestKind::record_stop:
            case RequestKind::scene_load:
            case RequestKind::identify:
            case RequestKind::mark:
                break;
        }
        return true;
    };
    do {
        try {
            state = status_of(daemon).at("state").get<std::string>();
        } catch (const ConnectionError& e) {
            // Over the daemon's limit of clients it serves one disarm and closes
            // (docs/control.md, "Limits"): the disarm is taken, at the servo's next tick.
            if (kind != RequestKind::disarm) throw;
            std::cout << "disarm taken (was " << before
                      << "); the daemon, serving as many clients as it may, answered it and "
                         "closed: hapticctl status confirms the state once a place is free\n";
            return hapticd::daemon::kExitOk;
        }
        if (settled()) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    } while (std::chrono::steady_clock::now() < deadline);
    std::cout << "state " << state << " (was " << before << ")\n";
    if (!settled()) {
        std::cerr << "hapticctl: the servo is still " << state << " a second after "
                  << hapticd::daemon::control_socket::request_name(kind)
                  << " (a latched fault that returns at once, or a stalled servo thread)\n";
        return hapticd::daemon::kExitFault;
    }
    return hapticd::daemon::kExitOk;
}

// coupling K [B]: the daemon checks the gains (its range, then its stability check) and
// says why when it refuses them.
int set_coupling(ControlConnection& daemon, double stiffness, std::optional<double> damping) {
    const nlohmann::json reply =
        daemon.request(hapticd::daemon::control_socket::Request{.kind = RequestKind::coupling,
                                                                .id = nullptr,
                                                                .stiffness_n_per_m = stiffness,
                                                                .damping_n_s_per_m = damping});
    if (!reply.at("ok").get<bool>()) {
        std::cerr << "hapticctl: " << reply.value("error", std::string("refused")) << "\n";
        return hapticd::daemon::kExitFault;
    }
    std::cout << "coupling k_c " << reply.at("stiffness").get<double>() << " N/m, b_c "
              << reply.at("damping").get<double>()
              << " N s/m from the next tick, through the soft start\n"
              << reply.at("verdict").get<std::string>() << "\n";
    return hapticd::daemon::kExitOk;
}

int watch(ControlConnection& daemon, int count) {
    std::signal(SIGINT, on_interrupt);
    std::signal(SIGTERM, on_interrupt);
    auto next = std::chrono::steady_clock::now();
    for (int printed = 0; interrupted == 0 && (count == 0 || printed < count); ++printed) {
        std::cout << hapticd::ctl::watch_line(status_of(daemon)) << "\n" << std::flush;
        next += std::chrono::milliseconds(100);
        std::this_thread::sleep_until(next);
    }
    return hapticd::daemon::kExitOk;
}

// FILE as the user means it in their shell: relative to the working directory as the shell
// names it ($PWD, when that is this process's working directory), with '.' and '..' taken
// lexically as `cd` takes them, so that `link/../x` is x beside link, not beside its target.
std::string shell_absolute(const std::string& file) {
    std::filesystem::path base = std::filesystem::current_path();
    if (const char* pwd = std::getenv("PWD"); pwd != nullptr && pwd[0] == '/') {
        struct stat named {};
        struct stat here {};
        if (::stat(pwd, &named) == 0 && ::stat(".", &here) == 0 && named.st_dev == here.st_dev &&
            named.st_ino == here.st_ino) {
            base = pwd;
        }
    }
    return (base / file).lexically_normal().string();
}

// A recording's or a log's FILE: a name alone goes as it is (the daemon makes it in its
// outputs directory, and its reply says where); a path is made absolute as the user means it.
// docs/control.md, "Paths and strings".
std::string client_file(const std::string& file) {
    return file.find('/') == std::string::npos ? file : shell_absolute(file);
}

// record start FILE, record stop: the daemon creates and closes the file; hapticctl says
// where it is and what it holds.
int record(ControlConnection& daemon, const std::optional<std::string>& path) {
    hapticd::daemon::control_socket::Request request{
        .kind = path ? RequestKind::record_start : RequestKind::record_stop, .id = nullptr};
    if (path) request.path = client_file(*path);
    const nlohmann::json reply = daemon.request(request);
    if (!reply.at("ok").get<bool>()) {
        std::cerr << "hapticctl: " << reply.value("error", std::string("refused")) << "\n";
        return hapticd::daemon::kExitFault;
    }
    if (path) {
        std::cout << "recording to " << reply.at("path").get<std::string>() << " from tick "
                  << reply.at("first_tick").get<std::uint64_t>() << "\n";
        return hapticd::daemon::kExitOk;
    }
    // "complete" is new in this release: a daemon of the one before says only "dropped".
    const auto dropped = reply.at("dropped").get<std::uint64_t>();
    const bool complete = reply.value("complete", dropped == 0);
    std::cout << reply.at("path").get<std::string>() << ": "
              << reply.at("records").get<std::uint64_t>() << " records, "
              << (dropped == 0 ? std::string("none lost") : std::to_string(dropped) + " lost")
              << "\n";
    if (!complete) {
        std::cerr << "hapticctl: the recording is INCOMPLETE: "
                  << reply.value("failure", std::to_string(dropped) + " records lost") << "\n";
        return hapticd::daemon::kExitFault;
    }
    return hapticd::daemon::kExitOk;
}

// scene FILE (made absolute here): the daemon reads, builds and checks it, and the servo takes
// it at the start of a tick, through the soft start.
int load_scene(ControlConnection& daemon, const std::string& path) {
    hapticd::daemon::control_socket::Request request{.kind = RequestKind::scene_load,
                                                     .id = nullptr};
    request.path = shell_absolute(path);
    const nlohmann::json reply = daemon.request(request);
    if (!reply.at("ok").get<bool>()) {
        std::cerr << "hapticctl: " << reply.value("error", std::string("refused")) << "\n";
        return hapticd::daemon::kExitFault;
    }
    std::cout << "scene \"" << reply.at("scene").get<std::string>() << "\" from "
              << reply.at("path").get<std::string>()
              << " from the next tick, through the soft start\n"
              << reply.at("verdict").get<std::string>() << "\n";
    return hapticd::daemon::kExitOk;
}

// mark TEXT: the daemon numbers it, and every record from the servo's next tick on carries
// the number in its `mark` column, the text in a "# mark N:" line of the log and recording.
int mark(ControlConnection& daemon, const std::string& text) {
    hapticd::daemon::control_socket::Request request{.kind = RequestKind::mark, .id = nullptr};
    request.text = text;
    const nlohmann::json reply = daemon.request(request);
    if (!reply.at("ok").get<bool>()) {
        std::cerr << "hapticctl: " << reply.value("error", std::string("refused")) << "\n";
        return hapticd::daemon::kExitFault;
    }
    std::cout << "mark " << reply.at("mark").get<std::uint32_t>() << " from the tick after "
              << reply.at("after_tick").get<std::uint64_t>() << "\n";
    return hapticd::daemon::kExitOk;
}

// identify [FILE] (as for record start; without, the daemon names one in its outputs directory):
// the daemon plays the excitation of hapticd --identify open loop and records it. hapticctl waits
// for its end and prints how it ended: exit 0 only when it ran to its end. Interrupting
// hapticctl stops the waiting, not the excitation (hapticctl disarm does that).
int identify(ControlConnection& daemon, const std::optional<std::string>& path, bool wait) {
    hapticd::daemon::control_socket::Request request{.kind = RequestKind::identify, .id = nullptr};
    if (path) request.path = client_file(*path);
    const nlohmann::json reply = daemon.request(request);
    if (!reply.at("ok").get<bool>()) {
        std::cerr << "hapticctl: " << reply.value("error", std::string("refused")) << "\n";
        return hapticd::daemon::kExitFault;
    }
    const auto log = reply.at("path").get<std::string>();
    const auto excitation_s = reply.at("excitation_s").get<double>();
    const auto wait_s = reply.at("wait_s").get<double>();
    std::cout << "identify: the excitation plays for " << excitation_s
              << " s once the handle is still (let go of it); the log is " << log << "\n"
              << std::flush;
    if (!wait) return hapticd::daemon::kExitOk;
    std::signal(SIGINT, on_interrupt);
    std::signal(SIGTERM, on_interrupt);
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(wait_s + excitation_s + 10.0));
    auto next_progress = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (interrupted == 0 && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        const nlohmann::json s = status_of(daemon);
        const nlohmann::json& run = s.at("identify");
        if (!run.is_object() || run.at("path").get<std::string>() != log) continue;
        if (!run.at("active").get<bool>()) {
            const bool complete = run.at("complete").get<bool>();
            (complete ? std::cout : std::cerr)
                << (complete ? "identify: " : "hapticctl: identify: ")
                << run.at("outcome").get<std::string>() << "\n";
            return complete ? hapticd::daemon::kExitOk : hapticd::daemon::kExitFault;
        }
        if (std::chrono::steady_clock::now() >= next_progress) {
            std::cout << "identify: " << run.at("phase").get<std::string>() << ", "
                      << run.at("played_s").get<double>() << " of " << excitation_s << " s\n"
                      << std::flush;
            next_progress += std::chrono::seconds(5);
        }
    }
    std::cerr
        << "hapticctl: identify: stopped waiting "
        << (interrupted != 0
                ? std::string("(interrupted)")
                : "after " + std::to_string(static_cast<int>(wait_s + excitation_s + 10.0)) + " s")
        << "; the excitation plays on: hapticctl status shows it, hapticctl disarm stops it\n";
    return hapticd::daemon::kExitFault;
}

// stream: CSV on stdout from the daemon's telemetry events, for a pipe into a plot. Ends on
// SIGINT or SIGTERM, after --count rows, or quietly when the reader of stdout goes away.
int stream(ControlConnection& daemon, double rate_hz, int count) {
    std::signal(SIGINT, on_interrupt);
    std::signal(SIGTERM, on_interrupt);
    std::signal(SIGPIPE, SIG_IGN);
    const nlohmann::json reply = daemon.request(hapticd::daemon::control_socket::Request{
        .kind = RequestKind::subscribe, .id = nullptr, .rate_hz = rate_hz});
    if (!reply.at("ok").get<bool>()) {
        std::cerr << "hapticctl: " << reply.value("error", std::string("refused")) << "\n";
        return hapticd::daemon::kExitFault;
    }
    const int axes = reply.at("axes").get<int>();
    std::cout << hapticd::ctl::stream_header(axes) << "\n" << std::flush;
    daemon.interrupt_on(&interrupted);  // a slow --rate: SIGINT ends the wait for an event
    for (int printed = 0; interrupted == 0 && (count == 0 || printed < count); ++printed) {
        nlohmann::json event;
        try {
            event = daemon.next_event();
        } catch (const hapticd::ctl::Interrupted&) {
            break;
        }
        if (interrupted != 0) break;
        std::cout << hapticd::ctl::stream_row(event, axes) << "\n" << std::flush;
        if (!std::cout) return hapticd::daemon::kExitOk;  // the pipe's reader is gone
    }
    return hapticd::daemon::kExitOk;
}

int run_main(int argc, char** argv) {
    CLI::App app{
        "hapticctl: the operator's command line for a running hapticd, through its control "
        "socket (docs/control.md; hapticctl(1)).\n\n"
        "Exit status: 0 done; 1 the daemon refused the request, or could not be reached; 2 "
        "bad usage.",
        "hapticctl"};
    app.set_version_flag("--version", std::string("hapticctl ") + hapticd::install::kVersion);
    std::string instance;
    std::string socket_path;
    auto* instance_option = app.add_option("-i,--instance", instance,
                                           "the instance NAME of hapticd@NAME: its socket is "
                                           "/run/hapticd/NAME.sock");
    auto* socket_option =
        app.add_option("--socket", socket_path, "the control socket's PATH (hapticd --socket)")
            ->check(socket_path_length());
    instance_option->excludes(socket_option);
    app.require_subcommand(0, 1);

    bool as_json = false;
    auto* status = app.add_subcommand("status",
                                      "print the servo's state, rate, positions, "
                                      "forces and faults");
    status->add_flag("--json", as_json, "print the daemon's status object as one JSON line");
    int count = 0;
    auto* watch_command =
        app.add_subcommand("watch", "print a status line every 100 ms until interrupted");
    watch_command->add_option("--count", count, "stop after N lines (0: until interrupted)")
        ->check(CLI::Range(0, 100000000));
    auto* arm = app.add_subcommand(
        "arm", "let forces flow: once the handle is still, the soft start ramps them up");
    auto* disarm = app.add_subcommand("disarm", "zero force from the next tick on");
    auto* reset = app.add_subcommand(
        "reset", "clear a latched fault; an armed servo then starts again through the soft start");

    double stiffness = 0.0;
    double damping = 0.0;
    auto* coupling = app.add_subcommand(
        "coupling",
        "set the coupling's k_c [and b_c] (16): checked by the daemon's stability check first, "
        "refused with its verdict when they fail it; forces return through the soft start");
    coupling->add_option("K", stiffness, "k_c, N/m")->required()->check(finite_non_negative());
    auto* damping_option =
        coupling->add_option("B", damping, "b_c, N s/m (default: the damping in force)")
            ->check(finite_non_negative());

    double stream_rate_hz = hapticd::daemon::control_socket::kDefaultSubscribeRateHz;
    int stream_count = 0;
    auto* stream_command = app.add_subcommand(
        "stream",
        "write the servo's telemetry as CSV to stdout (tick, t_s, state, x, xe, f per axis, "
        "faults), decimated to --rate, for a live plot");
    stream_command
        ->add_option("--rate", stream_rate_hz, "rows a second, > 0 and <= 100 (default 10)")
        ->check(CLI::Range(0.001, hapticd::daemon::control_socket::kMaxSubscribeRateHz));
    stream_command->add_option("--count", stream_count, "stop after N rows (0: until interrupted)")
        ->check(CLI::Range(0, 100000000));

    std::string record_path;
    auto* record_command =
        app.add_subcommand("record", "record every tick to a file, in the hapticd --log format");
    auto* record_start = record_command->add_subcommand(
        "start",
        "start recording to FILE, a new file the daemon creates in its directory for a client's "
        "files (LOGS_DIRECTORY as a service; docs/control.md, \"Paths and strings\"), and say "
        "where");
    record_start
        ->add_option("FILE", record_path,
                     "the file to create: a name alone, or a path to that directory")
        ->required()
        ->check(non_empty_path("name the file to create"));
    auto* record_stop =
        record_command->add_subcommand("stop", "stop recording; print how many records it holds");
    record_command->allow_extras();  // a word that is neither start nor stop is named below

    std::string scene_path;
    auto* scene_command = app.add_subcommand(
        "scene",
        "render the scene in FILE from a tick boundary on, through the soft start: the daemon "
        "refuses a scene of the other causality, or one that fails its stability check with "
        "the gains in force, and says why");
    scene_command->add_option("FILE", scene_path, "the scene file (docs/scenes.md)")
        ->required()
        ->check(non_empty_path("name the scene file"));

    std::string mark_text;
    auto* mark_command = app.add_subcommand(
        "mark",
        "put a trial marker in the log and the recording from the next tick on: the `mark` "
        "column counts the marks (and the changes of gains and scene), a \"# mark N: TEXT\" "
        "line names them (docs/daemon.md, \"Telemetry\")");
    mark_command->add_option("TEXT", mark_text, "the marker: 1 to 200 bytes, one line")
        ->required()
        ->check([](const std::string& text) {
            const auto problem = hapticd::daemon::control_socket::mark_text_problem(text);
            return problem ? "TEXT: " + *problem : std::string();
        });

    std::string identify_path;
    bool no_wait = false;
    auto* identify_command = app.add_subcommand(
        "identify",
        "play the excitation of hapticd --identify ([identify] of the daemon's config) open "
        "loop on the disarmed daemon and record it for haptic-tune identify; wait for its end "
        "and say how it ended (hapticctl disarm stops it)");
    auto* identify_file = identify_command
                              ->add_option("FILE", identify_path,
                                           "the log to create, as for record start (default: "
                                           "identify-START-N.csv)")
                              ->check(non_empty_path("name the log to create, or leave FILE out"));
    identify_command->add_flag("--no-wait", no_wait,
                               "return once the excitation is handed to the servo");

    // A word that is not a command is said below, by name; the commands themselves (made
    // above, before this) still refuse what they do not take.
    app.allow_extras();
    if (const std::optional<int> ended = hapticd::tools::parse_command_line(app, argc, argv)) {
        return *ended;
    }
    if (record_command->parsed() && !record_start->parsed() && !record_stop->parsed()) {
        const std::vector<std::string> words = record_command->remaining();
        std::cerr << "hapticctl: record "
                  << (words.empty() ? std::string("needs") : "\"" + words.front() + "\": give")
                  << " start FILE or stop (hapticctl record --help)\n";
        return hapticd::daemon::kExitBadInput;
    }
    if (!app.remaining().empty() || app.get_subcommands().empty()) {
        std::cerr << "hapticctl: "
                  << (app.remaining().empty()
                          ? std::string("no command")
                          : "\"" + app.remaining().front() + "\" is not a command")
                  << ": one of status, watch, arm, disarm, reset, coupling, stream, record, scene, "
                     "identify, mark (hapticctl --help)\n";
        return hapticd::daemon::kExitBadInput;
    }
    if (instance_option->count() == 0 && socket_option->count() == 0) {
        std::cerr << "hapticctl: which daemon? give -i NAME (hapticd@NAME) or --socket PATH\n";
        return hapticd::daemon::kExitBadInput;
    }
    if (instance_option->count() != 0) {
        if (const auto bad = bad_instance_name(instance)) {
            std::cerr << "hapticctl: -i \"" << instance << "\": an instance name " << *bad << "\n";
            return hapticd::daemon::kExitBadInput;
        }
        socket_path = hapticd::ctl::instance_socket(instance);
    }
    try {
        // The stability check of a coupling or scene request may take seconds (check =
        // "exact"); a stream's events come once a period.
        std::chrono::milliseconds timeout = std::chrono::seconds(2);
        if (coupling->parsed() || scene_command->parsed()) timeout = std::chrono::seconds(120);
        if (record_command->parsed() || identify_command->parsed()) {
            timeout = std::chrono::seconds(30);
        }
        if (stream_command->parsed()) {
            timeout = std::max(timeout, std::chrono::milliseconds(static_cast<std::int64_t>(
                                            std::ceil(3000.0 / stream_rate_hz))));
        }
        ControlConnection daemon(socket_path, timeout);
        if (status->parsed()) {
            const nlohmann::json s = status_of(daemon);
            std::cout << (as_json ? s.dump() + "\n" : hapticd::ctl::status_text(s));
            return hapticd::daemon::kExitOk;
        }
        if (watch_command->parsed()) return watch(daemon, count);
        if (stream_command->parsed()) return stream(daemon, stream_rate_hz, stream_count);
        if (record_start->parsed()) return record(daemon, record_path);
        if (record_stop->parsed()) return record(daemon, std::nullopt);
        if (scene_command->parsed()) return load_scene(daemon, scene_path);
        if (mark_command->parsed()) return mark(daemon, mark_text);
        if (identify_command->parsed()) {
            return identify(daemon,
                            identify_file->count() == 0 ? std::nullopt
                                                        : std::optional<std::string>(identify_path),
                            !no_wait);
        }
        if (arm->parsed()) return change_state(daemon, RequestKind::arm);
        if (disarm->parsed()) return change_state(daemon, RequestKind::disarm);
        if (reset->parsed()) return change_state(daemon, RequestKind::reset);
        if (coupling->parsed()) {
            return set_coupling(
                daemon, stiffness,
                damping_option->count() != 0 ? std::optional<double>(damping) : std::nullopt);
        }
    } catch (const ConnectionError& e) {
        std::cerr << "hapticctl: " << e.what() << "\n";
        return hapticd::daemon::kExitFault;
    } catch (const nlohmann::json::exception& e) {
        std::cerr << "hapticctl: the daemon's reply is not as docs/control.md says: " << e.what()
                  << "\n";
        return hapticd::daemon::kExitFault;
    }
    return hapticd::daemon::kExitBadInput;
}

}  // namespace

// What hapticctl prints carries the daemon's strings (a scene's name, a path, a refusal that
// quotes a file): every control character in them is written out, so that none can clear the
// operator's screen or fake a state (docs/control.md, "What a client supplies").
class PrintableOutput {
  public:
    PrintableOutput()
        : out_(std::cout.rdbuf()),
          err_(std::cerr.rdbuf()),
          out_before_(std::cout.rdbuf(&out_)),
          err_before_(std::cerr.rdbuf(&err_)) {}
    ~PrintableOutput() {
        std::cout.flush();
        std::cout.rdbuf(out_before_);
        std::cerr.rdbuf(err_before_);
    }
    PrintableOutput(const PrintableOutput&) = delete;
    PrintableOutput& operator=(const PrintableOutput&) = delete;

  private:
    hapticd::input::PrintableFilter out_;
    hapticd::input::PrintableFilter err_;
    std::streambuf* out_before_;
    std::streambuf* err_before_;
};

int main(int argc, char** argv) {
    const PrintableOutput printable_output;
    try {
        return run_main(argc, argv);
    } catch (const std::exception& error) {
        std::cerr << "hapticctl: error: " << error.what() << "\n";
    } catch (...) {
        std::cerr << "hapticctl: error: an unknown exception\n";
    }
    return hapticd::daemon::kExitFault;
}
