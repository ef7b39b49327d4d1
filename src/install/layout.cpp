#include "hapticd/install/layout.hpp"

#include <filesystem>
#include <system_error>

#ifndef HAPTICD_BUILD_BIN_DIR
#error "HAPTICD_BUILD_BIN_DIR and the other layout paths come from src/install/CMakeLists.txt"
#endif

namespace hapticd::install {
namespace {

namespace fs = std::filesystem;

fs::path resolved(const fs::path& path) {
    std::error_code error;
    fs::path canonical = fs::weakly_canonical(path, error);
    return error ? path.lexically_normal() : canonical;
}

}  // namespace

Layout layout_for(const std::string& executable) {
    Layout layout;
    layout.executable = resolved(executable).string();
    const fs::path bin_dir = fs::path(layout.executable).parent_path();
    layout.build_tree = bin_dir == resolved(HAPTICD_BUILD_BIN_DIR);
    if (layout.build_tree) {
        layout.plugin_dir = HAPTICD_BUILD_PLUGIN_DIR;
        layout.chart_script = HAPTICD_BUILD_CHART_SCRIPT;
    } else {
        layout.plugin_dir = (bin_dir / HAPTICD_PLUGIN_DIR_FROM_BIN).lexically_normal().string();
        layout.chart_script = (bin_dir / HAPTICD_CHART_SCRIPT_FROM_BIN).lexically_normal().string();
    }
    return layout;
}

const Layout& layout() {
    static const Layout self = [] {
        std::error_code error;
        const fs::path exe = fs::read_symlink("/proc/self/exe", error);
        return layout_for(error ? std::string() : exe.string());
    }();
    return self;
}

}  // namespace hapticd::install
