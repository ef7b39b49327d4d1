// The scene loader: TOML -> validated objects -> the one environment the scene needs.
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "hapticd/env/external_environment.hpp"
#include "hapticd/env/god_object.hpp"
#include "hapticd/env/penalty_scene.hpp"
#include "hapticd/env/plugin_environment.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/env/virtual_mass.hpp"
#include "hapticd/input/text_input.hpp"
#include "hapticd/servo/soft_start.hpp"
#include "scene_fields.hpp"

namespace hapticd::env {

const char* to_string(Causality causality) noexcept {
    return causality == Causality::impedance ? "impedance" : "admittance";
}

namespace {

using detail::kCoefficient;
using detail::kCoordinate;
using detail::kDamping;
using detail::kMass;
using detail::kPositiveDamping;
using detail::kPositiveForce;
using detail::kPositiveLength;
using detail::kPositiveStiffness;
using detail::kStiffness;
using detail::Range;
using detail::read_vector;
using detail::TableReader;
using input::Number;

// The keys of the schema (scene.hpp), each with its range and default; vectors are read
// with read_vector.
constexpr Number kOffset{"offset", kCoordinate, 0.0};
constexpr Number kObjectStiffness{"stiffness", kPositiveStiffness};
constexpr Number kWallDamping{"damping", kDamping, 0.0};
constexpr Number kDamperDamping{"damping", kPositiveDamping};
constexpr Number kDetentPeriod{"period", kPositiveLength};
constexpr Number kDetentPeakForce{"peak_force", kPositiveForce};
constexpr input::Flag kDetentPeriodic{"periodic", true};
constexpr Number kNormalForce{"normal_force", kPositiveForce};
constexpr Number kStaticCoefficient{"static_coefficient", kCoefficient};
constexpr Number kRadius{"radius", kPositiveLength};
constexpr Number kVirtualMass{"mass", kMass};
constexpr Number kVirtualMassStiffness{"stiffness", kStiffness, 0.0};
constexpr Number kVirtualMassDamping{"damping", kDamping, 0.0};

std::string_view side_name(SphereSide side) noexcept {
    return side == SphereSide::inside ? "inside" : "outside";
}
constexpr SphereSide kSides[] = {SphereSide::outside, SphereSide::inside};
constexpr input::Choice<SphereSide> kSide{"side", kSides, &side_name, SphereSide::outside};

// [external] (external_environment.hpp).
std::string_view between_name(BetweenUpdates between) noexcept { return to_string(between); }
constexpr BetweenUpdates kBetweens[] = {BetweenUpdates::extrapolate, BetweenUpdates::hold};
constexpr input::Choice<BetweenUpdates> kBetweenUpdates{
    "between_updates", kBetweens, &between_name, ExternalSpec{}.between_updates,
    "what the coupling sees between the world's updates"};
constexpr input::Integer kLockstepEvery{
    "lockstep_every", 0,
    100000,           ExternalSpec{}.lockstep_every,
    "ticks",          "0: free-running; N: the tick waits for the world every N"};
constexpr Number kStaleAfter{"stale_after",
                             Range{.lo = 0.0, .hi = 10.0, .lo_open = true, .unit = "s"},
                             ExternalSpec{}.stale_after_s, "no update for this long is stale"};
constexpr Number kStaleRamp{"ramp", servo::kRampTimeRange, ExternalSpec{}.ramp_s,
                            "a stale world's force ramps to zero over this long"};
constexpr Number kLockstepTimeout{
    "lockstep_timeout", Range{.lo = 0.0, .hi = 600.0, .lo_open = true, .unit = "s"},
    ExternalSpec{}.lockstep_timeout_s, "the longest a lockstep tick waits for the world's answer"};
constexpr servo::PassivityMode kPortPassivityModes[] = {
    servo::PassivityMode::control, servo::PassivityMode::observe, servo::PassivityMode::off};
constexpr input::Choice<servo::PassivityMode> kPortPassivity{
    "passivity", kPortPassivityModes, &servo::to_string, ExternalSpec{}.passivity,
    "the passivity controller on the world's port; observe or off take the world for passive"};

const char* const kPenaltyKinds[] = {"wall", "spring", "damper", "detent", "friction"};
const char* const kArrayKinds[] = {"wall",     "spring",      "damper",      "detent",
                                   "friction", "proxy_plane", "proxy_sphere"};

class SceneParser {
  public:
    SceneParser(const toml::table& root, std::string source, const SceneOptions& options)
        : root_(root), source_(std::move(source)), file_(root, source_, ""), options_(options) {}

