#include "chart_options.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <sstream>

namespace hapticd::tools {
namespace {

std::string to_lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

/// The whole of `text` as a finite number; nothing for anything else ("", "3.5.1", "inf").
std::optional<double> parse_finite(const std::string& text) {
    if (text.empty() || std::isspace(static_cast<unsigned char>(text.front())) != 0) return {};
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(text.c_str(), &end);
    if (errno != 0 || end != text.c_str() + text.size() || !std::isfinite(value)) return {};
    return value;
}

}  // namespace

void add_chart_file_options(CLI::App& command, ChartLook& look, const std::string& out_flag,
                            const std::string& out_help) {
    look.out_flag = out_flag;
    command.add_option(out_flag, look.out, out_help);
    command.add_option("--size", look.size,
                       "figure width x height, in inches unless cm or mm follows, each 1 to "
                       "40 in: 3.5x2.6in for a journal column (default 7x4.8in)");
    command.add_option("--font-size", look.font_size_pt, "font size in points (default 9)")
        ->check(CLI::Range(4.0, 30.0));
}

void add_chart_look_options(CLI::App& command, ChartLook& look) {
    add_chart_file_options(command, look, "--out",
                           "chart file to write: .png, .svg (text kept as text) or .pdf "
                           "(required unless --json)");
    command.add_flag("--json", look.json, "print the charted data as JSON");
}

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
    add_chart_look_options(command, options.look);
    command.add_option("--points", options.points, "frequencies on the chart (default 400)")
        ->check(CLI::Range(10, 100000));
}

std::pair<double, double> chart_size_in(const std::string& size) {
    constexpr double kMinIn = 1.0;
    constexpr double kMaxIn = 40.0;
    const std::string allowed =
        "WxH with an optional unit in, cm or mm (e.g. 3.5x2.6in, "
        "90x60mm), each 1 to 40 in";
    std::string text = to_lower(trimmed(size));
    double inches_per_unit = 1.0;
    for (const auto& [unit, factor] :
         {std::pair{"mm", 1.0 / 25.4}, std::pair{"cm", 1.0 / 2.54}, std::pair{"in", 1.0}}) {
        const std::string suffix(unit);
        if (text.size() > suffix.size() && text.ends_with(suffix)) {
            text.resize(text.size() - suffix.size());
            inches_per_unit = factor;
            break;
        }
    }
    const std::size_t cross = text.find('x');
    std::optional<double> width;
    std::optional<double> height;
    if (cross != std::string::npos) {
        width = parse_finite(text.substr(0, cross));
        height = parse_finite(text.substr(cross + 1));
    }
    if (!width || !height) throw UsageError("--size " + size + ": not " + allowed);
    const std::pair<double, double> inches{*width * inches_per_unit, *height * inches_per_unit};
    for (const double side : {inches.first, inches.second}) {
        if (!(side >= kMinIn && side <= kMaxIn)) {
            throw UsageError("--size " + size + ": " + number_text(side, 4) +
                             " in is out of range (" + allowed + ")");
        }
    }
    return inches;
}

nlohmann::ordered_json chart_output_json(const ChartLook& look) {
    const auto [width_in, height_in] = chart_size_in(look.size);
    return {{"path", look.out},
            {"format", chart_format(look.out, look.out_flag)},
            {"size_in", {width_in, height_in}},
            {"font_size_pt", look.font_size_pt}};
}

void check_chart_output(const ChartLook& look) {
    chart_size_in(look.size);
    if (look.out.empty()) {
        if (!look.json) {
            throw UsageError(look.out_flag +
                             " FILE (.png, .svg or .pdf) is required unless --json");
        }
        return;
    }
    chart_format(look.out, look.out_flag);
    check_writable(look.out, look.out_flag);
}

std::string chart_format(const std::string& path, const std::string& flag) {
    const std::string extension = to_lower(std::filesystem::path(path).extension().string());
    for (const char* format : {"png", "svg", "pdf"}) {
        if (extension == std::string(".") + format) return format;
    }
    throw UsageError(flag + " " + path + ": unsupported file extension '" +
                     std::filesystem::path(path).extension().string() +
                     "' (allowed: .png, .svg, .pdf)");
}

void check_writable(const std::string& path, const std::string& flag) {
    namespace fs = std::filesystem;
    std::error_code error;
    const fs::file_status status = fs::status(path, error);
    if (fs::exists(status)) {
        if (!fs::is_regular_file(status)) {
            throw UsageError(flag + " " + path + ": exists and is not a regular file");
        }
        if (::access(path.c_str(), W_OK) != 0) {
            throw UsageError(flag + " " + path + ": not writable (" + std::strerror(errno) + ")");
        }
        return;
    }
    fs::path directory = fs::path(path).parent_path();
    if (directory.empty()) directory = ".";
    if (!fs::is_directory(directory, error)) {
        throw UsageError(flag + " " + path + ": directory " + directory.string() +
                         " does not exist");
    }
    if (::access(directory.c_str(), W_OK | X_OK) != 0) {
        throw UsageError(flag + " " + path + ": directory " + directory.string() +
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
