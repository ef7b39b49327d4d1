#include "chart_options.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <sstream>

namespace hapticd::tools {
namespace {

std::string to_lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

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
        const std::string name = trimmed(item);
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

}  // namespace hapticd::tools
