#include "scene_fields.hpp"

#include <cmath>
#include <glm/geometric.hpp>
#include <sstream>

namespace hapticd::env::detail {

bool Range::contains(double value) const noexcept {
    if (!std::isfinite(value)) return false;
    const bool above = lower_inclusive ? value >= lower : value > lower;
    const bool below = upper_inclusive ? value <= upper : value < upper;
    return above && below;
}

std::string Range::describe() const {
    std::string text = (lower_inclusive ? ">= " : "> ") + format_number(lower);
    if (std::isfinite(upper))
        text += (upper_inclusive ? " and <= " : " and < ") + format_number(upper);
    if (!unit.empty()) text += " " + std::string(unit);
    return text;
}

std::string format_number(double value) {
    std::ostringstream out;
    out << value;
    return out.str();
}

std::string format_node(const toml::node& node) {
    std::ostringstream out;
    if (const auto* text = node.as_string()) {
        out << '"' << text->get() << '"';
    } else if (const auto* array = node.as_array()) {
        out << '[';
        for (std::size_t i = 0; i < array->size(); ++i) {
            out << (i ? ", " : "") << format_node(*array->get(i));
        }
        out << ']';
    } else if (node.is_table()) {
        out << "{...}";
    } else if (const auto* integer = node.as_integer()) {
        out << integer->get();
    } else if (const auto* floating = node.as_floating_point()) {
        out << floating->get();
    } else if (const auto* boolean = node.as_boolean()) {
        out << (boolean->get() ? "true" : "false");
    } else {
        out << "<" << node.type() << ">";  // a date or time
    }
    return out.str();
}

std::string format_vector(const Vec3& v, int axes) {
    std::string text = "[";
    for (int i = 0; i < axes; ++i) text += (i ? ", " : "") + format_number(v[i]);
    return text + "]";
}

std::string where(const std::string& source, const toml::node* node) {
    if (node != nullptr && node->source().begin.line > 0) {
        return source + ":" + std::to_string(node->source().begin.line) + ": ";
    }
    return source + ": ";
}

TableReader::TableReader(const toml::table& table, std::string source, std::string context,
                         int axes, std::initializer_list<std::string_view> allowed_keys)
    : table_(table), source_(std::move(source)), context_(std::move(context)), axes_(axes) {
    for (const auto& [key, node] : table_) {
        bool known = false;
        for (const auto allowed : allowed_keys) known = known || key.str() == allowed;
        if (known) continue;
        std::string allowed_list;
        for (const auto allowed : allowed_keys) {
            allowed_list += (allowed_list.empty() ? "" : ", ") + std::string(allowed);
        }
        throw SceneError(where(source_, &node) + context_ + " has an unknown key '" +
                         std::string(key.str()) + "': allowed keys are " + allowed_list);
    }
}

const toml::node* TableReader::find(std::string_view key) const { return table_.get(key); }

void TableReader::fail(std::string_view key, const std::string& message) const {
    const toml::node* node = table_.get(key);
    throw SceneError(where(source_, node != nullptr ? node : &table_) + context_ + " " +
                     std::string(key) + message);
}

double TableReader::number(std::string_view key, const Range& range,
                           std::optional<double> default_value) {
    const toml::node* node = find(key);
    if (node == nullptr) {
        if (default_value) return *default_value;
        fail(key, " is missing: required, allowed " + range.describe());
    }
    std::optional<double> value;
    if (const auto* integer = node->as_integer()) value = static_cast<double>(integer->get());
    if (const auto* floating = node->as_floating_point()) value = floating->get();
    if (!value)
        fail(key, " = " + format_node(*node) + " is not a number: allowed " + range.describe());
    if (!range.contains(*value)) {
        fail(key, " = " + format_node(*node) + " is out of range: allowed " + range.describe());
    }
    return *value;
}

Vec3 TableReader::vector(std::string_view key, bool direction, std::optional<Vec3> default_value) {
    const toml::node* node = find(key);
    if (node == nullptr) {
        if (default_value) return *default_value;
        fail(key, std::string(" is missing: required, allowed an array of ") +
                      std::to_string(axes_) + " numbers (the scene's axes)");
    }
    const auto* array = node->as_array();
    const std::string shown = format_node(*node);
    if (array == nullptr) {
        fail(key, " = " + shown + " is not an array: allowed an array of " + std::to_string(axes_) +
                      " numbers (the scene's axes)");
    }
    if (static_cast<int>(array->size()) != axes_) {
        fail(key, " = " + shown + " has " + std::to_string(array->size()) +
                      " components: allowed exactly " + std::to_string(axes_) +
                      " (the scene's axes)");
    }
    const Range coordinate{-kMaxLength_m, true, kMaxLength_m, true, "m"};
    Vec3 out(0.0);
    for (int i = 0; i < axes_; ++i) {
        const toml::node& item = *array->get(static_cast<std::size_t>(i));
        std::optional<double> value;
        if (const auto* integer = item.as_integer()) value = static_cast<double>(integer->get());
        if (const auto* floating = item.as_floating_point()) value = floating->get();
        if (!value) fail(key, " = " + shown + " has a non-number component " + format_node(item));
        if (!direction && !coordinate.contains(*value)) {
            fail(key, " = " + shown + " is out of range: allowed components from " +
                          format_number(-kMaxLength_m) + " to " + format_number(kMaxLength_m) +
                          " m");
        }
        if (direction && !std::isfinite(*value)) {
            fail(key, " = " + shown + " is out of range: allowed finite components");
        }
        out[i] = *value;
    }
    if (direction) {
        const double length = glm::length(out);
        if (!(length > 0.0) || !std::isfinite(length)) {
            fail(key, " = " + shown + " is out of range: allowed a non-zero direction");
        }
        out /= length;
    }
    return out;
}

bool TableReader::boolean(std::string_view key, bool default_value) {
    const toml::node* node = find(key);
    if (node == nullptr) return default_value;
    const auto* value = node->as_boolean();
    if (value == nullptr)
        fail(key, " = " + format_node(*node) + " is not a boolean: allowed true or false");
    return value->get();
}

std::string TableReader::string(std::string_view key, std::optional<std::string> default_value) {
    const toml::node* node = find(key);
    if (node == nullptr) {
        if (default_value) return *default_value;
        fail(key, " is missing: required, allowed a string");
    }
    const auto* value = node->as_string();
    if (value == nullptr) fail(key, " = " + format_node(*node) + " is not a string");
    return value->get();
}

}  // namespace hapticd::env::detail
