// The run's output files, --log and --summary: refused when they are inputs or each other,
// created and locked before the device opens, and the summary written when the run ends.
#pragma once

#include <iosfwd>
#include <memory>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/output_files.hpp"
#include "hapticd/daemon/run.hpp"
#include "hapticd/servo/summary.hpp"
#include "outputs/summary_json.hpp"
#include "socket/server.hpp"

namespace hapticd::daemon {

/// The outputs, opened before the device (prepare_outputs()).
struct Outputs {
    OutputFile log;      ///< --log, locked; emptied when the run starts
    OutputFile summary;  ///< --summary FILE; emptied when the run starts
    /// --socket: bound and listening, served once the loop exists (docs/control.md).
    std::unique_ptr<control_socket::SocketServer> control;
};

/// Refuses outputs that are inputs (or each other), then creates them: all before the device
/// is opened, so that a run that could not keep its results never starts; and binds the
/// control socket. Throws OutputError naming the option and the file, or
/// control_socket::ControlSocketError.
Outputs prepare_outputs(const RunOptions& options, const Config& config);

/// Writes the summary: JSON to --summary FILE or "-" (`out`), else text to `log`. False when
/// --summary FILE could not be written whole (the JSON then goes to `log`, so that it is not
/// lost).
bool write_summary(const RunOptions& options, Outputs& outputs, const servo::Summary& summary,
                   const RunContext& context, std::ostream& out, std::ostream& log);

}  // namespace hapticd::daemon
