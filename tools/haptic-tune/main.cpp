// haptic-tune: the offline design tool. Sizes the virtual coupling from (21), checks any
// design against the stability models, and draws the design-procedure charts.
#include <iostream>
#include <optional>

#include "commands.hpp"
#include "hapticd/input/input_error.hpp"
#include "hapticd/install/version.hpp"
#include "parse_command_line.hpp"

namespace {

int run_main(int argc, char** argv) {
    using namespace hapticd::tools;
    CLI::App app{
        "haptic-tune: size and check the virtual coupling of an impedance haptic display "
        "(Adams & Hannaford 1999, inequality (21))",
        "haptic-tune"};
    app.set_version_flag("--version", std::string("haptic-tune ") + hapticd::install::kVersion);
    app.require_subcommand(1);
    Invocation invocation;
    add_size_command(app, invocation);
    add_check_command(app, invocation);
    add_plot_command(app, invocation);
    add_zwidth_command(app, invocation);
    add_plot_run_command(app, invocation);
    add_diag_command(app, invocation);
    add_identify_command(app, invocation);
    add_autotune_command(app, invocation);
    add_conform_command(app, invocation);
    if (const std::optional<int> ended = parse_command_line(app, argc, argv)) return *ended;
    try {
        return invocation.run();
    } catch (const hapticd::input::InputError& error) {  // "config error", "infeasible", ...
        std::cerr << "haptic-tune: " << error.kind() << ": " << error.what() << '\n';
    } catch (const std::invalid_argument& error) {  // a model's own range check
        std::cerr << "haptic-tune: invalid input: " << error.what() << '\n';
    } catch (const std::exception& error) {
        // Anything else is a failure of the computation on this input, never a crash.
        std::cerr << "haptic-tune: error: " << error.what() << '\n';
    }
    return kExitBadInput;
}

}  // namespace

/// Nothing escapes, not even from setting up the command line: a message and exit 2.
int main(int argc, char** argv) {
    try {
        return run_main(argc, argv);
    } catch (const std::exception& error) {
        std::cerr << "haptic-tune: error: " << error.what() << '\n';
    } catch (...) {
        std::cerr << "haptic-tune: error: an unknown exception\n";
    }
    return hapticd::tools::kExitBadInput;
}
