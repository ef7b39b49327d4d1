#include "chart_renderer.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "hapticd/theory/unit_circle.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/input_checks.hpp"

extern char** environ;

#ifndef HAPTICD_CHART_SCRIPT_BUILD
#error "HAPTICD_CHART_SCRIPT_BUILD must be defined (tools/haptic-tune/CMakeLists.txt)"
#endif
#ifndef HAPTICD_CHART_SCRIPT_INSTALLED
#error "HAPTICD_CHART_SCRIPT_INSTALLED must be defined (tools/haptic-tune/CMakeLists.txt)"
#endif

namespace hapticd::tools {
namespace {

constexpr const char* kDefaultPython = "/usr/bin/python3";
/// hapticd_chart.py exits with this code when it cannot import matplotlib.
constexpr int kScriptNoMatplotlib = 3;
constexpr const char* kInstallHint =
    "install python3-matplotlib (Debian/Ubuntu: apt install python3-matplotlib), or set "
    "HAPTICD_PYTHON to a python interpreter that has matplotlib";

std::string env_or_empty(const char* name) {
    const char* value = std::getenv(name);
    return value == nullptr ? std::string() : std::string(value);
}

bool is_regular_file(const std::string& path) {
    std::error_code error;
    return std::filesystem::is_regular_file(path, error);
}

std::string find_chart_script() {
    if (const std::string from_env = env_or_empty("HAPTICD_CHART_SCRIPT"); !from_env.empty()) {
        if (!is_regular_file(from_env)) {
            throw ChartError("HAPTICD_CHART_SCRIPT=" + from_env + " is not a file");
        }
        return from_env;
    }
    for (const char* candidate : {HAPTICD_CHART_SCRIPT_BUILD, HAPTICD_CHART_SCRIPT_INSTALLED}) {
        if (is_regular_file(candidate)) return candidate;
    }
    throw ChartError(std::string("chart script hapticd_chart.py not found (looked for ") +
                     HAPTICD_CHART_SCRIPT_BUILD + " and " + HAPTICD_CHART_SCRIPT_INSTALLED +
                     "); set HAPTICD_CHART_SCRIPT to its path");
}

std::string trim(const std::string& text) {
    const auto first = text.find_first_not_of(" \t\r\n");
    if (first == std::string::npos) return {};
    const auto last = text.find_last_not_of(" \t\r\n");
    return text.substr(first, last - first + 1);
}

std::string to_lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

/// Closes a file descriptor once.
class Fd {
  public:
    explicit Fd(int fd = -1) : fd_(fd) {}
    Fd(const Fd&) = delete;
    Fd& operator=(const Fd&) = delete;
    ~Fd() { reset(); }
    int get() const { return fd_; }
    void reset() {
        if (fd_ >= 0) ::close(fd_);
        fd_ = -1;
    }

  private:
    int fd_;
};

/// Ignores SIGPIPE while it lives, so a script that exits early makes write() fail with
/// EPIPE instead of killing haptic-tune.
class IgnoreSigpipe {
  public:
    IgnoreSigpipe() {
        struct sigaction ignore {};
        ignore.sa_handler = SIG_IGN;
        sigemptyset(&ignore.sa_mask);
        ::sigaction(SIGPIPE, &ignore, &old_);
    }
    IgnoreSigpipe(const IgnoreSigpipe&) = delete;
    IgnoreSigpipe& operator=(const IgnoreSigpipe&) = delete;
    ~IgnoreSigpipe() { ::sigaction(SIGPIPE, &old_, nullptr); }

