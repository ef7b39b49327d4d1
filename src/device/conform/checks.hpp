// The checks of the conformance tester (conformance.hpp), one function each, run in order
// by run_conformance(). Each opens the session it needs and leaves the link drained.
#pragma once

#include "conform_host.hpp"
#include "hapticd/device/conform/conformance.hpp"

namespace hapticd::device::conform {

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
CheckResult verdict(const char* name, const char* section, const Finding& finding,
                    std::string evidence);

}  // namespace hapticd::device::conform
