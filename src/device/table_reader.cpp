// The configuration-table reader shared by the device plugins (table_reader.hpp).
#include "hapticd/device/table_reader.hpp"

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "hapticd/input/text_input.hpp"

namespace hapticd::device {

bool Range::contains(double x) const {
    return std::isfinite(x) && (lo_open ? x > lo : x >= lo) && x <= hi;
}

std::string Range::describe() const {
    std::ostringstream s;
    s << "a number " << (lo_open ? "> " : ">= ") << lo;
    if (hi < kInf) s << " and <= " << hi;
    if (*unit != '\0') s << " (" << unit << ")";
    return s.str();
}

std::string printed(const toml::node& node) {
    std::ostringstream s;
    if (const auto* str = node.as_string()) {
        s << '"' << str->get() << '"';
    } else {
        node.visit([&s](const auto& value) { s << value; });
    }
    std::string text = s.str();
    for (char& c : text) {
        if (c == '\n') c = ' ';
    }
    return text;
}

TableReader::TableReader(const toml::table& table, std::string prefix, const std::string& source,
                         std::string doc)
    : table_(table), prefix_(std::move(prefix)), source_(source), doc_(std::move(doc)) {}

void TableReader::fail(std::string_view key, const std::string& what) const {
    throw std::runtime_error(source_ + ": " + prefix_ + std::string(key) + " " + what);
}

void TableReader::fail_value(std::string_view key, const toml::node& node,
                             const std::string& allowed) const {
    fail(key, "= " + printed(node) + " is not allowed: must be " + allowed);
}

const toml::node* TableReader::get(std::string_view key) {
    used_.insert(std::string(key));
    return table_.get(key);
}

double TableReader::number(const toml::node& node, std::string_view key, const Range& range) const {
    std::optional<double> value;
    if (const auto* f = node.as_floating_point()) value = f->get();
    if (const auto* i = node.as_integer()) value = static_cast<double>(i->get());
    if (!value || !range.contains(*value)) fail_value(key, node, range.describe());
    return *value;
}

double TableReader::number(std::string_view key, double fallback, const Range& range) {
    const toml::node* node = get(key);
    return node == nullptr ? fallback : number(*node, key, range);
}

std::int64_t TableReader::integer(std::string_view key, std::int64_t fallback, std::int64_t lo,
                                  std::int64_t hi) {
    const toml::node* node = get(key);
    if (node == nullptr) return fallback;
    const auto* i = node->as_integer();
    if (i == nullptr || i->get() < lo || i->get() > hi) {
        fail_value(key, *node,
                   "an integer from " + std::to_string(lo) + " to " + std::to_string(hi));
    }
    return i->get();
}

bool TableReader::boolean(std::string_view key, bool fallback) {
    const toml::node* node = get(key);
    if (node == nullptr) return fallback;
    const auto* b = node->as_boolean();
    if (b == nullptr) fail_value(key, *node, "true or false");
    return b->get();
}

std::string TableReader::string(std::string_view key, std::string fallback) {
    const toml::node* node = get(key);
    if (node == nullptr) return fallback;
    const auto* s = node->as_string();
    if (s == nullptr) fail_value(key, *node, "a string");
    return s->get();
}

std::string TableReader::choice(std::string_view key, std::string fallback,
                                std::initializer_list<const char*> allowed) {
    const toml::node* node = get(key);
    if (node == nullptr) return fallback;
    std::string options;
    for (const char* a : allowed) {
        options += options.empty() ? "" : " | ";
        options += std::string("\"") + a + "\"";
        if (const auto* s = node->as_string(); s != nullptr && s->get() == a) return a;
    }
    fail_value(key, *node, "one of " + options);
}

std::vector<double> TableReader::times(std::string_view key) {
    const toml::node* node = get(key);
    std::vector<double> values;
    if (node == nullptr) return values;
    const auto* array = node->as_array();
    if (array == nullptr) fail_value(key, *node, "an array of times >= 0 (s)");
    for (const toml::node& element : *array) {
        values.push_back(number(element, key, Range{0.0, kInf, false, "s"}));
    }
    return values;
}

const toml::table* TableReader::subtable(std::string_view key) {
    const toml::node* node = get(key);
    if (node == nullptr) return nullptr;
    if (const auto* t = node->as_table()) return t;
    fail_value(key, *node, "a table");
}

void TableReader::finish() const {
    for (const auto& [key, node] : table_) {
        if (!used_.contains(std::string(key.str()))) {
            fail(key.str(), "is not a known key (= " + printed(node) + "); see " + doc_);
        }
    }
}

toml::table parse_plugin_table(const std::string& toml_text, const std::string& source) {
    if (const std::string e = input::toml_shape_error(toml_text, source); !e.empty()) {
        throw std::runtime_error(e);
    }
    try {
        return toml::parse(toml_text, source);
    } catch (const toml::parse_error& e) {
        std::ostringstream s;
        s << source << ": the device table is not valid TOML: " << e.description();
        throw std::runtime_error(s.str());
    }
}

}  // namespace hapticd::device
