// The scene loader: TOML -> validated objects -> the one environment the scene needs.
#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <utility>

#include "hapticd/env/god_object.hpp"
#include "hapticd/env/penalty_scene.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/env/virtual_mass.hpp"
#include "hapticd/input/text_input.hpp"
#include "scene_fields.hpp"

namespace hapticd::env {

const char* to_string(Causality causality) noexcept {
    return causality == Causality::impedance ? "impedance" : "admittance";
}

namespace {

using detail::kMaxCoefficient;
using detail::kMaxDamping_n_s_per_m;
using detail::kMaxForce_n;
using detail::kMaxLength_m;
using detail::kMaxMass_kg;
using detail::kMaxStiffness_n_per_m;
using detail::Range;
using detail::TableReader;
using detail::where;

constexpr Range kPositiveStiffness{0.0, false, kMaxStiffness_n_per_m, true, "N/m"};
constexpr Range kStiffness{0.0, true, kMaxStiffness_n_per_m, true, "N/m"};
constexpr Range kPositiveDamping{0.0, false, kMaxDamping_n_s_per_m, true, "N s/m"};
constexpr Range kDamping{0.0, true, kMaxDamping_n_s_per_m, true, "N s/m"};
constexpr Range kPositiveForce{0.0, false, kMaxForce_n, true, "N"};
constexpr Range kPositiveLength{0.0, false, kMaxLength_m, true, "m"};
constexpr Range kOffset{-kMaxLength_m, true, kMaxLength_m, true, "m"};
constexpr Range kMass{0.0, false, kMaxMass_kg, true, "kg"};
constexpr Range kCoefficient{0.0, false, kMaxCoefficient, true, ""};

const char* const kPenaltyKinds[] = {"wall", "spring", "damper", "detent", "friction"};
const char* const kTopLevelKeys[] = {"scene",       "wall",         "spring",
                                     "damper",      "detent",       "friction",
                                     "proxy_plane", "proxy_sphere", "virtual_mass"};

class SceneParser {
  public:
    SceneParser(const toml::table& root, std::string source)
        : root_(root), source_(std::move(source)) {}

