// haptic-tune plot and zwidth, end to end through the real executable: the plotted numbers
// against closed forms computed here, the image files, and the input errors.
// Every suite name starts with "plot" so that `ctest -R plot` runs them all.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <ostream>
#include <string>
#include <vector>

#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd {
namespace {

using hapticd::testing::run_command;
using nlohmann::json;
using Complex = std::complex<double>;
constexpr double kPi = std::numbers::pi;
constexpr Complex kJ{0.0, 1.0};

// The device and design every test uses unless it says otherwise.
constexpr double kMass = 0.1;     // kg
constexpr double kDamping = 2.0;  // N s/m
constexpr double kRate = 1000.0;  // Hz
constexpr double kPeriod = 1.0 / kRate;
constexpr double kStiffness = 3000.0;     // N/m
constexpr double kCouplingDamping = 0.5;  // N s/m
const std::string kDevice = "--mass 0.1 --damping 2 --rate 1000";
const std::string kDesign = kDevice + " --stiffness 3000 --coupling-damping 0.5";

std::string tune(const std::string& args) { return std::string(HAPTIC_TUNE) + " " + args; }

json run_json(const std::string& args) {
    const auto result = run_command(tune(args));
    EXPECT_EQ(result.exit_code, 0) << args << "\n" << result.err;
    return json::parse(result.out);
}

using hapticd::testing::read_file;
using hapticd::testing::ScratchDir;

double theta_at(double frequency_hz) { return 2.0 * kPi * frequency_hz * kPeriod; }

// ---- closed forms, written out here independently of the theory layer ----------------

/// Right side of (21) for (13): ∠ZOH = -θ/2, |ZOH| = cos(θ/2).
double paper_bound(double theta) {
    return (1.0 - std::cos(theta / 2.0)) * std::cos(theta / 2.0) / (2.0 * kDamping);
}

/// Right side of (21) for the encoder model: ∠H = -θ, |H| = (sin(θ/2)/(θ/2))².
double encoder_bound(double theta) {
    const double sinc = std::sin(theta / 2.0) / (theta / 2.0);
    return (1.0 - std::cos(theta)) * sinc * sinc / (2.0 * kDamping);
}

/// (16): Z_c = b_c + k_c T z/(z - 1).
Complex coupling_impedance(double theta, double k = kStiffness, double bc = kCouplingDamping) {
    const Complex z = std::polar(1.0, theta);
    return bc + k * kPeriod * z / (z - 1.0);
}

/// (12) Tustin device impedance, and the hold term (13).
Complex tustin_device(double theta) {
    const Complex z = std::polar(1.0, theta);
    return kMass * (2.0 / kPeriod) * (z - 1.0) / (z + 1.0) + kDamping;
}
Complex paper_hold(double theta) {
    const Complex z = std::polar(1.0, theta);
    return 0.5 * (z + 1.0) / z;
}

/// The encoder model: m jω + b, and e^{-jθ} (sin(θ/2)/(θ/2))².
Complex encoder_device(double theta) { return kDamping + kJ * kMass * (theta / kPeriod); }
Complex encoder_hold(double theta) {
    const double sinc = std::sin(theta / 2.0) / (theta / 2.0);
    return std::polar(sinc * sinc, -theta);
}

std::vector<double> doubles(const json& array) { return array.get<std::vector<double>>(); }

// ---- plot -------------------------------------------------------------------------

TEST(plotCommand, JsonBoundsAreTheRightSideOf21InClosedForm) {
    const json j = run_json("plot " + kDesign + " --points 120 --json");
    const std::vector<double> f = doubles(j.at("frequency_hz"));
    ASSERT_EQ(f.size(), 120u);
    EXPECT_DOUBLE_EQ(f.front(), 0.1);
    EXPECT_DOUBLE_EQ(f.back(), 500.0);  // Nyquist
    for (std::size_t i = 1; i < f.size(); ++i) EXPECT_GT(f[i], f[i - 1]);

    const std::vector<double> paper = doubles(j.at("models").at("paper").at("bound"));
    const std::vector<double> encoder = doubles(j.at("models").at("encoder").at("bound"));
    ASSERT_EQ(paper.size(), f.size());
    ASSERT_EQ(encoder.size(), f.size());
    for (const std::size_t i : {std::size_t{40}, std::size_t{90}, std::size_t{110}}) {
        const double theta = theta_at(f[i]);
        EXPECT_NEAR(paper[i], paper_bound(theta), 1e-10 * paper_bound(theta)) << "f = " << f[i];
        EXPECT_NEAR(encoder[i], encoder_bound(theta), 1e-10 * encoder_bound(theta))
            << "f = " << f[i];
    }
    // At Nyquist the paper's hold term has |ZOH| = cos(π/2) = 0: the bound vanishes.
    EXPECT_NEAR(paper.back(), 0.0, 1e-12);
    EXPECT_NEAR(encoder.back(), encoder_bound(kPi), 1e-12);
}

TEST(plotCommand, JsonConductanceIsRealPartOfOneOverTheCoupling) {
    const json j = run_json("plot " + kDesign + " --points 120 --json");
    const std::vector<double> f = doubles(j.at("frequency_hz"));
    const std::vector<double> g = doubles(j.at("coupling_conductance"));
    ASSERT_EQ(g.size(), f.size());
    for (const std::size_t i :
         {std::size_t{0}, std::size_t{60}, std::size_t{100}, std::size_t{119}}) {
        const double expected = std::real(1.0 / coupling_impedance(theta_at(f[i])));
        EXPECT_NEAR(g[i], expected, 1e-9 * expected) << "f = " << f[i];
    }
    // At Nyquist z/(z-1) = 1/2, so Z_c = b_c + k_c T/2 is real.
    EXPECT_NEAR(g.back(), 1.0 / (kCouplingDamping + kStiffness * kPeriod / 2.0), 1e-9);
    const json& design = j.at("design");
    EXPECT_EQ(design.at("stiffness").get<double>(), kStiffness);
    EXPECT_EQ(design.at("damping").get<double>(), kCouplingDamping);
    EXPECT_EQ(design.at("source"), "flags");
}

TEST(plotCommand, WorstMarginPerModelMatchesCheck) {
    for (const std::string& design :
         std::vector<std::string>{kDesign, kDevice + " --stiffness 6000 --coupling-damping 1"}) {
        const json plot = run_json("plot " + design + " --json");
        for (const std::string model : {"paper", "encoder"}) {
            const auto check =
                run_command(tune("check " + design + " --model " + model + " --json"));
            ASSERT_TRUE(check.exit_code == 0 || check.exit_code == 1) << check.err;
            const json c = json::parse(check.out);
            const json& p = plot.at("models").at(model);
            EXPECT_NEAR(p.at("worst_margin").get<double>(), c.at("worst_margin").get<double>(),
                        1e-12)
                << design << " " << model;
            EXPECT_NEAR(p.at("worst_frequency_hz").get<double>(),
                        c.at("worst_frequency_hz").get<double>(), 1e-9);
            EXPECT_EQ(p.at("unconditionally_stable"), c.at("unconditionally_stable"));
            EXPECT_EQ(check.exit_code, c.at("unconditionally_stable").get<bool>() ? 0 : 1);
        }
    }
    // The second design is one the paper model passes and the encoder model does not.
    const json plot = run_json("plot " + kDevice + " --stiffness 6000 --coupling-damping 1 --json");
    EXPECT_TRUE(plot.at("models").at("paper").at("unconditionally_stable").get<bool>());
    EXPECT_FALSE(plot.at("models").at("encoder").at("unconditionally_stable").get<bool>());
    EXPECT_GT(plot.at("models").at("encoder").at("worst_frequency_hz").get<double>(), 0.0);
}

TEST(plotCommand, MarginArrayAndBindingMarkerAreConsistent) {
    const json j = run_json("plot " + kDevice + " --stiffness 6000 --coupling-damping 1 --json");
    const std::vector<double> g = doubles(j.at("coupling_conductance"));
    const json& encoder = j.at("models").at("encoder");
    const std::vector<double> bound = doubles(encoder.at("bound"));
    const json& margin = encoder.at("margin");
    const double worst = encoder.at("worst_margin").get<double>();
    for (std::size_t i = 0; i < g.size(); ++i) {
        ASSERT_TRUE(margin[i].is_number()) << i;  // the encoder bound is > 0 up to Nyquist
        EXPECT_NEAR(margin[i].get<double>(), g[i] / bound[i] - 1.0, 1e-9);
        EXPECT_GE(margin[i].get<double>(), worst - 1e-9);  // the refined minimum is lowest
    }
    const json& marker = encoder.at("marker");
    const double theta = theta_at(marker.at("frequency_hz").get<double>());
    EXPECT_EQ(marker.at("frequency_hz").get<double>(),
              encoder.at("worst_frequency_hz").get<double>());
    EXPECT_NEAR(marker.at("bound").get<double>(), encoder_bound(theta), 1e-12);
    EXPECT_NEAR(marker.at("conductance").get<double>() / marker.at("bound").get<double>() - 1.0,
                worst, 1e-9);
}

TEST(plotCommand, EveryBindingMarkerIsOnTheChartsFrequencyAxis) {
    // The pen display sized with the passive model binds at 0.007 Hz, below the chart's
    // lowest frequency (0.1 Hz): its marker sits at the left edge, not off the axes.
    const json j = run_json("plot " + kDevice + " --json");
    const std::vector<double> f = doubles(j.at("frequency_hz"));
    const json& passive = j.at("models").at("passive");
    EXPECT_GT(passive.at("worst_frequency_hz").get<double>(), 0.0);
    EXPECT_LT(passive.at("worst_frequency_hz").get<double>(), f.front());
    for (const auto& [name, model] : j.at("models").items()) {
        const double marker_hz = model.at("marker").at("frequency_hz").get<double>();
        EXPECT_GE(marker_hz, f.front()) << name;
        EXPECT_LE(marker_hz, f.back()) << name;
    }
    EXPECT_EQ(passive.at("marker").at("frequency_hz").get<double>(), f.front());
}

TEST(plotCommand, ModelsOptionSelectsAndOrdersTheCurves) {
    const json j = run_json("plot " + kDesign + " --models encoder --json --points 20");
    ASSERT_EQ(j.at("models").size(), 1u);
    EXPECT_TRUE(j.at("models").contains("encoder"));
    const json both =
        run_json("plot " + kDesign + " --models encoder,paper,encoder --json --points 20");
    ASSERT_EQ(both.at("models").size(), 2u);
    EXPECT_EQ(both.at("models").begin().key(), "encoder");
}

TEST(plotCommand, WithoutStiffnessItSizesWithThePassiveModel) {
    const json j = run_json("plot " + kDevice + " --coupling-damping 0.5 --json --points 20");
    const json size = run_json("size " + kDevice + " --coupling-damping 0.5 --json");
    const json& design = j.at("design");
    EXPECT_EQ(design.at("source"), "sized");
    EXPECT_EQ(design.at("sizing_model"), "passive");
    EXPECT_NEAR(design.at("stiffness").get<double>(), size.at("stiffness").get<double>(),
                1e-9 * size.at("stiffness").get<double>());
    EXPECT_EQ(design.at("damping").get<double>(), 0.5);
    EXPECT_NE(j.at("title").get<std::string>().find("sized"), std::string::npos);
    // And the text output says so.
    const ScratchDir dir;
    const auto text = run_command(tune("plot " + kDevice + " --out " + dir.file("s.svg")));
    ASSERT_EQ(text.exit_code, 0) << text.err;
    EXPECT_NE(text.out.find("sized from (21) with the passive model"), std::string::npos)
        << text.out;
}

TEST(plotCommand, TakesTheCouplingFromTheConfigFile) {
    const ScratchDir dir;
    const std::string config = dir.file("design.toml");
    std::ofstream(config)
        << "[servo]\nrate_hz = 1000\n\n[device.model]\nmass = 0.1\ndamping = 2\n\n"
           "[coupling]\nstiffness = 2500\ndamping = 0.25\n";
    const json j = run_json("plot --config " + config + " --json --points 20");
    EXPECT_EQ(j.at("design").at("source"), "config");
    EXPECT_EQ(j.at("design").at("stiffness").get<double>(), 2500.0);
    EXPECT_EQ(j.at("design").at("damping").get<double>(), 0.25);
    const json flags = run_json("plot --config " + config + " --stiffness 1000 --json --points 20");
    EXPECT_EQ(flags.at("design").at("source"), "flags");
    EXPECT_EQ(flags.at("design").at("stiffness").get<double>(), 1000.0);
    EXPECT_EQ(flags.at("design").at("damping").get<double>(), 0.25);
}

// ---- image files ------------------------------------------------------------------

std::uint32_t big_endian_u32(const std::string& bytes, std::size_t at) {
    std::uint32_t value = 0;
    for (std::size_t i = 0; i < 4; ++i) {
        value = (value << 8) | static_cast<unsigned char>(bytes[at + i]);
    }
    return value;
}

void expect_png(const std::string& path) {
    const std::string png = read_file(path);
    ASSERT_GE(png.size(), 33u) << path;
    EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    EXPECT_EQ(png.substr(12, 4), "IHDR");    // the first chunk, after its 4-byte length
    EXPECT_GT(big_endian_u32(png, 16), 0u);  // width
    EXPECT_GT(big_endian_u32(png, 20), 0u);  // height
}

TEST(plotFiles, WritesAPng) {
    const ScratchDir dir;
    const std::string out = dir.file("design.png");
    const auto result = run_command(tune("plot " + kDesign + " --out " + out));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    expect_png(out);
    EXPECT_NE(result.out.find(out), std::string::npos) << result.out;
}

TEST(plotFiles, WritesAnSvgAndJsonTogether) {
    const ScratchDir dir;
    const std::string out = dir.file("design.SVG");  // the extension's case does not matter
    const auto result = run_command(tune("plot " + kDesign + " --out " + out + " --json"));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_NE(read_file(out).find("<svg"), std::string::npos);
    // The script printed nothing into it: it parses and is the plot's data.
    const json j = json::parse(result.out);
    EXPECT_EQ(j.at("kind"), "design-procedure");
}

TEST(plotFiles, ZwidthWritesPngAndSvg) {
    const ScratchDir dir;
    const auto png = run_command(tune("zwidth " + kDesign + " --out " + dir.file("z.png")));
    ASSERT_EQ(png.exit_code, 0) << png.err;
    expect_png(dir.file("z.png"));
    const auto svg = run_command(tune("zwidth " + kDesign + " --out " + dir.file("z.svg")));
    ASSERT_EQ(svg.exit_code, 0) << svg.err;
    EXPECT_NE(read_file(dir.file("z.svg")).find("<svg"), std::string::npos);
}

/// The number in `text` right after `key` (e.g. ` width="` in an SVG's root element).
double number_after(const std::string& text, const std::string& key) {
    const std::size_t at = text.find(key);
    if (at == std::string::npos) return std::nan("");
    return std::stod(text.substr(at + key.size()));
}

TEST(plotFiles, WritesAPdfAtTheSizeAsked) {
    const ScratchDir dir;
    const std::string out = dir.file("design.pdf");
    const auto result =
        run_command(tune("plot " + kDesign + " --size 3.5x2.8in --font-size 7 --out " + out));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::string pdf = read_file(out);
    EXPECT_EQ(pdf.substr(0, 5), "%PDF-");
    // The page is the figure, 3.5 x 2.8 in = 252 x 201.6 pt, not cropped.
    EXPECT_NE(pdf.find("/MediaBox [ 0 0 252 201.6 ]"), std::string::npos);
}

TEST(plotFiles, SvgTextIsTextAtTheSizeAndFontAsked) {
    const ScratchDir dir;
    const std::string out = dir.file("z.svg");
    const auto result =
        run_command("SOURCE_DATE_EPOCH=86400 " +
                    tune("zwidth " + kDesign + " --size 90x60mm --font-size 11 --out " + out));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::string svg = read_file(out);
    // 90 x 60 mm = 255.1 x 170.1 pt.
    EXPECT_NEAR(number_after(svg, " width=\""), 90.0 / 25.4 * 72.0, 0.1);
    EXPECT_NEAR(number_after(svg, " height=\""), 60.0 / 25.4 * 72.0, 0.1);
    // Editable text: the labels are <text> elements with their words, not glyph paths.
    EXPECT_NE(svg.find("<text"), std::string::npos);
    EXPECT_NE(svg.find("frequency f (Hz)</text>"), std::string::npos);
    EXPECT_NE(svg.find("font: 11px"), std::string::npos);
    // The caption line (wrapped at the figure's width) names the command, the models, the
    // device and the date (SOURCE_DATE_EPOCH's when it is set).
    for (const char* words : {"haptic-tune zwidth", "the impedance display;", "passive; device",
                              "m = 0.1 kg", "\u00b7 1970-01-02</text>"}) {
        EXPECT_NE(svg.find(words), std::string::npos) << words;
    }
}

// ---- zwidth -----------------------------------------------------------------------

TEST(plotZwidth, TheLoopDelayTurnsTheCouplingsShareAndLeavesZminAlone) {
    // (25) with d periods of delay: Z_max = Z_d + Z_c H e^{-jdθ}; Z_min = Z_d (24).
    const double delay_periods = 1.5;
    const json prompt = run_json("zwidth " + kDesign + " --models encoder --points 40 --json");
    const json delayed =
        run_json("zwidth " + kDesign + " --models encoder --points 40 --delay 0.0015 --json");
    EXPECT_EQ(delayed.at("delay_s").get<double>(), 0.0015);
    const std::vector<double> f = doubles(delayed.at("frequency_hz"));
    const json& model = delayed.at("models").at("encoder");
    EXPECT_EQ(doubles(model.at("zmin_magnitude")),
              doubles(prompt.at("models").at("encoder").at("zmin_magnitude")));
    const std::vector<double> zmax = doubles(model.at("zmax_magnitude"));
    for (const std::size_t i : {std::size_t{5}, std::size_t{25}, std::size_t{38}}) {
        const double theta = theta_at(f[i]);
        const Complex expected =
            encoder_device(theta) + coupling_impedance(theta) * encoder_hold(theta) *
                                        std::polar(1.0, -delay_periods * theta);
        EXPECT_NEAR(zmax[i], std::abs(expected), 1e-9 * zmax[i]) << "f = " << f[i];
    }
    EXPECT_NE(zmax, doubles(prompt.at("models").at("encoder").at("zmax_magnitude")));
}

TEST(plotZwidth, ImpedanceDisplayIs24And25PerModel) {
    const json j = run_json("zwidth " + kDesign + " --points 80 --json");
    EXPECT_EQ(j.at("display"), "impedance");
    EXPECT_EQ(j.at("units"), "N s/m");
    const std::vector<double> f = doubles(j.at("frequency_hz"));
    ASSERT_EQ(f.size(), 80u);
    const json& models = j.at("models");
    const std::vector<double> paper_min = doubles(models.at("paper").at("zmin_magnitude"));
    const std::vector<double> paper_max = doubles(models.at("paper").at("zmax_magnitude"));
    const std::vector<double> enc_min = doubles(models.at("encoder").at("zmin_magnitude"));
    const std::vector<double> enc_max = doubles(models.at("encoder").at("zmax_magnitude"));
    for (const std::size_t i :
         {std::size_t{0}, std::size_t{30}, std::size_t{60}, std::size_t{75}}) {
        const double theta = theta_at(f[i]);
        const double omega = 2.0 * kPi * f[i];
        // (24): Z_min = Z_d. Encoder model: |m jω + b|; paper: |Tustin (12)|.
        EXPECT_NEAR(enc_min[i], std::hypot(kDamping, kMass * omega), 1e-9 * enc_min[i]);
        const Complex tustin = tustin_device(theta);
        EXPECT_NEAR(paper_min[i], std::abs(tustin), 1e-9 * paper_min[i]);
        // (26): Z_max = Z_min + Z_c H, with the complex Z_min.
        const Complex zc = coupling_impedance(theta);
        EXPECT_NEAR(paper_max[i], std::abs(tustin + zc * paper_hold(theta)), 1e-9 * paper_max[i]);
        EXPECT_NEAR(enc_max[i], std::abs(encoder_device(theta) + zc * encoder_hold(theta)),
                    1e-9 * enc_max[i])
            << "f = " << f[i];
    }
    // At low frequency the coupling spring dominates: |Z_max| ≈ k_c/ω, |Z_min| ≈ b.
    const double omega0 = 2.0 * kPi * f.front();
    EXPECT_NEAR(enc_max.front(), kStiffness / omega0, 0.01 * kStiffness / omega0);
    EXPECT_NEAR(enc_min.front(), kDamping, 0.01 * kDamping);
}

TEST(plotZwidth, AdmittanceDisplayIs42And43) {
    const double kp = 20.0;   // N s/m
    const double ki = 500.0;  // N/m
    const double mc = 0.5;    // kg, a pure-mass coupling
    const json j = run_json("zwidth " + kDevice +
                            " --display admittance --kp 20 --ki 500 --coupling-mass 0.5 "
                            "--models encoder --points 60 --json");
    EXPECT_EQ(j.at("display"), "admittance");
    EXPECT_TRUE(j.at("design").at("damping").is_null());
    const std::vector<double> f = doubles(j.at("frequency_hz"));
    const std::vector<double> zmin = doubles(j.at("models").at("encoder").at("zmin_magnitude"));
    const std::vector<double> zmax = doubles(j.at("models").at("encoder").at("zmax_magnitude"));
    for (const std::size_t i : {std::size_t{5}, std::size_t{40}, std::size_t{55}}) {
        const double theta = theta_at(f[i]);
        const Complex z = std::polar(1.0, theta);
        const Complex pi_gain = kp + ki * kPeriod * z / (z - 1.0);  // (27)
        const Complex h = encoder_hold(theta);
        const Complex zda = encoder_device(theta) + pi_gain * h;                       // (30)
        const Complex tracking = h * pi_gain / (encoder_device(theta) + h * pi_gain);  // (29)
        const Complex zca = 1.0 / (kPeriod * z / ((z - 1.0) * mc));                    // (32)
        EXPECT_NEAR(zmax[i], std::abs(zda), 1e-9 * zmax[i]);                           // (43)
        EXPECT_NEAR(zmin[i], std::abs(zca / (tracking + zca / zda)), 1e-9 * zmin[i]);  // (42)
    }
}

// ---- bad input and a missing renderer ---------------------------------------------

struct BadChartInput {
    std::string args;
    std::string must_name;
};
// Names the case readably in test listings (instead of the struct's raw bytes).
void PrintTo(const BadChartInput& input, std::ostream* out) {
    *out << "expect '" << input.must_name << "' from: " << input.args;
}
class plotBadInput : public ::testing::TestWithParam<BadChartInput> {};

TEST_P(plotBadInput, ExitsTwoAndNamesTheValue) {
    const auto result = run_command(tune(GetParam().args));
    EXPECT_EQ(result.exit_code, 2) << result.out;
    EXPECT_NE(result.err.find(GetParam().must_name), std::string::npos) << result.err;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, plotBadInput,
    ::testing::Values(
        BadChartInput{"plot " + kDesign + " --models foo --json", "foo"},
        BadChartInput{"plot " + kDesign + " --models paper,,encoder --json", "empty"},
        BadChartInput{"zwidth " + kDesign + " --models paper,bar --json", "bar"},
        BadChartInput{"plot " + kDesign + " --out /tmp/x.bmp", ".bmp"},
        BadChartInput{"zwidth " + kDesign + " --out chart", "--out chart"},
        BadChartInput{"plot " + kDesign + " --out /nonexistent-hapticd-dir/x.png",
                      "/nonexistent-hapticd-dir"},
        BadChartInput{"plot " + kDesign, "--out"},
        BadChartInput{"plot " + kDesign + " --points 3 --json", "--points"},
        BadChartInput{"plot " + kDevice + " --stiffness 0 --coupling-damping 0 --json",
                      "no coupling"},
        BadChartInput{"plot --mass 0.1 --damping 2 --json", "--rate"},
        BadChartInput{"zwidth " + kDevice + " --display admittance --kp 20 --json", "--ki"},
        BadChartInput{"zwidth " + kDesign + " --kp 20 --json", "--display admittance"},
        BadChartInput{
            "zwidth " + kDevice + " --display admittance --kp 20 --ki 500 --delay 0.001 --json",
            "no loop delay"},
        BadChartInput{"plot " + kDesign + " --size 3x --json", "--size 3x"},
        BadChartInput{"plot " + kDesign + " --size 7x4.8ft --json", "--size 7x4.8ft"},
        BadChartInput{"plot " + kDesign + " --size 0.5x3 --json", "1 to 40 in"},
        BadChartInput{"plot " + kDesign + " --size 200x100cm --json", "78.74 in"},
        BadChartInput{"plot " + kDesign + " --font-size 2 --json", "--font-size"}));

TEST(plotRenderer, MissingPythonSaysWhatToInstall) {
    const ScratchDir dir;
    const auto result = run_command("HAPTICD_PYTHON=/nonexistent/python3 " +
                                    tune("plot " + kDesign + " --out " + dir.file("x.png")));
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_NE(result.err.find("/nonexistent/python3"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("python3-matplotlib"), std::string::npos) << result.err;
}

TEST(plotRenderer, MissingMatplotlibSaysWhatToInstall) {
    const ScratchDir dir;
    // A matplotlib package that cannot be imported, ahead of the real one on the path.
    std::filesystem::create_directories(dir.file("fake/matplotlib"));
    std::ofstream(dir.file("fake/matplotlib/__init__.py")) << "raise ImportError('simulated')\n";
    const auto result = run_command("PYTHONPATH=" + dir.file("fake") + " " +
                                    tune("zwidth " + kDesign + " --out " + dir.file("x.png")));
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_NE(result.err.find("python3-matplotlib"), std::string::npos) << result.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.png")));
}

TEST(plotRenderer, AFailingScriptIsReportedWithItsMessage) {
    const ScratchDir dir;
    std::ofstream(dir.file("broken.py")) << "import sys\nsys.stdin.read()\n"
                                            "print('renderer exploded', file=sys.stderr)\n"
                                            "sys.exit(1)\n";
    const auto result = run_command("HAPTICD_CHART_SCRIPT=" + dir.file("broken.py") + " " +
                                    tune("plot " + kDesign + " --out " + dir.file("x.png")));
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_NE(result.err.find("renderer exploded"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("status 1"), std::string::npos) << result.err;
}

}  // namespace
}  // namespace hapticd
