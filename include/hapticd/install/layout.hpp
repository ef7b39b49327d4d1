// Where the running executable finds its plugins and data files (docs/install.md).
//
// An executable of a build tree (<build>/bin/) uses that build tree's files only; any other
// copy is an installed one and uses the files of its own installation only, found relative
// to the executable (<prefix>/bin/../<libdir>/hapticd/plugins), so that a staged install
// (DESTDIR), a relocated prefix and the .deb all work, and an installed hapticd never loads a
// plugin from a build tree that happens to exist on the same PC, nor the other way round.
#pragma once

#include <string>

namespace hapticd::install {

struct Layout {
    bool build_tree = false;   ///< the executable is the build tree's, not an installed copy
    std::string executable;    ///< its absolute path (/proc/self/exe)
    std::string plugin_dir;    ///< the device plugins (hapticd-device-<kind>.so)
    std::string chart_script;  ///< hapticd_chart.py, which haptic-tune runs to draw charts
};

/// The layout of the running executable, worked out once.
const Layout& layout();

/// The layout of an executable at `executable` (an absolute path); layout() is this for
/// /proc/self/exe. Lexical: no file is looked at except to resolve symbolic links.
Layout layout_for(const std::string& executable);

}  // namespace hapticd::install