    Scene parse(int device_axes) {
        // Every table the schema has, then the rest refused, before anything is read.
        const toml::table* header = file_.subtable("scene");
        for (const char* kind : kArrayKinds) (void)file_.array_of_tables(kind);
        (void)file_.subtable("virtual_mass");
        const toml::table* plugin = file_.subtable("plugin");
        const toml::table* external = file_.subtable("external");
        file_.finish();
        Scene scene;
        read_header(header, scene, device_axes);
        axes_ = scene.axes;
        if (plugin != nullptr && external != nullptr) {
            throw SceneError(source_ +
                             ": [plugin] and [external] are each a whole scene: keep one");
        }
        if (plugin != nullptr) {
            build_plugin(*plugin, scene);
            return scene;
        }
        if (external != nullptr) {
            build_external(*external, scene);
            return scene;
        }

        const bool has_penalty = first_present(kPenaltyKinds) != nullptr;
        const bool has_proxy = root_.contains("proxy_plane") || root_.contains("proxy_sphere");
        const bool has_mass = root_.contains("virtual_mass");
        if (has_penalty && (has_proxy || has_mass)) {
            const std::string constraint =
                has_proxy ? (root_.contains("proxy_plane") ? "[[proxy_plane]]" : "[[proxy_sphere]]")
                          : "[virtual_mass]";
            throw SceneError(source_ +
                             ": a scene has one causality, but this one mixes penalty "
                             "(impedance) objects ([[" +
                             std::string(first_present(kPenaltyKinds)) +
                             "]]) with constraint (admittance) objects (" + constraint +
                             "): put them in separate scenes");
        }
        if (has_proxy && has_mass) {
            throw SceneError(source_ +
                             ": a scene holds one admittance environment, but this one "
                             "has both a god-object ([[proxy_plane]]/[[proxy_sphere]]) and a "
                             "[virtual_mass]: keep one");
        }
        if (has_proxy) {
            scene.causality = Causality::admittance;
            scene.admittance = build_god_object();
        } else if (has_mass) {
            scene.causality = Causality::admittance;
            scene.admittance = build_virtual_mass();
        } else {
            scene.causality = Causality::impedance;
            scene.impedance = build_penalty_scene();
        }
        scene.linear_objects = std::move(linear_);
        scene.unmodelled = std::move(unmodelled_);
        scene.most_negative_stiffness = std::move(negative_);
        return scene;
    }

  private:
    const char* first_present(const char* const (&kinds)[5]) const {
        for (const char* kind : kinds) {
            if (root_.contains(kind)) return kind;
        }
        return nullptr;
    }

    void read_header(const toml::table* table, Scene& scene, int device_axes) const {
        if (device_axes < 1 || device_axes > 3) {
            throw SceneError(source_ + ": the device has " + std::to_string(device_axes) +
                             " axes: allowed 1 to 3");
        }
        if (table == nullptr) {
            throw SceneError(source_ + ": [scene] is missing: required, with name and axes");
        }
        TableReader reader = file_.nested(*table, "scene");
        reader.only({"name", "axes"});
        scene.name = reader.read(input::Text{"name", std::nullopt, false, "a non-empty name"});
        scene.axes = static_cast<int>(reader.read(
            input::Integer{"axes", 1, device_axes, std::nullopt,
                           device_axes == 1 ? "the device has 1 axis" : "the device's axes"}));
        reader.finish();
    }

    /// Calls read(reader) for each table of the array of tables `kind` in `parent`, then
    /// refuses the keys it did not read.
    template <typename Read>
    void for_each(TableReader& parent, const char* kind,
                  std::initializer_list<std::string_view> keys, Read read) const {
        const toml::array* array = parent.array_of_tables(kind);
        if (array == nullptr) return;
        for (std::size_t i = 0; i < array->size(); ++i) {
            TableReader reader =
                parent.nested(*array->get(i)->as_table(), kind, static_cast<int>(i + 1));
            reader.only(keys);
            read(reader);
            reader.finish();
        }
    }

