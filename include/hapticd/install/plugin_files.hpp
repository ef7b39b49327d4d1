// Where plugins are found, for both kinds (device plugins, device/plugin_loader.hpp;
// environment plugins, env/plugin_environment.hpp), outside the tick.
//
// A name ("sim") of kind KIND ("device", "env") is looked up as `libhapticd-KIND-<name>.so`,
// then `hapticd-KIND-<name>.so`, in each directory of plugin_search_path() in order, first
// match wins:
//   1. $HAPTICD_PLUGIN_PATH, a colon-separated list (empty entries are skipped);
//   2. the executable's own plugin directory (install/layout.hpp): the build tree's
//      (<build>/lib/hapticd/plugins) for a build tree's executable, else its installation's
//      (<prefix>/<libdir>/hapticd/plugins), never both.
// A string containing '/' is a path and is used as given.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace hapticd::install {

/// The directories searched for a plugin name, in order (see the file comment).
std::vector<std::string> plugin_search_path();

/// File names tried in each directory for a plugin `name` of `kind`: lib-prefixed first.
std::vector<std::string> plugin_file_names(std::string_view kind, std::string_view name);

/// The file of plugin `name_or_path` of `kind`. Throws std::runtime_error when the name is
/// empty or no file is found: "KIND plugin 'NAME' not found; looked for:" and every file tried.
std::string find_plugin_file(std::string_view kind, std::string_view name_or_path);

/// dlopen(RTLD_NOW | RTLD_LOCAL) of `path`, dlclose()d when the last owner goes; null with
/// dlopen's own text in `error` when it fails.
std::shared_ptr<void> open_plugin_library(const std::string& path, std::string& error);

}  // namespace hapticd::install
