// The one TOML field reader (table_reader.hpp).
#include "hapticd/input/table_reader.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "hapticd/input/printable.hpp"
#include "hapticd/input/text_input.hpp"

namespace hapticd::input {

std::string format_value(const toml::node& node) {
    std::ostringstream out;
    if (const auto* text = node.as_string()) {
        out << '"' << text->get() << '"';
    } else if (const auto* array = node.as_array()) {
        out << '[';
        for (std::size_t i = 0; i < array->size(); ++i) {
            out << (i ? ", " : "") << format_value(*array->get(i));
        }
        out << ']';
    } else if (node.is_table()) {
        out << "{...}";
    } else if (const auto* integer = node.as_integer()) {
        out << *integer;  // as written: 0x12345 stays hexadecimal
    } else if (const auto* floating = node.as_floating_point()) {
        std::string number = format_number(floating->get());
        if (number.find_first_of(".eni") == std::string::npos) number += ".0";
        out << number;
    } else if (const auto* boolean = node.as_boolean()) {
        out << (boolean->get() ? "true" : "false");
    } else {
        node.visit([&out](const auto& value) { out << value; });  // a date or a time
    }
    return printable(out.str());
}

std::string where(std::string_view source, const toml::node* node) {
    std::string text(source);
    if (node != nullptr && node->source().begin.line > 0) {
        text += ":" + std::to_string(node->source().begin.line);
    }
    return text + ": ";
}

TableReader::TableReader(const toml::table& table, std::string source, std::string path, int index,
                         std::string doc)
    : table_(table),
      source_(std::move(source)),
      path_(std::move(path)),
      index_(index),
      doc_(std::move(doc)) {}

TableReader TableReader::nested(const toml::table& table, std::string_view key, int index) const {
    return TableReader(table, source_, path(key), index, doc_);
}

namespace {

std::optional<double> as_number(const toml::node& node) {
    if (const auto* floating = node.as_floating_point()) return floating->get();
    if (const auto* integer = node.as_integer()) return static_cast<double>(integer->get());
    return std::nullopt;
}

}  // namespace

double TableReader::read(const Number& field) {
    const std::optional<double> value = read_optional(field);  // the default when absent
    if (value) return *value;
    fail(field.key, "is missing: required, allowed " + field.range.describe());
}

std::optional<double> TableReader::read_optional(const Number& field) {
    const toml::node* node = get(field.key);
    if (node == nullptr) return field.default_value;
    return number(*node, field.key, field.range);
}

double TableReader::read_periods(std::string_view key, double max_periods, double rate_hz) {
    const std::string unit = "s: " + format_number(max_periods) +
                             " periods at [servo] rate_hz = " + format_number(rate_hz);
    const Range range{.lo = 0.0, .hi = max_periods / rate_hz, .hi_open = true, .unit = unit};
    const toml::node* node = get(key);
    if (node == nullptr) return 0.0;
    const std::optional<double> value = as_number(*node);
    if (!value) fail(key, "is not a number", range.describe());
    if (!(std::isfinite(*value) && *value >= 0.0 && *value * rate_hz < max_periods)) {
        fail(key, "is out of range", range.describe());
    }
    return *value;
}

double TableReader::number(const toml::node& node, std::string_view key, const Range& range) const {
    const std::optional<double> value = as_number(node);
    if (!value || !range.contains(*value)) {
        throw ConfigError(printable(prefix(&node) + name(key) + " = " + format_value(node) +
                                    (value ? " is out of range" : " is not a number") +
                                    ": allowed " + range.describe()));
    }
    return *value;
}

std::int64_t TableReader::read(const Integer& field) {
    const std::optional<std::int64_t> value = read_optional(field);
    if (value) return *value;
    fail(field.key, "is missing: required, allowed " + field.describe());
}

std::optional<std::int64_t> TableReader::read_optional(const Integer& field) {
    const toml::node* node = get(field.key);
    if (node == nullptr) return field.default_value;
    const auto* integer = node->as_integer();
    if (integer == nullptr) fail(field.key, "is not an integer", field.describe());
    if (!field.contains(integer->get())) fail(field.key, "is out of range", field.describe());
    return integer->get();
}

bool TableReader::read(const Flag& field) {
    const toml::node* node = get(field.key);
    if (node == nullptr) return field.default_value;
    const auto* boolean = node->as_boolean();
    if (boolean == nullptr) fail(field.key, "is not a boolean", "true or false");
    return boolean->get();
}

std::string TableReader::read(const Text& field) {
    std::optional<std::string> value = read_optional(field);
    if (value) return std::move(*value);
    fail(field.key, "is missing: required, allowed " + field.describe());
}

std::optional<std::string> TableReader::read_optional(const Text& field) {
    const toml::node* node = get(field.key);
    if (node == nullptr) {
        if (field.default_value) return std::string(*field.default_value);
        return std::nullopt;
    }
    const auto* text = node->as_string();
    if (text == nullptr) fail(field.key, "is not a string", field.describe());
    if (text->get().empty() && !field.allow_empty) fail(field.key, "is empty", field.describe());
    if (field.max_bytes != 0 && text->get().size() > field.max_bytes) {
        fail(field.key, "is too long (" + std::to_string(text->get().size()) + " bytes)",
             field.describe());
    }
    // No name, path or label needs one, and each is shown in the journal and on terminals.
    if (const std::size_t at = find_control(text->get()); at != std::string::npos) {
        fail(field.key, "holds a control character at byte " + std::to_string(at + 1),
             field.describe() + " without control characters");
    }
    return text->get();
}

void TableReader::mark(std::string_view key, Kind kind) {
    for (auto& [known, known_kind] : known_) {
        if (known == key) {
            known_kind = kind;
            return;
        }
    }
    known_.emplace_back(std::string(key), kind);
}

const toml::node* TableReader::get(std::string_view key) {
    mark(key, Kind::key);
    return table_.get(key);
}

bool TableReader::has(std::string_view key) const { return table_.contains(key); }

const toml::table* TableReader::subtable(std::string_view key) {
    mark(key, Kind::table);
    const toml::node* node = table_.get(key);
    if (node == nullptr) return nullptr;
    if (const auto* table = node->as_table()) return table;
    fail(key, "is not a table", "a table [" + path(key) + "]");
}

const toml::array* TableReader::array_of_tables(std::string_view key) {
    mark(key, Kind::array_of_tables);
    const toml::node* node = table_.get(key);
    if (node == nullptr) return nullptr;
    const auto* array = node->as_array();
    if (array == nullptr || !array->is_array_of_tables()) {
        fail(key, "is not an array of tables",
             "[[" + path(key) + "]] tables, one for each " + std::string(key));
    }
    return array;
}

std::string TableReader::prefix(const toml::node* node) const { return where(source_, node); }

std::string TableReader::name() const {
    if (path_.empty()) return "";
    if (index_ > 0) return "[[" + path_ + "]] #" + std::to_string(index_);
    return "[" + path_ + "]";
}

std::string TableReader::name(std::string_view key) const {
    const std::string table = name();
    return table.empty() ? std::string(key) : table + " " + std::string(key);
}

std::string TableReader::path(std::string_view key) const {
    return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

void TableReader::fail(std::string_view key, std::string_view problem,
                       std::string_view allowed) const {
    const toml::node* node = table_.get(key);
    std::string text = prefix(node != nullptr ? node : &table_) + name(key);
    if (node != nullptr) text += " = " + format_value(*node);
    text += " ";
    text += problem;
    text += ": allowed ";
    text += allowed;
    throw ConfigError(printable(text));
}

void TableReader::fail(std::string_view key, std::string_view message) const {
    const toml::node* node = table_.get(key);
    throw ConfigError(printable(prefix(node != nullptr ? node : &table_) + name(key) + " " +
                                std::string(message)));
}

void TableReader::fail_table(std::string_view message) const {
    const std::string table = name();
    throw ConfigError(
        printable(prefix(&table_) + table + (table.empty() ? "" : " ") + std::string(message)));
}

void TableReader::finish() const {
    for (const auto& [key, node] : table_) {
        const std::string_view unread = key.str();
        const bool known = std::any_of(known_.begin(), known_.end(),
                                       [unread](const auto& k) { return k.first == unread; });
        if (known) continue;
        std::string allowed;
        for (const auto& [known_key, kind] : known_) {
            allowed += allowed.empty() ? "" : ", ";
            allowed += kind == Kind::table             ? "[" + path(known_key) + "]"
                       : kind == Kind::array_of_tables ? "[[" + path(known_key) + "]]"
                                                       : known_key;
        }
        if (allowed.empty()) allowed = "no keys";
        if (!doc_.empty()) allowed += " (" + doc_ + ")";
        if (node.is_table()) {
            throw ConfigError(printable(prefix(&node) + "[" + path(key.str()) +
                                        "] is not a known table: allowed " + allowed));
        }
        if (const auto* array = node.as_array(); array != nullptr && array->is_array_of_tables()) {
            throw ConfigError(printable(prefix(&node) + "[[" + path(key.str()) +
                                        "]] is not a known table: allowed " + allowed));
        }
        throw ConfigError(printable(prefix(&node) + name(key.str()) + " = " + format_value(node) +
                                    " is not a known key: allowed " + allowed));
    }
}

void TableReader::only(std::initializer_list<std::string_view> keys) {
    for (const std::string_view key : keys) {
        const toml::node* node = table_.get(key);
        const bool is_array_of_tables = node != nullptr && node->is_array_of_tables();
        mark(key, node != nullptr && node->is_table() ? Kind::table
                  : is_array_of_tables                ? Kind::array_of_tables
                                                      : Kind::key);
    }
    finish();
}

toml::table parse_document(std::string_view text, const std::string& source) {
    if (const std::string e = toml_shape_error(text, source); !e.empty())
        throw ConfigError(printable(e));
    try {
        return toml::parse(text, source);
    } catch (const toml::parse_error& error) {
        throw ConfigError(printable(source + ":" + std::to_string(error.source().begin.line) + ":" +
                                    std::to_string(error.source().begin.column) +
                                    ": TOML syntax error: " + std::string(error.description())));
    }
}

const toml::table* table_at(const toml::table& document, std::string_view path,
                            const std::string& source) {
    const toml::table* table = &document;
    std::string walked;
    while (!path.empty()) {
        const std::size_t dot = path.find('.');
        const std::string_view part = path.substr(0, dot);
        walked += (walked.empty() ? "" : ".") + std::string(part);
        const toml::node* node = table->get(part);
        if (node == nullptr) return nullptr;
        table = node->as_table();
        if (table == nullptr) {
            throw ConfigError(printable(where(source, node) + walked + " = " + format_value(*node) +
                                        " is not a table: allowed a table [" + walked + "]"));
        }
        path = dot == std::string_view::npos ? std::string_view() : path.substr(dot + 1);
    }
    return table;
}

}  // namespace hapticd::input