    std::unique_ptr<ImpedanceEnvironment> build_penalty_scene() {
        PenaltyObjects objects;
        for_each(file_, "wall", {"normal", "offset", "stiffness", "damping"}, [&](TableReader& r) {
            Wall wall;
            wall.normal_in_free_space = read_vector(r, "normal", axes_, true);
            wall.offset_m = r.read(kOffset);
            wall.stiffness_n_per_m = r.read(kObjectStiffness);
            wall.damping_n_s_per_m = r.read(kWallDamping);
            objects.walls.push_back(wall);
            linear("wall", objects.walls.size(), 0.0, wall.stiffness_n_per_m,
                   wall.damping_n_s_per_m);
        });
        for_each(file_, "spring", {"anchor", "stiffness"}, [&](TableReader& r) {
            Spring spring;
            spring.anchor_m = read_vector(r, "anchor", axes_, false, Vec3(0.0));
            spring.stiffness_n_per_m = r.read(kObjectStiffness);
            objects.springs.push_back(spring);
            linear("spring", objects.springs.size(), 0.0, spring.stiffness_n_per_m, 0.0);
        });
        for_each(file_, "damper", {"damping"}, [&](TableReader& r) {
            objects.dampers.push_back(Damper{r.read(kDamperDamping)});
            linear("damper", objects.dampers.size(), 0.0, 0.0,
                   objects.dampers.back().damping_n_s_per_m);
        });
        for_each(file_, "detent", {"axis", "center", "period", "peak_force", "periodic"},
                 [&](TableReader& r) {
                     Detent detent;
                     detent.axis = read_vector(r, "axis", axes_, true);
                     detent.center_m = read_vector(r, "center", axes_, false, Vec3(0.0));
                     detent.period_m = r.read(kDetentPeriod);
                     detent.peak_force_n = r.read(kDetentPeakForce);
                     detent.periodic = r.read(kDetentPeriodic);
                     objects.detents.push_back(detent);
                     const double slope_n_per_m =
                         -2.0 * std::numbers::pi * detent.peak_force_n / detent.period_m;
                     if (!negative_ || slope_n_per_m < negative_->stiffness_n_per_m) {
                         negative_ = LinearObject{
                             .source = "[[detent]] #" + std::to_string(objects.detents.size()),
                             .stiffness_n_per_m = slope_n_per_m};
                     }
                     unmodelled("[[detent]] #" + std::to_string(objects.detents.size()) +
                                ": its force is periodic in position, with a slope that "
                                "changes sign, so it has no passive linear model");
                 });
        for_each(file_, "friction",
                 {"normal_force", "static_coefficient", "kinetic_coefficient", "stiffness"},
                 [&](TableReader& r) {
                     StickSlipFriction friction;
                     friction.normal_force_n = r.read(kNormalForce);
                     friction.static_coefficient = r.read(kStaticCoefficient);
                     friction.kinetic_coefficient =
                         r.read(Number{"kinetic_coefficient",
                                       {.lo = 0.0,
                                        .hi = friction.static_coefficient,
                                        .lo_open = true,
                                        .unit = "at most static_coefficient"}});
                     friction.stiffness_n_per_m = r.read(kObjectStiffness);
                     objects.frictions.push_back(friction);
                     unmodelled("[[friction]] #" + std::to_string(objects.frictions.size()) +
                                ": stick-slip switches between a spring and a sliding force, "
                                "so it has no linear model");
                 });
        if (linear_.size() > 1) {
            // Every contact at once: the objects' stiffnesses and dampings add.
            LinearObject all{"all " + std::to_string(linear_.size()) + " objects at once"};
            for (const LinearObject& o : linear_) {
                all.stiffness_n_per_m += o.stiffness_n_per_m;
                all.damping_n_s_per_m += o.damping_n_s_per_m;
            }
            linear_.push_back(all);
        }
        auto scene = std::make_unique<PenaltyScene>(std::move(objects), axes_);
        scene->reset(Vec3(0.0));
        return scene;
    }

