#include "hapticd/tune/result_json.hpp"

namespace hapticd::tune {
namespace {

template <typename Check>
nlohmann::ordered_json exact_check_json(const Check& check) {
    return {{"stable", check.stable},
            {"worst_margin", check.worst_margin},
            {"worst_spectral_radius", check.worst_spectral_radius},
            {"worst_frequency_hz", check.worst_frequency_hz},
            {"worst_operator", check.worst_operator.describe()},
            {"worst_environment", check.worst_environment.describe()},
            {"cases_checked", check.cases_checked}};
}

}  // namespace

void to_json(nlohmann::ordered_json& json, const ExactCheck& check) {
    json = exact_check_json(check);
}

void to_json(nlohmann::ordered_json& json, const AdmittanceExactCheck& check) {
    json = exact_check_json(check);
}

}  // namespace hapticd::tune
