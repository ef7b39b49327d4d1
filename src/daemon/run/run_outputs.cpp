#include "run/run_outputs.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ostream>

#include "hapticd/daemon/journal.hpp"

namespace hapticd::daemon {

bool write_summary(const RunOptions& options, Outputs& outputs, const servo::Summary& summary,
                   const RunContext& context, std::ostream& out, std::ostream& log) {
    if (!options.summary_path) {
        log << summary_text(summary, context);
        return true;
    }
    const std::string json = summary_json(summary, context) + "\n";
    if (*options.summary_path == "-") {
        out << json << std::flush;
        return static_cast<bool>(out);
    }
    bool written = outputs.summary && write_all(outputs.summary.fd(), json);
    const int error = errno;
    if (outputs.summary && ::close(outputs.summary.release()) != 0 && written) written = false;
    if (!written) {
        log << priority::err << "hapticd: --summary " << *options.summary_path
            << ": cannot write the summary: " << std::strerror(error) << "\n";
        log << json;
    }
    return written;
}

Outputs prepare_outputs(const RunOptions& options, const Config& config) {
    std::vector<NamedPath> inputs;
    if (options.config_path) inputs.push_back({"--config", *options.config_path});
    if (!config.scene_file.empty()) {
        inputs.push_back({"the scene ([scene] file in " + config.source + ")", config.scene_file});
    }
    if (const std::string plugin = plugin_file(config.device.plugin); !plugin.empty()) {
        inputs.push_back({"the device plugin ([device] plugin in " + config.source + ")", plugin});
    }
    std::vector<NamedPath> outputs;
    if (options.log_path) outputs.push_back({"--log", *options.log_path});
    if (options.summary_path && *options.summary_path != "-") {
        outputs.push_back({"--summary", *options.summary_path});
    }
    Outputs opened;
    refuse_overlapping_paths(inputs, outputs);
    if (options.log_path) opened.log = open_locked_log("--log", *options.log_path);
    if (options.summary_path && *options.summary_path != "-") {
        opened.summary = open_output("--summary", *options.summary_path);
    }
    if (options.socket_path) {
        try {
            opened.control = std::make_unique<control_socket::SocketServer>(*options.socket_path);
        } catch (const control_socket::ControlSocketError& e) {
            throw input::with_context("--socket: ", e);
        }
    }
    return opened;
}

}  // namespace hapticd::daemon
