#include "hapticd/env/god_object.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <limits>
#include <utility>

namespace hapticd::env {
namespace {

using Contacts = std::array<PlaneConstraint, GodObject::kMaxContacts>;

constexpr double kMultiplierTolerance = 1e-12;
constexpr double kSingularGram = 1e-12;  // det of the normals' Gram matrix: near-parallel
constexpr double kConverged_m = 1e-12;
constexpr int kShortenings = 4;

bool finite(const Vec3& v) noexcept {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool satisfies(const Contacts& contacts, int count, const Vec3& y) noexcept {
    for (int k = 0; k < count; ++k) {
        if (gap_m(contacts[k], y) < -kContactTolerance_m) return false;
    }
    return true;
}

/// The point nearest `goal` in the intersection of the contact half-spaces, by trying the
/// active sets of one, two and three planes (more are linearly dependent in 3-D) and
/// keeping the KKT points: equality on the set, multipliers >= 0, the rest satisfied.
/// Returns false if none is found (degenerate contacts).
bool nearest_in_contacts(const Contacts& contacts, int count, const Vec3& goal,
                         Vec3& nearest) noexcept {
    if (satisfies(contacts, count, goal)) {
        nearest = goal;
        return true;
    }
    double best_m2 = std::numeric_limits<double>::infinity();
    auto consider = [&](const Vec3& y) {
        const Vec3 step = y - goal;
        const double distance_m2 = glm::dot(step, step);
        if (distance_m2 < best_m2 && satisfies(contacts, count, y)) {
            best_m2 = distance_m2;
            nearest = y;
        }
    };
    // Residual d - n·goal of each contact: how far the goal is on the solid side.
    std::array<double, GodObject::kMaxContacts> residual{};
    for (int i = 0; i < count; ++i) residual[i] = -gap_m(contacts[i], goal);

    for (int i = 0; i < count; ++i) {  // a face
        if (residual[i] < 0.0) continue;
        consider(goal + residual[i] * contacts[i].normal_in_free_space);
    }
    for (int i = 0; i < count; ++i) {  // an edge
        for (int j = i + 1; j < count; ++j) {
            const Vec3& ni = contacts[i].normal_in_free_space;
            const Vec3& nj = contacts[j].normal_in_free_space;
            const double c = glm::dot(ni, nj);
            const double det = 1.0 - c * c;
            if (det < kSingularGram) continue;
            const double li = (residual[i] - c * residual[j]) / det;
            const double lj = (residual[j] - c * residual[i]) / det;
            if (li < -kMultiplierTolerance || lj < -kMultiplierTolerance) continue;
            consider(goal + li * ni + lj * nj);
        }
    }
    for (int i = 0; i < count; ++i) {  // a corner
        for (int j = i + 1; j < count; ++j) {
            for (int k = j + 1; k < count; ++k) {
                const Mat3 normals(contacts[i].normal_in_free_space,
                                   contacts[j].normal_in_free_space,
                                   contacts[k].normal_in_free_space);  // columns
                const double det = glm::determinant(normals);
                if (det * det < kSingularGram) continue;
                // goal + N λ lies on all three planes: Nᵀ N λ = residual.
                const Vec3 r(residual[i], residual[j], residual[k]);
                const Vec3 lambda = glm::inverse(glm::transpose(normals) * normals) * r;
                if (lambda.x < -kMultiplierTolerance || lambda.y < -kMultiplierTolerance ||
                    lambda.z < -kMultiplierTolerance) {
                    continue;
                }
                consider(goal + normals * lambda);
            }
        }
    }
    return best_m2 < std::numeric_limits<double>::infinity();
}

}  // namespace

GodObject::GodObject(ConstraintSet constraints, int axes)
    : constraints_(std::move(constraints)), axes_(std::clamp(axes, 1, 3)) {
    reset(Vec3(0.0));
}

Vec3 GodObject::mask(const Vec3& v) const noexcept {
    Vec3 out = v;
    for (int i = axes_; i < 3; ++i) out[i] = 0.0;
    return out;
}

Vec3 GodObject::step(const Vec3& device_position_m, const Vec3& /*device_velocity_mps*/,
                     const CouplingGains& /*gains*/, double /*period_s*/) noexcept {
    last_iterations_ = 0;
    if (!finite(device_position_m)) return proxy_m_;
    const Vec3 goal = mask(device_position_m);
    Vec3 proxy = proxy_m_;

    for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
        last_iterations_ = iteration + 1;
        // 1. Contacts at the proxy, as tangent half-spaces.
        Contacts contacts;
        int count = 0;
        for (const auto& plane : constraints_.planes) {
            if (count < kMaxContacts && gap_m(plane, proxy) <= kContactTolerance_m) {
                contacts[count++] = plane;
            }
        }
        for (const auto& sphere : constraints_.spheres) {
            if (count < kMaxContacts && gap_m(sphere, proxy) <= kContactTolerance_m) {
                contacts[count++] = tangent_plane(sphere, proxy);
            }
        }
        // 2. The target: nearest the goal within the contacts.
        Vec3 target;
        if (!nearest_in_contacts(contacts, count, goal, target)) break;
        target = mask(target);
        if (glm::length(target - proxy) <= kConverged_m) break;

        // 3. Sweep toward the target; stop at the first surface entered.
        bool moved = false;
        for (int attempt = 0; attempt <= kShortenings && !moved; ++attempt) {
            const Vec3 aim =
                attempt == 0 ? target : proxy + std::ldexp(1.0, -attempt) * (target - proxy);
            double first_t = 1.0;
            int hit_plane = -1;
            int hit_sphere = -1;
            for (std::size_t i = 0; i < constraints_.planes.size(); ++i) {
                const auto& plane = constraints_.planes[i];
                if (gap_m(plane, proxy) <= kContactTolerance_m) continue;  // a contact
                const double t = first_entry(plane, proxy, aim);
                if (t < first_t) {
                    first_t = t;
                    hit_plane = static_cast<int>(i);
                    hit_sphere = -1;
                }
            }
            for (std::size_t i = 0; i < constraints_.spheres.size(); ++i) {
                const auto& sphere = constraints_.spheres[i];
                if (gap_m(sphere, proxy) <= kContactTolerance_m) continue;
                const double t = first_entry(sphere, proxy, aim);
                if (t < first_t) {
                    first_t = t;
                    hit_sphere = static_cast<int>(i);
                    hit_plane = -1;
                }
            }
            const bool hit = hit_plane >= 0 || hit_sphere >= 0;
            Vec3 next = hit ? proxy + first_t * (aim - proxy) : aim;
            if (hit_plane >= 0) next = project_to_surface(constraints_.planes[hit_plane], next);
            if (hit_sphere >= 0) next = project_to_surface(constraints_.spheres[hit_sphere], next);
            // A tangent move leaves a spherical cavity it slides in: back onto its surface.
            for (const auto& sphere : constraints_.spheres) {
                if (sphere.side == SphereSide::inside && gap_m(sphere, next) < 0.0) {
                    next = project_to_surface(sphere, next);
                }
            }
            next = mask(next);
            if (constraints_.is_free(next)) {
                moved = glm::length(next - proxy) > kConverged_m;
                proxy = next;
                if (!moved) attempt = kShortenings;  // no progress possible: stop trying
            }
        }
        if (!moved) break;
    }
    proxy_m_ = proxy;
    return proxy_m_;
}

void GodObject::reset(const Vec3& position_m) noexcept {
    if (!finite(position_m)) return;
    Vec3 start = mask(position_m);
    // Projected into the free space; or, when the scene has no free point near here and the
    // proxy is not free either, the position itself: the best there is.
    if (constraints_.project_to_free(start) || !constraints_.is_free(proxy_m_)) {
        proxy_m_ = mask(start);
    }
}

}  // namespace hapticd::env
