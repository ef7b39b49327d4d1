// Rigid constraints for the admittance (constraint based) environments: half-spaces and
// spheres. Free space is where every constraint's gap is >= 0 (to within
// kContactTolerance_m); the gap is the signed distance to the surface, positive on the free
// side. Used by the god-object (god_object.hpp) and the constrained virtual mass
// (virtual_mass.hpp). All functions are real-time safe.
#pragma once

#include <vector>

#include "hapticd/env/environment.hpp"

namespace hapticd::env {

/// Points within this distance of a surface count as on it; a proxy or mass is "in free
/// space" when no gap is below -kContactTolerance_m (1 nm: far below any encoder count).
inline constexpr double kContactTolerance_m = 1e-9;

/// The half-space n·x >= d is free; n (unit) points into free space.
struct PlaneConstraint {
    Vec3 normal_in_free_space{0.0, 0.0, 1.0};
    double offset_m = 0.0;
};

enum class SphereSide {
    outside,  ///< a solid ball: the tool stays outside it
    inside,   ///< a spherical cavity: the tool stays inside it
};

struct SphereConstraint {
    Vec3 center_m{0.0};
    double radius_m = 0.0;  ///< > 0
    SphereSide side = SphereSide::outside;
};

/// Signed distance to the surface, positive in free space, m.
[[nodiscard]] double gap_m(const PlaneConstraint& c, const Vec3& x) noexcept;
[[nodiscard]] double gap_m(const SphereConstraint& c, const Vec3& x) noexcept;

/// The unit normal into free space at the surface point nearest x. At a sphere's centre,
/// where every direction is nearest, it is +x.
[[nodiscard]] Vec3 free_normal(const PlaneConstraint& c, const Vec3& x) noexcept;
[[nodiscard]] Vec3 free_normal(const SphereConstraint& c, const Vec3& x) noexcept;

/// The surface point nearest x.
[[nodiscard]] Vec3 project_to_surface(const PlaneConstraint& c, const Vec3& x) noexcept;
[[nodiscard]] Vec3 project_to_surface(const SphereConstraint& c, const Vec3& x) noexcept;

/// The tangent half-space at the surface point nearest x (the plane itself for a plane).
[[nodiscard]] PlaneConstraint tangent_plane(const PlaneConstraint& c, const Vec3& x) noexcept;
[[nodiscard]] PlaneConstraint tangent_plane(const SphereConstraint& c, const Vec3& x) noexcept;

/// The first t in [0, 1] where the segment from `from` (free) to `to` enters the solid side
/// of c, or a value > 1 if it does not.
[[nodiscard]] double first_entry(const PlaneConstraint& c, const Vec3& from,
                                 const Vec3& to) noexcept;
[[nodiscard]] double first_entry(const SphereConstraint& c, const Vec3& from,
                                 const Vec3& to) noexcept;

/// The constraints of one environment, by type; filled at build time, never grown after.
struct ConstraintSet {
    std::vector<PlaneConstraint> planes;
    std::vector<SphereConstraint> spheres;

    [[nodiscard]] std::size_t size() const noexcept { return planes.size() + spheres.size(); }
    /// The smallest gap over all constraints (+infinity if there are none), m.
    [[nodiscard]] double min_gap_m(const Vec3& x) const noexcept;
    [[nodiscard]] bool is_free(const Vec3& x) const noexcept {
        return min_gap_m(x) >= -kContactTolerance_m;
    }
    /// A free point near x by alternating projections onto violated surfaces (the nearest
    /// free point when the constraints do not interact); returns false if `rounds` were not
    /// enough, and then `x` is left as the last projection.
    bool project_to_free(Vec3& x, int rounds = 32) const noexcept;
};

}  // namespace hapticd::env
