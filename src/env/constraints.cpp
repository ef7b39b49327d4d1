#include "hapticd/env/constraints.hpp"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

namespace hapticd::env {
namespace {

constexpr double kNoEntry = 2.0;

}  // namespace

double gap_m(const PlaneConstraint& c, const Vec3& x) noexcept {
    return glm::dot(c.normal_in_free_space, x) - c.offset_m;
}

double gap_m(const SphereConstraint& c, const Vec3& x) noexcept {
    const double distance_m = glm::length(x - c.center_m);
    return c.side == SphereSide::outside ? distance_m - c.radius_m : c.radius_m - distance_m;
}

Vec3 free_normal(const PlaneConstraint& c, const Vec3& /*x*/) noexcept {
    return c.normal_in_free_space;
}

Vec3 free_normal(const SphereConstraint& c, const Vec3& x) noexcept {
    const Vec3 radial = x - c.center_m;
    const double distance_m = glm::length(radial);
    const Vec3 outward = distance_m > 0.0 ? radial / distance_m : Vec3(1.0, 0.0, 0.0);
    return c.side == SphereSide::outside ? outward : -outward;
}

Vec3 project_to_surface(const PlaneConstraint& c, const Vec3& x) noexcept {
    return x - gap_m(c, x) * c.normal_in_free_space;
}

Vec3 project_to_surface(const SphereConstraint& c, const Vec3& x) noexcept {
    const Vec3 radial = x - c.center_m;
    const double distance_m = glm::length(radial);
    const Vec3 outward = distance_m > 0.0 ? radial / distance_m : Vec3(1.0, 0.0, 0.0);
    return c.center_m + c.radius_m * outward;
}

PlaneConstraint tangent_plane(const PlaneConstraint& c, const Vec3& /*x*/) noexcept { return c; }

PlaneConstraint tangent_plane(const SphereConstraint& c, const Vec3& x) noexcept {
    const Vec3 normal = free_normal(c, x);
    return {normal, glm::dot(normal, project_to_surface(c, x))};
}

double first_entry(const PlaneConstraint& c, const Vec3& from, const Vec3& to) noexcept {
    const double gap_from = gap_m(c, from);
    const double gap_to = gap_m(c, to);
    if (gap_to >= 0.0) return kNoEntry;
    if (gap_from <= 0.0) return 0.0;
    return gap_from / (gap_from - gap_to);
}

double first_entry(const SphereConstraint& c, const Vec3& from, const Vec3& to) noexcept {
    // |from + t u - center|² = r²:  a t² + 2 h t + q = 0.
    const Vec3 u = to - from;
    const Vec3 w = from - c.center_m;
    const double a = glm::dot(u, u);
    if (a == 0.0) return gap_m(c, from) < 0.0 ? 0.0 : kNoEntry;
    const double h = glm::dot(u, w);
    const double q = glm::dot(w, w) - c.radius_m * c.radius_m;
    const double discriminant = h * h - a * q;
    if (c.side == SphereSide::outside) {
        if (q <= 0.0) return 0.0;                             // starts inside the ball
        if (discriminant < 0.0 || h >= 0.0) return kNoEntry;  // misses, or moves away
        // Smaller root, in the cancellation-free form q / (-h + sqrt(disc)).
        const double t = q / (-h + std::sqrt(discriminant));
        return t <= 1.0 ? t : kNoEntry;
    }
    if (q >= 0.0) return 0.0;  // starts outside the cavity
    if (gap_m(c, to) >= 0.0) return kNoEntry;
    // Larger root (the exit); disc > 0 since q < 0.
    const double root = std::sqrt(discriminant);
    const double t = h <= 0.0 ? (-h + root) / a : -q / (h + root);
    return t;
}

double ConstraintSet::min_gap_m(const Vec3& x) const noexcept {
    double smallest = std::numeric_limits<double>::infinity();
    for (const auto& plane : planes) smallest = std::min(smallest, gap_m(plane, x));
    for (const auto& sphere : spheres) smallest = std::min(smallest, gap_m(sphere, x));
    return smallest;
}

bool ConstraintSet::project_to_free(Vec3& x, int rounds) const noexcept {
    for (int round = 0; round < rounds; ++round) {
        if (is_free(x)) return true;
        for (const auto& plane : planes) {
            if (gap_m(plane, x) < 0.0) x = project_to_surface(plane, x);
        }
        for (const auto& sphere : spheres) {
            if (gap_m(sphere, x) < 0.0) x = project_to_surface(sphere, x);
        }
    }
    return is_free(x);
}

}  // namespace hapticd::env