    ConstraintSet read_constraints(TableReader& parent, const char* plane_kind,
                                   const char* sphere_kind) const {
        ConstraintSet constraints;
        for_each(parent, plane_kind, {"normal", "offset"}, [&](TableReader& r) {
            PlaneConstraint plane;
            plane.normal_in_free_space = read_vector(r, "normal", axes_, true);
            plane.offset_m = r.read(kOffset);
            constraints.planes.push_back(plane);
        });
        for_each(parent, sphere_kind, {"center", "radius", "side"}, [&](TableReader& r) {
            SphereConstraint sphere;
            sphere.center_m = read_vector(r, "center", axes_, false, Vec3(0.0));
            sphere.radius_m = r.read(kRadius);
            sphere.side = r.read(kSide);
            constraints.spheres.push_back(sphere);
        });
        return constraints;
    }

    std::unique_ptr<AdmittanceEnvironment> build_god_object() {
        ConstraintSet constraints = read_constraints(file_, "proxy_plane", "proxy_sphere");
        auto god_object = std::make_unique<GodObject>(std::move(constraints), axes_);
        linear_.push_back({"the god-object in contact with its constraints", 0.0, 0.0, 0.0, true});
        if (!god_object->constraints().is_free(god_object->proxy_m())) {
            throw SceneError(source_ +
                             ": the [[proxy_plane]]/[[proxy_sphere]] constraints leave "
                             "no free space near the origin: allowed constraints whose free "
                             "space is not empty");
        }
        return god_object;
    }

    std::unique_ptr<AdmittanceEnvironment> build_virtual_mass() {
        TableReader reader = file_.nested(*file_.subtable("virtual_mass"), "virtual_mass");
        reader.only({"mass", "stiffness", "damping", "anchor", "plane", "sphere"});
        VirtualMassParameters parameters;
        parameters.mass_kg = reader.read(kVirtualMass);
        parameters.stiffness_n_per_m = reader.read(kVirtualMassStiffness);
        parameters.damping_n_s_per_m = reader.read(kVirtualMassDamping);
        parameters.anchor_m = read_vector(reader, "anchor", axes_, false, Vec3(0.0));
        ConstraintSet constraints = read_constraints(reader, "plane", "sphere");
        reader.finish();
        if (!constraints.is_free(parameters.anchor_m)) {
            reader.fail("anchor", "is inside a constraint", "a point in free space");
        }
        linear_.push_back({"[virtual_mass]", parameters.mass_kg, parameters.stiffness_n_per_m,
                           parameters.damping_n_s_per_m, false});
        if (!constraints.planes.empty() || !constraints.spheres.empty()) {
            linear_.push_back(
                {"[virtual_mass] in contact with its constraints", 0.0, 0.0, 0.0, true});
        }
        return std::make_unique<VirtualMass>(parameters, std::move(constraints), axes_);
    }

    // [plugin]: a world of the lab's own (plugin_environment.hpp), alone in its scene. Its
    // causality is the plugin's. hapticd has no model of it: the stability check holds for it
    // only as a passive environment (docs/scenes.md, "Your own world").
    void build_plugin(const toml::table& table, Scene& scene) {
        require_alone("plugin");
        TableReader reader = file_.nested(table, "plugin");
        reader.only({"name", "max_call_us", "settings"});
        PluginSpec spec;
        spec.name = reader.read(input::Text{
            "name", std::nullopt, false,
            "a plugin name (libhapticd-env-NAME.so on the plugin path) or a path with '/'"});
        const double period_us = 1e6 / options_.rate_hz;
        spec.max_call_us = reader.read(input::Number{
            "max_call_us", input::Range{.lo = 0.0, .hi = period_us, .lo_open = true, .unit = "us"},
            period_us / 4.0, "the most a tick's calls into the world may take"});
        if (const toml::table* settings = reader.subtable("settings")) {
            std::ostringstream text;
            text << toml::toml_formatter(*settings);
            spec.settings_toml = text.str();
        }
        reader.finish();
        if (!options_.load_plugins) {
            throw SceneError(source_ +
                             ": [plugin] scenes are not read here: " + options_.why_no_plugins);
        }
        LoadedPlugin loaded;
        try {
            loaded = load_environment_plugin(spec, axes_, options_.rate_hz, source_);
        } catch (const std::runtime_error& e) {
            throw SceneError(e.what());
        }
        scene.unmodelled = "the plugin world [plugin] " + loaded.name +
                           ": hapticd has no model of it, and takes it for a passive environment";
        if (loaded.admittance) {
            scene.causality = Causality::admittance;
            scene.admittance = std::move(loaded.admittance_environment);
        } else {
            scene.causality = Causality::impedance;
            scene.impedance = std::move(loaded.impedance);
        }
        scene.plugin = loaded.name + " (" + loaded.path + ")";
    }

