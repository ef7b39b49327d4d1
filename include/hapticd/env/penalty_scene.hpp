// A penalty (impedance) scene: the sum of plain penalty objects, held by type in vectors
// that are filled when the scene is built and never grow afterwards. evaluate() sums the
// objects' forces and Jacobians; commit()/reset() update the stateful ones (friction).
// No virtual call per object, no allocation, lock, log or throw in the tick.
//
// Forces and Jacobians are masked to the scene's axes: components beyond `axes` are zero.
#pragma once

#include <vector>

#include "hapticd/env/environment.hpp"
#include "hapticd/env/friction.hpp"
#include "hapticd/env/penalty_objects.hpp"

namespace hapticd::env {

/// The objects of a penalty scene, by type.
struct PenaltyObjects {
    std::vector<Wall> walls;
    std::vector<Spring> springs;
    std::vector<Damper> dampers;
    std::vector<Detent> detents;
    std::vector<StickSlipFriction> frictions;

    [[nodiscard]] std::size_t size() const noexcept {
        return walls.size() + springs.size() + dampers.size() + detents.size() + frictions.size();
    }
};

class PenaltyScene final : public ImpedanceEnvironment {
  public:
    /// `axes` in 1..3: forces and Jacobians are zero beyond it.
    explicit PenaltyScene(PenaltyObjects objects, int axes = 3);

    PenaltyForce evaluate(const Vec3& tool_position_m,
                          const Vec3& tool_velocity_mps) const noexcept override;
    void commit(const Vec3& tool_position_m, const Vec3& tool_velocity_mps) noexcept override;
    void reset(const Vec3& tool_position_m) noexcept override;

    [[nodiscard]] const PenaltyObjects& objects() const noexcept { return objects_; }
    [[nodiscard]] int axes() const noexcept { return axes_; }

  private:
    PenaltyObjects objects_;
    int axes_;
};

}  // namespace hapticd::env
