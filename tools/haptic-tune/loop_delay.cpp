#include "loop_delay.hpp"

#include <iostream>

#include "autotune_error.hpp"
#include "cli_common.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tools {

const char* to_string(DelaySource source) {
    switch (source) {
        case DelaySource::option:
            return "--delay";
        case DelaySource::measured:
            return "measured";
        case DelaySource::config:
            return "config";
        case DelaySource::none:
            break;
    }
    return "none";
}

std::string periods_text(double delay_s, double rate_hz) {
    const double periods = delay_s * rate_hz;
    return number_text(periods, 4) + (periods == 1.0 ? " period" : " periods");
}

namespace {

LoopDelay find_sizing_delay(std::optional<double> delay_option, bool from_log,
                            const daemon::Config& config, bool lockstep) {
    LoopDelay out;
    const double rate_hz = config.servo.rate_hz;
    const bool stated = config.device.model.delay_stated;
    if (delay_option) {
        out.delay_s = *delay_option;
        out.source = DelaySource::option;
        out.note = "loop delay " + number_text(out.delay_s) + " s (" +
                   periods_text(out.delay_s, rate_hz) + "): --delay";
        return out;
    }
    if (from_log) {
        out.delay_s = config.device.model.delay_s;
        out.source = stated ? DelaySource::config : DelaySource::none;
        out.note = stated ? "loop delay " + number_text(out.delay_s) + " s (" +
                                periods_text(out.delay_s, rate_hz) +
                                "): [device.model] delay (not measured: from --log there is no "
                                "device to run)"
                          : "loop delay 0: not measured (from --log there is no device to run) "
                            "and neither --delay nor [device.model] delay states one";
        return out;
    }
    // Measure it, as haptic-tune diag does: zero force, the daemon's schedule.
    daemon::DiagOptions diag;
    diag.duration_s = kDelayMeasurementS;
    diag.lockstep = lockstep;
    std::cerr << "haptic-tune: autotune: measuring the loop delay over the link ("
              << kDelayMeasurementS << " s at zero force)\n";
    try {
        out.measurement = daemon::run_link_diag(config, diag, std::cerr);
    } catch (const std::exception& e) {
        throw AutotuneError(std::string("cannot measure the loop delay: device error: ") +
                            e.what() + " (give --delay SECONDS to skip the measurement)");
    }
    const daemon::DiagReport& m = *out.measurement;
    std::string why_not;
    if (!m.delay_measured) {
        why_not = m.delay_missing;
    } else if (m.bad_ack_command + m.bad_ack_time + m.acausal + m.clock_backwards > 0) {
        why_not =
            "the device's acknowledgements or timestamps contradicted themselves (" +
            std::to_string(m.bad_ack_command + m.bad_ack_time + m.acausal + m.clock_backwards) +
            " times; haptic-tune diag shows which)";
    } else if (!(m.recommended_delay_s * rate_hz < tune::kMaxDelayPeriods)) {
        why_not = "the measured p99 " + number_text(m.delay_s.p99) +
                  " s is beyond the stability models' range (under 10 periods)";
    }
    if (why_not.empty()) {
        out.delay_s = m.recommended_delay_s;
        out.source = DelaySource::measured;
        out.note = "loop delay measured over the link (" + std::to_string(m.delay_commands) +
                   " commands at zero force): p50 " + periods_text(m.delay_s.p50, rate_hz) +
                   ", p99 " + periods_text(m.delay_s.p99, rate_hz) + "; sized for " +
                   number_text(out.delay_s) + " s (" + periods_text(out.delay_s, rate_hz) +
                   ": the p99 rounded up to the next 0.05 period)";
        if (stated && config.device.model.delay_s != out.delay_s) {
            out.note +=
                ", replacing [device.model] delay = " + number_text(config.device.model.delay_s);
        }
        std::cerr << "haptic-tune: autotune: " << out.note << '\n';  // before the long run
        return out;
    }
    if (stated) {
        out.delay_s = config.device.model.delay_s;
        out.source = DelaySource::config;
        out.note = "loop delay " + number_text(out.delay_s) + " s (" +
                   periods_text(out.delay_s, rate_hz) +
                   "): [device.model] delay; not measured: " + why_not;
        std::cerr << "haptic-tune: autotune: " << out.note << '\n';
        return out;
    }
    throw AutotuneError("the loop delay is unknown: it could not be measured over the link (" +
                        why_not +
                        "), and neither --delay nor [device.model] delay states it. Gains sized "
                        "for no delay would be past the limit of a real loop; give --delay "
                        "SECONDS (docs/autotune.md, docs/stability-models.md); nothing was "
                        "written");
}

}  // namespace

LoopDelay find_loop_delay(std::optional<double> delay_option, bool from_log,
                          const daemon::Config& config, bool lockstep) {
    LoopDelay out = find_sizing_delay(delay_option, from_log, config, lockstep);
    out.identification_delay_s =
        out.source == DelaySource::measured ? out.measurement->delay_s.p50 : out.delay_s;
    return out;
}

}  // namespace hapticd::tools
