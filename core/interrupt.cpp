// SIGINT / SIGTERM handling (core/interrupt.hpp).
#include "core/interrupt.hpp"

#include <csignal>

namespace mpsfsi {

namespace {

volatile std::sig_atomic_t received = 0;

extern "C" void on_interrupt(const int signo) {
  if (received != 0) {  // the second signal: stop at once, with the default action of that signal
    std::signal(signo, SIG_DFL);
    std::raise(signo);
    return;
  }
  received = signo;
}

}  // namespace

void install_interrupt_handlers() {
  struct sigaction action = {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // blocking calls (MPI, file writes) go on; the run loop reads the flag
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int interrupt_signal() { return static_cast<int>(received); }

const char* signal_name(const int signo) {
  switch (signo) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    default: return "a signal";
  }
}

}  // namespace mpsfsi
