#include "scene_fields.hpp"

#include <cmath>
#include <glm/geometric.hpp>

namespace hapticd::env::detail {

std::string format_vector(const Vec3& v, int axes) {
    std::string text = "[";
    for (int i = 0; i < axes; ++i) text += (i ? ", " : "") + input::format_number(v[i]);
    return text + "]";
}

Vec3 read_vector(TableReader& reader, std::string_view key, int axes, bool direction,
                 std::optional<Vec3> default_value) {
    const std::string what = "an array of " + std::to_string(axes) + " numbers (the scene's axes)";
    const toml::node* node = reader.get(key);
    if (node == nullptr) {
        if (default_value) return *default_value;
        reader.fail(key, "is missing: required, allowed " + what);
    }
    const auto* array = node->as_array();
    if (array == nullptr) reader.fail(key, "is not an array", what);
    if (static_cast<int>(array->size()) != axes) {
        reader.fail(key, "has " + std::to_string(array->size()) + " components",
                    "exactly " + std::to_string(axes) + " (the scene's axes)");
    }
    Vec3 out(0.0);
    for (int i = 0; i < axes; ++i) {
        const toml::node& item = *array->get(static_cast<std::size_t>(i));
        if (!item.is_number()) {
            reader.fail(key, "has a non-number component " + input::format_value(item), what);
        }
        const double value = *item.value<double>();
        if (!direction && !kCoordinate.contains(value)) {
            reader.fail(key, "is out of range",
                        "components from " + input::format_number(-kMaxLength_m) + " to " +
                            input::format_number(kMaxLength_m) + " m");
        }
        if (direction && !std::isfinite(value)) {
            reader.fail(key, "is out of range", "finite components");
        }
        out[i] = value;
    }
    if (direction) {
        const double length = glm::length(out);
        if (!(length > 0.0) || !std::isfinite(length)) {
            reader.fail(key, "is out of range", "a non-zero direction");
        }
        out /= length;
    }
    return out;
}

}  // namespace hapticd::env::detail
