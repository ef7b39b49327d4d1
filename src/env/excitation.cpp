#include "hapticd/env/excitation.hpp"

#include <cmath>
#include <glm/geometric.hpp>
#include <numbers>
#include <stdexcept>

#include "hapticd/input/range.hpp"

namespace hapticd::env {
namespace {

const ExcitationSettings& validated(const ExcitationSettings& s) {
    if (s.periods < 1 || s.periods > 100'000)
        input::reject_out_of_range("excitation: periods", s.periods, "1..100000");
    if (!(s.fade_s >= 0.0) || !std::isfinite(s.fade_s))
        input::reject_out_of_range("excitation: fade_s", s.fade_s, ">= 0");
    if (!(s.workspace_half_width_m > 0.0) || !std::isfinite(s.workspace_half_width_m)) {
        input::reject_out_of_range("excitation: workspace_half_width_m", s.workspace_half_width_m,
                                   "finite and > 0");
    }
    if (!(s.force_limit_n > 0.0) || !std::isfinite(s.force_limit_n)) {
        input::reject_out_of_range("excitation: force_limit_n", s.force_limit_n, "finite and > 0");
    }
    if (!(s.still_speed_mps >= 0.0) || !std::isfinite(s.still_speed_mps)) {
        input::reject_out_of_range("excitation: still_speed_mps", s.still_speed_mps,
                                   "finite and >= 0");
    }
    if (!(s.still_time_s >= 0.0) || !std::isfinite(s.still_time_s)) {
        input::reject_out_of_range("excitation: still_time_s", s.still_time_s, "finite and >= 0");
    }
    return s;
}

}  // namespace

const char* to_string(ExcitationEnvironment::Phase phase) noexcept {
    switch (phase) {
        case ExcitationEnvironment::Phase::waiting_for_still:
            return "waiting_for_still";
        case ExcitationEnvironment::Phase::running:
            return "running";
        case ExcitationEnvironment::Phase::finished:
            return "finished";
        case ExcitationEnvironment::Phase::left_workspace:
            return "left_workspace";
        case ExcitationEnvironment::Phase::interrupted:
            return "interrupted";
    }
    return "unknown";
}

ExcitationEnvironment::ExcitationEnvironment(const ExcitationSettings& settings)
    : settings_(validated(settings)), signal_(settings.signal) {
    const double rate = settings_.signal.sample_rate_hz;
    fade_samples_ = std::llround(settings_.fade_s * rate);
    samples_ =
        2 * fade_samples_ + settings_.periods * static_cast<std::int64_t>(signal_.period_samples());
    still_ticks_needed_ = std::llround(settings_.still_time_s * rate);
}

double ExcitationEnvironment::envelope(std::int64_t j) const noexcept {
    if (j < 0 || j >= samples_) return 0.0;
    const std::int64_t fade = fade_samples_;
    const double pi = std::numbers::pi;
    if (j < fade) {
        return 0.5 * (1.0 - std::cos(pi * static_cast<double>(j) / static_cast<double>(fade)));
    }
    const std::int64_t fade_out = samples_ - fade;  // F + K L
    if (j >= fade_out) {
        return 0.5 *
               (1.0 + std::cos(pi * static_cast<double>(j - fade_out) / static_cast<double>(fade)));
    }
    return 1.0;
}

Vec3 ExcitationEnvironment::scheduled_force_n(std::int64_t j) const noexcept {
    Vec3 force(0.0);
    const double w = envelope(j);
    if (w == 0.0) return force;
    for (int axis = 0; axis < axes(); ++axis) {
        force[axis] = w * signal_.sample(axis, j - fade_samples_);
    }
    const double norm = glm::length(force);
    if (norm > settings_.force_limit_n) force *= settings_.force_limit_n / norm;
    return force;
}

bool ExcitationEnvironment::inside_workspace(const Vec3& position_m) const noexcept {
    for (int axis = 0; axis < axes(); ++axis) {
        // Written so that NaN counts as outside.
        if (!(std::abs(position_m[axis] - center_m_[axis]) <= settings_.workspace_half_width_m)) {
            return false;
        }
    }
    return true;
}

PenaltyForce ExcitationEnvironment::evaluate(const Vec3& tool_position_m,
                                             const Vec3& /*tool_velocity_mps*/) const noexcept {
    PenaltyForce out;  // zero force, zero Jacobians: a pure source
    if (phase_ != Phase::running || !inside_workspace(tool_position_m)) return out;
    out.force_n = scheduled_force_n(played_);
    return out;
}

void ExcitationEnvironment::commit(const Vec3& tool_position_m,
                                   const Vec3& tool_velocity_mps) noexcept {
    ++ticks_;
    switch (phase_) {
        case Phase::waiting_for_still: {
            bool still = true;
            for (int axis = 0; axis < axes(); ++axis) {
                if (!(std::abs(tool_velocity_mps[axis]) < settings_.still_speed_mps)) still = false;
            }
            still_for_ = still ? still_for_ + 1 : 0;
            if (still_for_ >= still_ticks_needed_) {
                phase_ = Phase::running;
                start_tick_ = ticks_;  // the next tick plays j = 0
                played_ = 0;
                center_m_ = Vec3(0.0);
                for (int axis = 0; axis < axes(); ++axis) center_m_[axis] = tool_position_m[axis];
            }
            break;
        }
        case Phase::running:
            if (!inside_workspace(tool_position_m)) {
                phase_ = Phase::left_workspace;
                exit_position_m_ = tool_position_m;
                break;
            }
            if (++played_ >= samples_) phase_ = Phase::finished;
            break;
        case Phase::finished:
        case Phase::left_workspace:
        case Phase::interrupted:
            break;
    }
}

void ExcitationEnvironment::reset(const Vec3& /*tool_position_m*/) noexcept {
    if (phase_ == Phase::running) {
        phase_ = Phase::interrupted;
    } else if (phase_ == Phase::waiting_for_still) {
        still_for_ = 0;
    }
}

}  // namespace hapticd::env
