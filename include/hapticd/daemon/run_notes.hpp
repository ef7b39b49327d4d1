// The notes of a run (docs/daemon.md, "Telemetry"): a trial marker (`hapticctl mark TEXT`,
// the control socket's `mark`) or a change of the coupling's gains or of the scene, numbered
// from 1 in the order they came. The number goes to the servo loop (LoopInbox::mark), which
// stamps it on every record from its next tick on (the telemetry's `mark` column); the text
// stays here, for the telemetry writers, which put "# mark N: TEXT" before the first line
// that carries N. So the rows between two marks are one trial, at one set of gains, in one
// scene, and a paper's script groups them by `mark`.
//
// Any thread; add() and text() lock a mutex, never on the servo thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace hapticd::daemon {

/// The most notes a run keeps: a mark a second for four hours of trials and then some.
inline constexpr std::uint32_t kMaxRunNotes = 100'000;

class RunNotes {
  public:
    /// Adds `text` (one line: control_socket::mark_text_problem() says nothing against it)
    /// as the next note and calls `publish` with its number while no other add() can run, so
    /// that the numbers reach the loop in order. nullopt when the run holds kMaxRunNotes.
    std::optional<std::uint32_t> add(std::string text,
                                     const std::function<void(std::uint32_t)>& publish);
    /// The text of note `number` (1 to the last added); empty for any other number.
    std::string text(std::uint32_t number) const;

  private:
    mutable std::mutex mutex_;
    std::vector<std::string> texts_;
};

}  // namespace hapticd::daemon
