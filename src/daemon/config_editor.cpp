// Value edits in a TOML config that keep the rest of the text (config_editor.hpp).
#include "hapticd/daemon/config_editor.hpp"

#include <toml++/toml.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "hapticd/input/text_input.hpp"

namespace hapticd::daemon {
namespace {

struct Line {
    std::string text;  ///< without the newline
    bool newline = true;
};

std::vector<Line> split_lines(std::string_view text) {
    std::vector<Line> lines;
    std::size_t start = 0;
    while (start < text.size()) {
        const std::size_t end = text.find('\n', start);
        if (end == std::string_view::npos) {
            lines.push_back({std::string(text.substr(start)), false});
            break;
        }
        lines.push_back({std::string(text.substr(start, end - start)), true});
        start = end + 1;
    }
    return lines;
}

std::string join_lines(const std::vector<Line>& lines) {
    std::string out;
    for (const Line& line : lines) out += line.text + (line.newline ? "\n" : "");
    return out;
}

std::string value_text(const ConfigValue& value) {
    if (const auto* number = std::get_if<double>(&value)) return format_config_number(*number);
    if (const auto* flag = std::get_if<bool>(&value)) return *flag ? "true" : "false";
    std::string quoted = "\"";
    for (const char c : std::get<std::string>(value)) {
        if (c == '"' || c == '\\') quoted += '\\';
        quoted += c;
    }
    return quoted + "\"";
}

/// Every leaf of a parsed document as "dotted.key" -> its printed value.
void flatten(const toml::table& table, const std::string& prefix,
             std::map<std::string, std::string>& out) {
    for (const auto& [key, node] : table) {
        const std::string name = prefix + std::string(key.str());
        if (const auto* sub = node.as_table()) {
            flatten(*sub, name + ".", out);
        } else {
            std::ostringstream s;
            node.visit([&s](const auto& v) { s << v; });
            out[name] = s.str();
        }
    }
}

toml::table parse(std::string_view text, const std::string& source, const char* which) {
    if (const std::string e = input::toml_shape_error(text, source); !e.empty()) {
        throw ConfigEditError(e);
    }
    try {
        return toml::parse(text, source);
    } catch (const toml::parse_error& e) {
        std::ostringstream m;
        m << source << ": " << which << " is not valid TOML: " << e.description() << " (line "
          << e.source().begin.line << ")";
        throw ConfigEditError(m.str());
    }
}

const std::regex kTableHeader(R"(^\s*\[\s*([A-Za-z0-9_.\- ]+?)\s*\]\s*(#.*)?$)");
// key = value [# comment]; the value is a number, boolean or a basic string without '#'.
const std::regex kKeyValue(
    R"(^(\s*)([A-Za-z0-9_\-]+)(\s*=\s*)([^#"\s][^#]*?|"[^"#]*")(\s*)(#.*)?$)");

}  // namespace

std::string format_config_number(double value) {
    char buffer[64];
    const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, value);  // shortest
    std::string text = error == std::errc() ? std::string(buffer, end) : std::to_string(value);
    if (std::isfinite(value) && text.find_first_of(".e") == std::string::npos) text += ".0";
    return text;
}

EditedConfig edit_config_text(std::string_view text, const std::vector<ConfigEdit>& edits,
                              const std::string& source) {
    const toml::table before = parse(text, source, "the config");
    std::vector<Line> lines = split_lines(text);
    EditedConfig result;

    for (const ConfigEdit& edit : edits) {
        const std::string new_value = value_text(edit.value);
        std::string table;  // the current table header ("" before the first)
        int table_header = -1;
        int last_key_in_table = -1;
        bool done = false;
        for (std::size_t i = 0; i < lines.size() && !done; ++i) {
            std::smatch m;
            if (std::regex_match(lines[i].text, m, kTableHeader)) {
                table = m[1].str();
                if (table == edit.table) table_header = static_cast<int>(i);
                continue;
            }
            if (table != edit.table || !std::regex_match(lines[i].text, m, kKeyValue)) continue;
            last_key_in_table = static_cast<int>(i);
            if (m[2].str() != edit.key) continue;
            // Replace the value; keep the comment where it was when the value fits.
            const std::string old_value = m[4].str();
            std::string padding = m[5].str();
            if (m[6].matched) {
                const long shift =
                    static_cast<long>(new_value.size()) - static_cast<long>(old_value.size());
                const long width = static_cast<long>(padding.size()) - shift;
                padding = std::string(static_cast<std::size_t>(std::max(1L, width)), ' ');
            }
            lines[i].text = m[1].str() + m[2].str() + m[3].str() + new_value +
                            (m[6].matched ? padding + m[6].str() : std::string());
            result.changes.push_back({edit.table, edit.key, old_value, new_value});
            done = true;
        }
        if (done) continue;
        const std::string line = edit.key + " = " + new_value;
        if (table_header >= 0) {
            const int after = std::max(table_header, last_key_in_table);
            lines.insert(lines.begin() + after + 1, Line{line, true});
        } else {
            if (!lines.empty() && !lines.back().newline) lines.back().newline = true;
            lines.push_back({"", true});
            lines.push_back({"[" + edit.table + "]", true});
            lines.push_back({line, true});
        }
        result.changes.push_back({edit.table, edit.key, "", new_value});
    }
    result.text = join_lines(lines);

    // The check: edited keys read back, nothing else moved.
    std::string edited_keys;
    for (const ConfigEdit& edit : edits) {
        edited_keys += (edited_keys.empty() ? "" : ", ") + edit.table + "." + edit.key;
    }
    toml::table after;
    try {
        after = toml::parse(result.text, source);
    } catch (const toml::parse_error& e) {
        throw ConfigEditError(source + ": could not set " + edited_keys +
                              " by editing the text: the result would not be valid TOML (" +
                              std::string(e.description()) +
                              "; does the file set the table as an inline table or with dotted "
                              "keys?); write it as a [table] with one key per line, or set it "
                              "by hand");
    }
    std::map<std::string, std::string> old_values;
    std::map<std::string, std::string> new_values;
    flatten(before, "", old_values);
    flatten(after, "", new_values);
    std::map<std::string, std::string> expected = old_values;
    for (const ConfigEdit& edit : edits) {
        toml::table probe;
        const std::string name = edit.table + "." + edit.key;
        std::ostringstream printed;
        std::visit(
            [&](const auto& v) {
                probe.insert("v", v);
                probe["v"].visit([&printed](const auto& x) { printed << x; });
            },
            edit.value);
        expected[name] = printed.str();
    }
    for (const auto& [name, value] : expected) {
        const auto found = new_values.find(name);
        if (found == new_values.end() || found->second != value) {
            throw ConfigEditError(source + ": could not set " + name +
                                  " by editing the text (the file sets it in a form the editor "
                                  "does not rewrite: a dotted key or an inline table?); write it "
                                  "as a [table] with one key per line, or set it by hand");
        }
    }
    if (new_values.size() != expected.size()) {
        throw ConfigEditError(source +
                              ": editing the text would have changed other keys; "
                              "nothing was written");
    }
    return result;
}

void write_config_with_backup(const std::string& path, const std::string& text,
                              const std::string& backup_path) {
    namespace fs = std::filesystem;
    std::error_code error;
    fs::copy_file(path, backup_path, fs::copy_options::overwrite_existing, error);
    if (error) {
        throw std::runtime_error("could not back up " + path + " to " + backup_path + ": " +
                                 error.message() + "; the config was not changed");
    }
    const std::string temporary = path + ".tmp";
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        out << text;
        out.flush();
        if (!out) {
            throw std::runtime_error("could not write " + temporary + ": " + std::strerror(errno) +
                                     "; the config was not changed");
        }
    }
    fs::permissions(temporary, fs::status(path).permissions(), error);
    fs::rename(temporary, path, error);
    if (error) {
        fs::remove(temporary);
        throw std::runtime_error("could not replace " + path + ": " + error.message() +
                                 "; the config was not changed (backup at " + backup_path + ")");
    }
}

}  // namespace hapticd::daemon