    Scene parse(int device_axes) {
        reject_unknown_tables();
        Scene scene;
        read_header(scene, device_axes);
        axes_ = scene.axes;

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
    void reject_unknown_tables() const {
        for (const auto& [key, node] : root_) {
            bool known = false;
            for (const char* allowed : kTopLevelKeys) known = known || key.str() == allowed;
            if (known) continue;
            std::string allowed_list;
            for (const char* allowed : kTopLevelKeys) {
                allowed_list += (allowed_list.empty() ? "" : ", ") + std::string(allowed);
            }
            throw SceneError(where(source_, &node) + "unknown table or key '" +
                             std::string(key.str()) + "': allowed are " + allowed_list);
        }
    }

    const char* first_present(const char* const (&kinds)[5]) const {
        for (const char* kind : kinds) {
            if (root_.contains(kind)) return kind;
        }
        return nullptr;
    }

    void read_header(Scene& scene, int device_axes) const {
        if (device_axes < 1 || device_axes > 3) {
            throw SceneError(source_ + ": the device has " + std::to_string(device_axes) +
                             " axes: allowed 1 to 3");
        }
        const toml::node* node = root_.get("scene");
        if (node == nullptr) {
            throw SceneError(source_ + ": [scene] is missing: required, with name and axes");
        }
        const toml::table* table = node->as_table();
        if (table == nullptr) {
            throw SceneError(where(source_, node) + "scene must be a table ([scene])");
        }
        TableReader reader(*table, source_, "[scene]", 0, {"name", "axes"});
        scene.name = reader.string("name");
        if (scene.name.empty()) reader.fail("name", " = \"\" is empty: allowed a non-empty string");
        const Range axes_range{
            1.0, true, static_cast<double>(device_axes), true,
            device_axes == 1 ? "(the device has 1 axis)" : "(the device's axes)"};
        const double axes = reader.number("axes", axes_range);
        if (axes != static_cast<double>(static_cast<int>(axes))) {
            reader.fail("axes", " = " + detail::format_number(axes) +
                                    " is not an integer: allowed " + axes_range.describe());
        }
        scene.axes = static_cast<int>(axes);
    }

    /// Calls read(reader) for each table of the array of tables `kind`.
    template <typename Read>
    void for_each(const char* kind, std::initializer_list<std::string_view> keys, Read read,
                  const toml::table* parent = nullptr, const std::string& parent_name = "") const {
        const toml::table& where_from = parent != nullptr ? *parent : root_;
        const toml::node* node = where_from.get(kind);
        if (node == nullptr) return;
        const std::string name = parent_name.empty() ? kind : parent_name + "." + kind;
        const toml::array* array = node->as_array();
        if (array == nullptr || !array->is_array_of_tables()) {
            throw SceneError(where(source_, node) + name + " must be an array of tables: write [[" +
                             name + "]] for each one");
        }
        for (std::size_t i = 0; i < array->size(); ++i) {
            const toml::table& table = *array->get(i)->as_table();
            TableReader reader(table, source_, "[[" + name + "]] #" + std::to_string(i + 1), axes_,
                               keys);
            read(reader);
        }
    }

    std::unique_ptr<ImpedanceEnvironment> build_penalty_scene() {
        PenaltyObjects objects;
        for_each("wall", {"normal", "offset", "stiffness", "damping"}, [&](TableReader& r) {
            Wall wall;
            wall.normal_in_free_space = r.vector("normal", true);
            wall.offset_m = r.number("offset", kOffset, 0.0);
            wall.stiffness_n_per_m = r.number("stiffness", kPositiveStiffness);
            wall.damping_n_s_per_m = r.number("damping", kDamping, 0.0);
            objects.walls.push_back(wall);
            linear("wall", objects.walls.size(), 0.0, wall.stiffness_n_per_m,
                   wall.damping_n_s_per_m);
        });
        for_each("spring", {"anchor", "stiffness"}, [&](TableReader& r) {
            Spring spring;
            spring.anchor_m = r.vector("anchor", false, Vec3(0.0));
            spring.stiffness_n_per_m = r.number("stiffness", kPositiveStiffness);
            objects.springs.push_back(spring);
            linear("spring", objects.springs.size(), 0.0, spring.stiffness_n_per_m, 0.0);
        });
        for_each("damper", {"damping"}, [&](TableReader& r) {
            objects.dampers.push_back(Damper{r.number("damping", kPositiveDamping)});
            linear("damper", objects.dampers.size(), 0.0, 0.0,
                   objects.dampers.back().damping_n_s_per_m);
        });
        for_each("detent", {"axis", "center", "period", "peak_force", "periodic"},
                 [&](TableReader& r) {
                     Detent detent;
                     detent.axis = r.vector("axis", true);
                     detent.center_m = r.vector("center", false, Vec3(0.0));
                     detent.period_m = r.number("period", kPositiveLength);
                     detent.peak_force_n = r.number("peak_force", kPositiveForce);
                     detent.periodic = r.boolean("periodic", true);
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
        for_each("friction",
                 {"normal_force", "static_coefficient", "kinetic_coefficient", "stiffness"},
                 [&](TableReader& r) {
                     StickSlipFriction friction;
                     friction.normal_force_n = r.number("normal_force", kPositiveForce);
                     friction.static_coefficient = r.number("static_coefficient", kCoefficient);
                     const Range kinetic{0.0, false, friction.static_coefficient, true,
                                         "(at most static_coefficient)"};
                     friction.kinetic_coefficient = r.number("kinetic_coefficient", kinetic);
                     friction.stiffness_n_per_m = r.number("stiffness", kPositiveStiffness);
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

    ConstraintSet read_constraints(const char* plane_kind, const char* sphere_kind,
                                   const toml::table* parent,
                                   const std::string& parent_name) const {
        ConstraintSet constraints;
        for_each(
            plane_kind, {"normal", "offset"},
            [&](TableReader& r) {
                PlaneConstraint plane;
                plane.normal_in_free_space = r.vector("normal", true);
                plane.offset_m = r.number("offset", kOffset, 0.0);
                constraints.planes.push_back(plane);
            },
            parent, parent_name);
        for_each(
            sphere_kind, {"center", "radius", "side"},
            [&](TableReader& r) {
                SphereConstraint sphere;
                sphere.center_m = r.vector("center", false, Vec3(0.0));
                sphere.radius_m = r.number("radius", kPositiveLength);
                const std::string side = r.string("side", "outside");
                if (side == "outside") {
                    sphere.side = SphereSide::outside;
                } else if (side == "inside") {
                    sphere.side = SphereSide::inside;
                } else {
                    r.fail("side",
                           " = \"" + side + "\" is not allowed: allowed \"outside\" or \"inside\"");
                }
                constraints.spheres.push_back(sphere);
            },
            parent, parent_name);
        return constraints;
    }

    std::unique_ptr<AdmittanceEnvironment> build_god_object() {
        ConstraintSet constraints = read_constraints("proxy_plane", "proxy_sphere", nullptr, "");
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
        const toml::node* node = root_.get("virtual_mass");
        const toml::table* table = node->as_table();
        if (table == nullptr) {
            throw SceneError(where(source_, node) +
                             "virtual_mass must be a table ([virtual_mass])");
        }
        TableReader reader(*table, source_, "[virtual_mass]", axes_,
                           {"mass", "stiffness", "damping", "anchor", "plane", "sphere"});
        VirtualMassParameters parameters;
        parameters.mass_kg = reader.number("mass", kMass);
        parameters.stiffness_n_per_m = reader.number("stiffness", kStiffness, 0.0);
        parameters.damping_n_s_per_m = reader.number("damping", kDamping, 0.0);
        parameters.anchor_m = reader.vector("anchor", false, Vec3(0.0));
        ConstraintSet constraints = read_constraints("plane", "sphere", table, "virtual_mass");
        if (!constraints.is_free(parameters.anchor_m)) {
            reader.fail("anchor", " = " + detail::format_vector(parameters.anchor_m, axes_) +
                                      " is inside a constraint: allowed a point in free space");
        }
        linear_.push_back({"[virtual_mass]", parameters.mass_kg, parameters.stiffness_n_per_m,
                           parameters.damping_n_s_per_m, false});
        if (!constraints.planes.empty() || !constraints.spheres.empty()) {
            linear_.push_back(
                {"[virtual_mass] in contact with its constraints", 0.0, 0.0, 0.0, true});
        }
        return std::make_unique<VirtualMass>(parameters, std::move(constraints), axes_);
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
    int axes_ = 0;
    // What the stability check's scene model needs (Scene::linear_objects).
    std::vector<LinearObject> linear_;
    std::string unmodelled_;
    std::optional<LinearObject> negative_;
};

}  // namespace

Scene parse_scene(std::string_view text, const std::string& source_name, int axes) {
    if (const std::string e = input::toml_shape_error(text, source_name); !e.empty()) {
        throw SceneError(e);
    }
    toml::table root;
    try {
        root = toml::parse(text, source_name);
    } catch (const toml::parse_error& error) {
        throw SceneError(source_name + ":" + std::to_string(error.source().begin.line) + ":" +
                         std::to_string(error.source().begin.column) +
                         ": TOML syntax error: " + std::string(error.description()));
    }
    return SceneParser(root, source_name).parse(axes);
}

Scene load_scene(const std::string& path, int axes) {
    std::string text;
    try {
        text = input::read_text_file(path, "the scene file");
    } catch (const input::InputError& e) {
        throw SceneError(e.what());
    }
    return parse_scene(text, path, axes);
}

}  // namespace hapticd::env
