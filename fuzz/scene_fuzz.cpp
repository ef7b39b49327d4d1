// libFuzzer target for the scene loader (env::parse_scene, docs/scenes.md): any text, for a
// device of 1, 2 or 3 axes, is either a scene or a SceneError; a scene that loads has exactly
// one environment of its causality, and renders finite forces (and tool positions) about the
// origin and its own reset point. Anything else is a finding. The seed corpus
// (fuzz/corpus/scene) is replayed in ctest under GCC (tests/fuzz_replay).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_check.hpp"
#include "hapticd/env/scene.hpp"

namespace {

using hapticd::env::Vec3;

bool finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    for (int axes = 1; axes <= 3; ++axes) {
        try {
            hapticd::env::Scene scene = hapticd::env::parse_scene(text, "fuzz.toml", axes);
            FUZZ_CHECK((scene.impedance != nullptr) != (scene.admittance != nullptr));
            FUZZ_CHECK(scene.axes >= 1 && scene.axes <= axes);
            for (const double x : {-0.01, 0.0, 0.01}) {
                const Vec3 at(x, -x, 0.5 * x);
                if (scene.impedance) {
                    scene.impedance->reset(Vec3(0.0));
                    const auto f = scene.impedance->evaluate(at, Vec3(0.1, 0.0, -0.1));
                    FUZZ_CHECK(finite(f.force_n));
                } else {
                    scene.admittance->reset(Vec3(0.0));
                    const Vec3 tool = scene.admittance->step(
                        at, Vec3(0.1, 0.0, -0.1),
                        {.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 1.0}, 1e-3);
                    FUZZ_CHECK(finite(tool));
                }
            }
        } catch (const hapticd::env::SceneError&) {
            // refused, with a message
        }
    }
    return 0;
}