  private:
    struct sigaction old_ {};
};

}  // namespace

void add_chart_options(CLI::App& command, ChartOptions& options) {
    add_device_options(command, options.device);
    command
        .add_option("--stiffness", options.stiffness,
                    "coupling stiffness k_c (N/m); default [coupling] stiffness from "
                    "--config, else sized from (21) with the passive model")
        ->check(non_negative_finite("N/m"));
    command
        .add_option("--coupling-damping", options.coupling_damping,
                    "coupling damping b_c (N s/m); default [coupling] damping from "
                    "--config, else 0")
        ->check(non_negative_finite("N s/m"));
    command.add_option("--models", options.models,
                       "comma-separated stability models to draw: paper, encoder, passive "
                       "(default paper,encoder,passive)");
    command.add_option("--out", options.out,
                       "chart file to write, .png or .svg (required unless --json)");
    command.add_option("--points", options.points, "frequencies on the chart (default 400)")
        ->check(CLI::Range(10, 100000));
    command.add_flag("--json", options.json, "print the plotted data as JSON");
}

void check_chart_output(const ChartOptions& options) {
    if (options.out.empty()) {
        if (!options.json) throw UsageError("--out FILE (.png or .svg) is required unless --json");
        return;
    }
    chart_format(options.out);
    check_writable(options.out);
}

std::string chart_format(const std::string& path) {
    const std::string extension = to_lower(std::filesystem::path(path).extension().string());
    if (extension == ".png") return "png";
    if (extension == ".svg") return "svg";
    throw UsageError("--out " + path + ": unsupported file extension '" +
                     std::filesystem::path(path).extension().string() + "' (allowed: .png, .svg)");
}

void check_writable(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code error;
    const fs::file_status status = fs::status(path, error);
    if (fs::exists(status)) {
        if (!fs::is_regular_file(status)) {
            throw UsageError("--out " + path + ": exists and is not a regular file");
        }
        if (::access(path.c_str(), W_OK) != 0) {
            throw UsageError("--out " + path + ": not writable (" + std::strerror(errno) + ")");
        }
        return;
    }
    fs::path directory = fs::path(path).parent_path();
    if (directory.empty()) directory = ".";
    if (!fs::is_directory(directory, error)) {
        throw UsageError("--out " + path + ": directory " + directory.string() + " does not exist");
    }
    if (::access(directory.c_str(), W_OK | X_OK) != 0) {
        throw UsageError("--out " + path + ": directory " + directory.string() +
                         " is not writable (" + std::strerror(errno) + ")");
    }
}

std::vector<theory::HoldModel> parse_model_list(const std::string& list) {
    std::vector<theory::HoldModel> models;
    std::stringstream stream(list);
    std::string item;
    while (std::getline(stream, item, ',')) {
        const std::string name = trim(item);
        if (name.empty()) {
            throw UsageError("--models '" + list +
                             "': empty model name (allowed: paper, encoder, passive)");
        }
        const std::optional<theory::HoldModel> model = theory::parse_hold_model(name);
        if (!model) {
            throw UsageError("--models: unknown model '" + name +
                             "' (allowed: paper, encoder, passive)");
        }
        if (std::find(models.begin(), models.end(), *model) == models.end()) {
            models.push_back(*model);
        }
    }
    if (models.empty()) throw UsageError("--models is empty (allowed: paper, encoder, passive)");
    return models;
}

std::vector<double> chart_frequencies_hz(double rate_hz, int points) {
    const double nyquist = theory::nyquist_hz(1.0 / rate_hz);
    const double lowest = std::min(0.1, nyquist / 1000.0);
    std::vector<double> frequencies(static_cast<std::size_t>(points));
    const double ratio = std::log(nyquist / lowest);
    for (int i = 0; i < points; ++i) {
        frequencies[static_cast<std::size_t>(i)] =
            lowest * std::exp(ratio * static_cast<double>(i) / static_cast<double>(points - 1));
    }
    frequencies.front() = lowest;
    frequencies.back() = nyquist;
    return frequencies;
}

ImpedanceDesign resolve_impedance_design(const ChartOptions& options, const DesignInput& input) {
    tune::check_device(input.device);
    tune::check_rate(input.rate_hz);
    ImpedanceDesign design;
    design.coupling.damping_n_s_per_m =
        options.coupling_damping.value_or(input.coupling_damping_n_s_per_m.value_or(0.0));
    design.coupling.velocity_filter_hz = input.velocity_filter_hz;
    if (options.stiffness) {
        design.coupling.stiffness_n_per_m = *options.stiffness;
        design.source = "flags";
    } else if (input.coupling_stiffness_n_per_m) {
        design.coupling.stiffness_n_per_m = *input.coupling_stiffness_n_per_m;
        design.source = "config";
    } else {
        tune::ImpedanceSizingRequest request;
        request.device = input.device;
        request.rate_hz = input.rate_hz;
        request.model = {theory::HoldModel::passive, input.delay_periods()};
        request.coupling_damping_n_s_per_m = design.coupling.damping_n_s_per_m;
        request.velocity_filter_hz = design.coupling.velocity_filter_hz;
        const tune::ImpedanceSizing sizing = tune::size_impedance_coupling(request);
        design.coupling = sizing.coupling;
        design.source = "sized";
        design.sized_binding_frequency_hz = sizing.binding_frequency_hz;
    }
    if (design.coupling.stiffness_n_per_m == 0.0 && design.coupling.damping_n_s_per_m == 0.0) {
        throw UsageError("--stiffness 0 with --coupling-damping 0 is no coupling at all");
    }
    return design;
}

nlohmann::ordered_json design_json(const ImpedanceDesign& design) {
    nlohmann::ordered_json out = {{"stiffness", design.coupling.stiffness_n_per_m},
                                  {"damping", design.coupling.damping_n_s_per_m},
                                  {"velocity_filter_hz", design.coupling.velocity_filter_hz},
                                  {"source", design.source}};
    if (design.source == "sized") {
        out["sizing_model"] = "passive";
        out["sizing_binding_frequency_hz"] = design.sized_binding_frequency_hz;
    }
    return out;
}

std::string format_number(double value) {
    std::ostringstream text;
    text << std::setprecision(4) << value;
    return text.str();
}

std::string describe_design(const ImpedanceDesign& design) {
    std::string text = "k_c = " + format_number(design.coupling.stiffness_n_per_m) +
                       " N/m, b_c = " + format_number(design.coupling.damping_n_s_per_m) + " N s/m";
    if (design.coupling.velocity_filter_hz > 0.0) {
        text +=
            " on a " + format_number(design.coupling.velocity_filter_hz) + " Hz velocity filter";
    }
    if (design.source == "sized") text += " (sized from (21) with the passive model)";
    if (design.source == "config") text += " (from [coupling] in the config)";
    return text;
}

std::string describe_device(const DesignInput& input) {
    return "m = " + format_number(input.device.mass_kg) +
           " kg, b = " + format_number(input.device.damping_n_s_per_m) + " N s/m, " +
           format_number(input.rate_hz) + " Hz servo";
}

ScriptRun run_python_script(const std::string& python, const std::string& script,
                            const std::string& input) {
    std::array<int, 2> to_child{};
    std::array<int, 2> from_child{};
    if (::pipe2(to_child.data(), O_CLOEXEC) != 0) {
        throw ChartError(std::string("pipe: ") + std::strerror(errno));
    }
    Fd child_in(to_child[0]);
    Fd write_end(to_child[1]);
    if (::pipe2(from_child.data(), O_CLOEXEC) != 0) {
        throw ChartError(std::string("pipe: ") + std::strerror(errno));
    }
    Fd read_end(from_child[0]);
    Fd child_out(from_child[1]);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, child_in.get(), STDIN_FILENO);
    // The script's stdout goes with its stderr: haptic-tune's own stdout may carry --json.
    posix_spawn_file_actions_adddup2(&actions, child_out.get(), STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, child_out.get(), STDERR_FILENO);
    std::vector<std::string> args = {python, script};
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int spawn_error =
        ::posix_spawnp(&pid, python.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawn_error != 0) {
        throw ChartError("cannot run the python interpreter '" + python +
                         "': " + std::strerror(spawn_error) + "; " + kInstallHint);
    }
    child_in.reset();
    child_out.reset();

