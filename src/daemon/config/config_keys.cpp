// The reference of the config's keys, from the field lists (config.hpp).
#include <string>
#include <vector>

#include "hapticd/daemon/config.hpp"

namespace hapticd::daemon {

std::string config_keys_markdown() {
    std::vector<input::FieldRow> rows;
    const auto add = [&rows](const auto& list) {
        for (input::FieldRow& row : input::rows(list)) rows.push_back(std::move(row));
    };
    add(kServoFields);
    add(kDeviceFields);
    add(kDeviceModelFields);
    add(kCouplingFields);
    add(kSceneFields);
    add(kSafetyFields);
    add(kIdentifyFields);
    std::string text = "| key | allowed | default | meaning |\n|---|---|---|---|\n";
    for (const input::FieldRow& row : rows) {
        text += "| `[" + row.table + "] " + row.key + "` | " + row.allowed + " | " +
                row.default_value + " | " + row.help + " |\n";
    }
    return text;
}

}  // namespace hapticd::daemon
