// Ctrl-C and SIGTERM for the commands a user waits on (`tactile sim`, `tactile sweep`).
//
// While an InterruptScope lives, the first SIGINT or SIGTERM only raises a flag: the
// command stops at its next check (a simulated flight within 0.1 s of simulated time, a
// sweep or a set of trials before it starts the next unit), closes its bags and writes
// what it has, marked `"interrupted": true` (tactile_cli README, "Signals"). A second
// signal means the user will not wait: the default action is restored and the signal
// raised again, so the process ends at once (a sweep's table and summary are rewritten
// after every finished environment, so they survive that too).
#pragma once

#include <stdexcept>

namespace tactile_cli {

class InterruptScope {
 public:
  /// Installs the SIGINT and SIGTERM handlers and clears the flag; the previous
  /// handlers come back when the scope ends. Scopes do not nest (throws std::logic_error).
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
};

/// True once SIGINT or SIGTERM arrived inside an InterruptScope (async-signal-safe flag).
bool interrupt_requested();
/// The first signal that arrived (SIGINT, SIGTERM), 0 if none.
int interrupt_signal();
/// Exit status of a command that a signal ended: 128 + the signal number (130 for Ctrl-C).
int interrupted_exit_status();

}  // namespace tactile_cli
