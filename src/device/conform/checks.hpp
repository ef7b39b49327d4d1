// The checks of the conformance tester (conformance.hpp), one function each, run in order
// by run_conformance(). Each opens the session it needs and leaves the link drained.
#pragma once

#include "conform_host.hpp"
#include "hapticd/device/conform/conformance.hpp"

namespace hapticd::device::conform {

/// Each check's name and its sections of docs/protocol.md, in the order run_conformance()
/// runs them: the one place they are spelled.
struct CheckId {
    const char* name;
    const char* section;
};
inline constexpr CheckId kHandshake{"handshake", "5.1, 4.2"};
inline constexpr CheckId kVersions{"versions", "3.2, 4.1"};
inline constexpr CheckId kSessions{"sessions", "5.1"};
inline constexpr CheckId kConfigure{"configure", "4.3, 5.4"};
inline constexpr CheckId kCommands{"commands", "4.5, 4.6"};
inline constexpr CheckId kTiming{"timing", "5.2, 5.7"};
inline constexpr CheckId kFrameErrors{"frame_errors", "3.3, 3.4"};
inline constexpr CheckId kMessageErrors{"message_errors", "3.4, 4.10"};
inline constexpr CheckId kWatchdog{"watchdog", "5.4, 5.5"};
inline constexpr CheckId kBye{"bye", "4.8, 5.1"};
inline constexpr CheckId kAllChecks[] = {kHandshake, kVersions, kSessions,    kConfigure,
                                         kCommands,  kTiming,   kFrameErrors, kMessageErrors,
                                         kWatchdog,  kBye};

// session_checks.cpp
CheckResult check_handshake(ConformHost& host, std::optional<protocol::Identity>& identity);
CheckResult check_versions(ConformHost& host, const protocol::Identity& identity);
CheckResult check_sessions(ConformHost& host);
CheckResult check_configure(ConformHost& host, const protocol::Identity& identity);
CheckResult check_bye(ConformHost& host);

// exchange_checks.cpp
CheckResult check_commands(ConformHost& host, const protocol::Identity& identity);
CheckResult check_timing(ConformHost& host, const protocol::Identity& identity);
CheckResult check_frame_errors(ConformHost& host);
CheckResult check_message_errors(ConformHost& host, const protocol::Identity& identity);
CheckResult check_watchdog(ConformHost& host, const protocol::Identity& identity);

/// The result of a check from its finding: pass with `evidence`, or fail with the finding.
CheckResult verdict(const CheckId& check, const Finding& finding, std::string evidence);

}  // namespace hapticd::device::conform
