#include "hapticd/install/plugin_files.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "hapticd/install/layout.hpp"

namespace hapticd::install {

std::vector<std::string> plugin_search_path() {
    std::vector<std::string> dirs;
    if (const char* env = std::getenv("HAPTICD_PLUGIN_PATH"); env != nullptr) {
        std::string_view rest(env);
        while (true) {
            const std::size_t colon = rest.find(':');
            const std::string_view dir = rest.substr(0, colon);
            if (!dir.empty()) dirs.emplace_back(dir);
            if (colon == std::string_view::npos) break;
            rest.remove_prefix(colon + 1);
        }
    }
    dirs.push_back(layout().plugin_dir);
    return dirs;
}

std::vector<std::string> plugin_file_names(std::string_view kind, std::string_view name) {
    const std::string base = "hapticd-" + std::string(kind) + "-" + std::string(name) + ".so";
    return {"lib" + base, base};
}

std::string find_plugin_file(std::string_view kind, std::string_view name_or_path) {
    if (name_or_path.empty()) throw std::runtime_error(std::string(kind) + " plugin name is empty");
    if (name_or_path.find('/') != std::string_view::npos) return std::string(name_or_path);
    std::vector<std::string> tried;
    for (const std::string& dir : plugin_search_path()) {
        for (const std::string& file : plugin_file_names(kind, name_or_path)) {
            std::string path = dir + "/" + file;
            std::error_code ec;
            if (std::filesystem::is_regular_file(path, ec)) return path;
            tried.push_back(std::move(path));
        }
    }
    std::ostringstream message;
    message << kind << " plugin '" << name_or_path << "' not found; looked for:";
    for (const std::string& path : tried) message << "\n  " << path;
    message << "\n(set HAPTICD_PLUGIN_PATH to a colon-separated list of directories, or give "
               "a path containing '/')";
    throw std::runtime_error(message.str());
}

std::shared_ptr<void> open_plugin_library(const std::string& path, std::string& error) {
    dlerror();  // clear any stale error
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
        const char* text = dlerror();
        error = text != nullptr ? text : "unknown dynamic-loader error";
        return nullptr;
    }
    return {handle, [](void* h) { dlclose(h); }};
}

}  // namespace hapticd::install
