// The tune layer's serialisers (result_json.hpp): each field is the result's own value, and a
// number that is not finite (an infinite m_c or b_c) is JSON null, not a string or a NaN.
#include "hapticd/tune/result_json.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "hapticd/tune/stability_check.hpp"

namespace hapticd::tune {
namespace {

const theory::DeviceModel kDevice{0.25, 0.5};

TEST(ResultJson, ImpedanceSizingCarriesTheSizedCouplingAndItsSolve) {
    ImpedanceSizingRequest request;
    request.device = kDevice;
    request.rate_hz = 1000.0;
    request.coupling_damping_n_s_per_m = 0.2;
    const ImpedanceSizing sizing = size_impedance_coupling(request);
    const nlohmann::ordered_json json = sizing;
    EXPECT_DOUBLE_EQ(json.at("stiffness").get<double>(), sizing.coupling.stiffness_n_per_m);
    EXPECT_GT(json.at("stiffness").get<double>(), 0.0);
    EXPECT_DOUBLE_EQ(json.at("damping").get<double>(), 0.2);
    EXPECT_DOUBLE_EQ(json.at("binding_frequency_hz").get<double>(), sizing.binding_frequency_hz);
    EXPECT_DOUBLE_EQ(json.at("verified_worst_margin").get<double>(), sizing.verified_worst_margin);
    EXPECT_EQ(json.at("solver").at("method").get<std::string>(), sizing.report.method);
    EXPECT_EQ(json.at("solver").at("verify_points").get<int>(), sizing.report.verify_points);
    EXPECT_GT(json.at("solver").at("verify_points").get<int>(), 0);
}

TEST(ResultJson, AnInfiniteDamperIsNull) {
    AdmittanceSizing sizing;
    sizing.coupling.mass_kg = 0.05;
    sizing.coupling.damping_n_s_per_m = std::numeric_limits<double>::infinity();
    const nlohmann::ordered_json json = sizing;
    EXPECT_TRUE(json.at("damping").is_null());
    EXPECT_DOUBLE_EQ(json.at("coupling_mass").get<double>(), 0.05);

    PassiveAdmittanceSizing passive;
    passive.coupling.mass_kg = std::numeric_limits<double>::infinity();
    passive.coupling.damping_n_s_per_m = 3.0;
    const nlohmann::ordered_json passive_json = passive;
    EXPECT_TRUE(passive_json.at("coupling_mass").is_null());
    EXPECT_DOUBLE_EQ(passive_json.at("damping").get<double>(), 3.0);
    EXPECT_TRUE(passive_json.at("exact_check").contains("worst_spectral_radius"));
}

TEST(ResultJson, DeviceAndForceFilterUseThePhysicalNames) {
    const nlohmann::ordered_json device = kDevice;
    EXPECT_EQ(device, (nlohmann::ordered_json{{"mass", 0.25}, {"damping", 0.5}}));
    const theory::ForceSensorFilter filter{100.0, 0.5, 2};
    const nlohmann::ordered_json json = filter;
    EXPECT_DOUBLE_EQ(json.at("cutoff_hz").get<double>(), 100.0);
    EXPECT_DOUBLE_EQ(json.at("damping_ratio").get<double>(), 0.5);
    EXPECT_EQ(json.at("order").get<int>(), 2);
    EXPECT_EQ(json.at("description").get<std::string>(), filter.describe());
}

TEST(ResultJson, AVerdictCarriesItsModelItsClassAndTheLineHapticdLogs) {
    StabilityDesign design;
    design.device = kDevice;
    design.coupling = {500.0, 0.0};
    design.rate_hz = 1000.0;
    const StabilityVerdict verdict = check_stability(design);
    const nlohmann::ordered_json json = verdict;
    EXPECT_EQ(json.at("unconditionally_stable").get<bool>(), verdict.passed);
    EXPECT_EQ(json.at("model").get<std::string>(), "passive");
    EXPECT_DOUBLE_EQ(json.at("worst_margin").get<double>(), verdict.worst_margin);
    EXPECT_EQ(json.at("holds_for").get<std::string>(), verdict.holds_for);
    EXPECT_EQ(json.at("verdict").get<std::string>(), verdict.describe());
    EXPECT_FALSE(json.contains("worst_operator"));  // only the exact model names one

    StabilityVerdict exact = verdict;
    exact.model = StabilityModel::exact;
    exact.exact = ExactCheck{};
    exact.exact->worst_operator = OperatorModel::heavy_hand(1.0, 2.0);
    exact.exact->worst_environment = EnvironmentModel::rigid_wall();
    exact.exact->worst_spectral_radius = 0.999;
    exact.exact->cases_checked = 42;
    const nlohmann::ordered_json exact_json = exact;
    EXPECT_EQ(exact_json.at("model").get<std::string>(), "exact");
    EXPECT_EQ(exact_json.at("worst_operator").get<std::string>(),
              exact.exact->worst_operator.describe());
    EXPECT_EQ(exact_json.at("worst_environment").get<std::string>(),
              exact.exact->worst_environment.describe());
    EXPECT_DOUBLE_EQ(exact_json.at("worst_spectral_radius").get<double>(), 0.999);
    EXPECT_EQ(exact_json.at("cases_checked").get<int>(), 42);
}

}  // namespace
}  // namespace hapticd::tune