    IgnoreSigpipe ignore_sigpipe;
    ::fcntl(write_end.get(), F_SETFL, ::fcntl(write_end.get(), F_GETFL) | O_NONBLOCK);
    ScriptRun run;
    std::size_t written = 0;
    if (input.empty()) write_end.reset();
    while (write_end.get() >= 0 || read_end.get() >= 0) {
        std::array<pollfd, 2> fds{};
        nfds_t count = 0;
        if (write_end.get() >= 0) fds[count++] = {write_end.get(), POLLOUT, 0};
        if (read_end.get() >= 0) fds[count++] = {read_end.get(), POLLIN, 0};
        if (::poll(fds.data(), count, -1) < 0) {
            if (errno == EINTR) continue;
            break;
        }
        for (nfds_t i = 0; i < count; ++i) {
            if (fds[i].revents == 0) continue;
            if (fds[i].fd == write_end.get()) {
                const ssize_t n =
                    ::write(write_end.get(), input.data() + written, input.size() - written);
                if (n > 0) written += static_cast<std::size_t>(n);
                const bool failed = n < 0 && errno != EAGAIN && errno != EINTR;
                if (failed || written == input.size()) write_end.reset();  // EOF for the script
            } else {
                std::array<char, 4096> buffer{};
                const ssize_t n = ::read(read_end.get(), buffer.data(), buffer.size());
                if (n > 0) {
                    run.output.append(buffer.data(), static_cast<std::size_t>(n));
                } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
                    read_end.reset();
                }
            }
        }
    }
    write_end.reset();  // also on a poll() failure, so the script cannot wait on us forever
    read_end.reset();
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) throw ChartError(std::string("waitpid: ") + std::strerror(errno));
    }
    if (WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) run.signal = WTERMSIG(status);
    return run;
}

void render_chart(nlohmann::ordered_json chart, const std::string& out_path,
                  const std::string& format) {
    std::string python = env_or_empty("HAPTICD_PYTHON");
    if (python.empty()) python = kDefaultPython;
    const std::string script = find_chart_script();
    chart["output"] = {{"path", out_path}, {"format", format}};
    const ScriptRun run = run_python_script(python, script, chart.dump());
    const std::string said = trim(run.output);
    if (run.exit_code == kScriptNoMatplotlib) {
        throw ChartError("cannot draw the chart: " + python + " has no matplotlib; " +
                         kInstallHint + (said.empty() ? "" : " (" + said + ")"));
    }
    if (run.exit_code != 0) {
        std::string what = run.signal != 0 ? "was killed by signal " + std::to_string(run.signal)
                                           : "exited with status " + std::to_string(run.exit_code);
        throw ChartError("chart script " + script + " (run with " + python + ") " + what +
                         (said.empty() ? std::string() : ":\n" + said));
    }
    std::error_code error;
    if (!std::filesystem::is_regular_file(out_path, error) ||
        std::filesystem::file_size(out_path, error) == 0) {
        throw ChartError("chart script " + script + " reported success but wrote no " + out_path);
    }
}

}  // namespace hapticd::tools