    // A world of the lab's own ([plugin], [external]) is the whole scene.
    void require_alone(const std::string& table) const {
        for (const char* kind : kArrayKinds) {
            if (root_.contains(kind)) {
                throw SceneError(source_ + ": [" + table +
                                 "] is the whole scene, but this one also has [[" +
                                 std::string(kind) + "]]: put the objects in the " + table +
                                 " world, or in a scene of their own");
            }
        }
        if (root_.contains("virtual_mass")) {
            throw SceneError(source_ + ": [" + table +
                             "] is the whole scene, but this one also has [virtual_mass]: keep "
                             "one");
        }
    }

    // [external]: a world another process renders at its own rate through shared memory
    // (external_environment.hpp), an admittance (22). hapticd has no model of it; the
    // passivity controller on its port makes it passive, unless the scene turns it off.
    void build_external(const toml::table& table, Scene& scene) {
        require_alone("external");
        TableReader reader = file_.nested(table, "external");
        reader.only({"between_updates", "stale_after", "ramp", "lockstep_every", "lockstep_timeout",
                     "passivity"});
        ExternalSpec spec;
        spec.between_updates = reader.read(kBetweenUpdates);
        spec.lockstep_every = static_cast<std::uint32_t>(reader.read(kLockstepEvery));
        const double every_s = spec.lockstep_every / options_.rate_hz;
        spec.stale_after_s = reader.read(kStaleAfter);
        if (spec.stale_after_s <= every_s) {
            throw SceneError(
                source_ + ": [external] stale_after = " + input::exact_number(spec.stale_after_s) +
                " is out of range: allowed > lockstep_every / rate_hz = " +
                input::exact_number(every_s) +
                " s (a world in lockstep answers once in that long)");
        }
        spec.ramp_s = reader.read(kStaleRamp);
        spec.lockstep_timeout_s = reader.read(kLockstepTimeout);
        spec.passivity = reader.read(kPortPassivity);
        reader.finish();
        std::string note;
        std::unique_ptr<ExternalChannel> channel;
        try {
            channel = std::make_unique<ExternalChannel>(
                options_.external_channel,
                ChannelShape{.axes = static_cast<std::uint32_t>(axes_),
                             .lockstep_every = spec.lockstep_every,
                             .rate_hz = options_.rate_hz,
                             .stale_after_s = spec.stale_after_s},
                options_.external_group, note);
        } catch (const std::runtime_error& e) {
            throw SceneError(source_ + ": [external]: " + e.what());
        }
        scene.external = channel->path();  // "": private
        scene.external_note = std::move(note);
        scene.unmodelled =
            spec.passivity == PassivityMode::control
                ? "the external world [external]: hapticd has no model of it; the passivity "
                  "controller on its port keeps it passive"
                : "the external world [external]: hapticd has no model of it, and takes it for "
                  "a passive environment (passivity = \"" +
                      std::string(servo::to_string(spec.passivity)) + "\")";
        scene.causality = Causality::admittance;
        scene.admittance =
            std::make_unique<ExternalEnvironment>(spec, std::move(channel), axes_, options_.stop);
    }

    void linear(const char* kind, std::size_t index, double mass, double stiffness,
                double damping) {
        linear_.push_back({"[[" + std::string(kind) + "]] #" + std::to_string(index), mass,
                           stiffness, damping, false});
    }
    void unmodelled(std::string why) {
        if (unmodelled_.empty()) unmodelled_ = std::move(why);
    }

    const toml::table& root_;
    std::string source_;
    TableReader file_;
    SceneOptions options_;
    int axes_ = 0;
    // What the stability check's scene model needs (Scene::linear_objects).
    std::vector<LinearObject> linear_;
    std::string unmodelled_;
    std::optional<LinearObject> negative_;
};

}  // namespace

Scene parse_scene(std::string_view text, const std::string& source_name, int axes,
                  const SceneOptions& options) {
    const toml::table root = input::parse_document(text, source_name);
    return SceneParser(root, source_name, options).parse(axes);
}

Scene load_scene(const std::string& path, int axes, const SceneOptions& options) {
    return parse_scene(input::read_text_file(path, "the scene file"), path, axes, options);
}

}  // namespace hapticd::env
