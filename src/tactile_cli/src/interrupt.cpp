#include "tactile_cli/interrupt.hpp"

#include <atomic>
#include <csignal>

namespace tactile_cli {

namespace {

std::atomic<int> g_signal{0};        // first signal received (0: none)
std::atomic<bool> g_active{false};   // an InterruptScope is installed
struct sigaction g_old_int {}, g_old_term {};

extern "C" void on_signal(int sig) {
  int none = 0;
  if (!g_signal.compare_exchange_strong(none, sig)) {
    // Second signal: the user will not wait. Default action, raised again.
    std::signal(sig, SIG_DFL);
    std::raise(sig);
  }
}

}  // namespace

InterruptScope::InterruptScope() {
  if (g_active.exchange(true)) throw std::logic_error("InterruptScope: already installed");
  g_signal = 0;
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, &g_old_int);
  sigaction(SIGTERM, &sa, &g_old_term);
}

InterruptScope::~InterruptScope() {
  sigaction(SIGINT, &g_old_int, nullptr);
  sigaction(SIGTERM, &g_old_term, nullptr);
  g_active = false;
}

bool interrupt_requested() { return g_signal.load() != 0; }
int interrupt_signal() { return g_signal.load(); }
int interrupted_exit_status() { return 128 + (g_signal.load() != 0 ? g_signal.load() : SIGINT); }

}  // namespace tactile_cli
