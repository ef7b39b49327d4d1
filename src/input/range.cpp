#include "hapticd/input/range.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "hapticd/input/fields.hpp"

namespace hapticd::input {

bool Range::contains(double value) const noexcept {
    if (!std::isfinite(value)) return false;
    const bool above = lo_open ? value > lo : value >= lo;
    const bool below = hi_open ? value < hi : value <= hi;
    return above && below;
}

std::string Range::describe() const {
    std::string text;
    if (std::isfinite(lo)) text = (lo_open ? "> " : ">= ") + format_number(lo);
    if (std::isfinite(hi)) {
        text +=
            (text.empty() ? "" : " and ") + std::string(hi_open ? "< " : "<= ") + format_number(hi);
    }
    if (text.empty()) text = "any finite number";
    if (!unit.empty()) text += " (" + std::string(unit) + ")";
    return text;
}

std::string Integer::describe() const {
    std::string text = std::to_string(lo) + ".." + std::to_string(hi);
    if (!unit.empty()) text += " (" + std::string(unit) + ")";
    return text;
}

std::string format_number(double value) {
    std::ostringstream out;
    out << value;
    return out.str();
}

std::string exact_number(double value) {
    std::array<char, 64> buffer{};
    const auto [end, error] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
    return error == std::errc() ? std::string(buffer.data(), end) : format_number(value);
}

std::string format_quantity(double value, std::string_view unit) {
    std::string text = format_number(value);
    if (!unit.empty()) text += " " + std::string(unit);
    return text;
}

std::string out_of_range(std::string_view name, std::string_view value, std::string_view allowed) {
    std::string text(name);
    text += " = ";
    text += value;
    text += " is out of range: allowed ";
    text += allowed;
    return text;
}

std::string out_of_range(std::string_view name, double value, std::string_view allowed) {
    return out_of_range(name, format_number(value), allowed);
}

std::string out_of_range(std::string_view name, double value, const Range& range) {
    return out_of_range(name, format_number(value), range.describe());
}

bool invalid(std::string* error, std::string message) {
    if (error != nullptr) *error = std::move(message);
    return false;
}

void reject_out_of_range(std::string_view name, std::string_view value, std::string_view allowed) {
    throw std::invalid_argument(out_of_range(name, value, allowed));
}

void reject_out_of_range(std::string_view name, double value, std::string_view allowed) {
    throw std::invalid_argument(out_of_range(name, value, allowed));
}

void reject_out_of_range(std::string_view name, double value, const Range& range) {
    throw std::invalid_argument(out_of_range(name, value, range));
}

}  // namespace hapticd::input
