// Stopping a run cleanly on SIGINT (Ctrl-C) and SIGTERM (batch schedulers, mpirun): the first signal only
// sets a flag, which the run loop reads after each step (every rank alike, coupling/simulation.cpp), so the
// run ends at the end of that step with a frame, a checkpoint and its log. A second signal ends the process at
// once, as if no handler were installed.
#pragma once

namespace mpsfsi {

/// Installs the handlers of SIGINT and SIGTERM (for the life of the process; idempotent).
void install_interrupt_handlers();

/// The number of the first signal received since install_interrupt_handlers (SIGINT or SIGTERM), else 0.
int interrupt_signal();

/// The name of a signal number: "SIGINT", "SIGTERM", else "a signal".
const char* signal_name(int signo);

}  // namespace mpsfsi
