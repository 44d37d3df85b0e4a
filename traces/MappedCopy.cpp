#include "traces/MappedCopy.hpp"

#include <setjmp.h>
#include <signal.h>

#include <atomic>
#include <cstring>
#include <mutex>

namespace oit::detail {

namespace {

// The copy in progress on this thread (null: none). Read by the handler,
// which runs on the faulting thread.
thread_local sigjmp_buf* t_copy = nullptr;
struct sigaction g_previous {};

void onSigbus(int sig, siginfo_t* info, void* context) {
  if (sigjmp_buf* jump = t_copy) {
    t_copy = nullptr;
    siglongjmp(*jump, 1);
  }
  // Not raised by a guarded copy: whatever handled SIGBUS before.
  if ((g_previous.sa_flags & SA_SIGINFO) && g_previous.sa_sigaction) {
    g_previous.sa_sigaction(sig, info, context);
  } else if (g_previous.sa_handler != SIG_DFL && g_previous.sa_handler != SIG_IGN) {
    g_previous.sa_handler(sig);
  } else {
    // Returning re-executes the faulting access, which now gets the default action.
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    ::sigaction(SIGBUS, &dfl, nullptr);
  }
}

void installHandler() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction sa {};
    sa.sa_sigaction = onSigbus;
    sa.sa_flags = SA_SIGINFO | SA_NODEFER;  // NODEFER: siglongjmp leaves no SIGBUS blocked
    sigemptyset(&sa.sa_mask);
    ::sigaction(SIGBUS, &sa, &g_previous);
  });
}

}  // namespace

bool copyFromMapping(void* dst, const void* src, size_t n) {
  installHandler();
  sigjmp_buf jump;
  if (sigsetjmp(jump, 1) != 0) return false;
  t_copy = &jump;
  // The compiler must not move the copy's loads across setting or clearing the
  // guard, which only the signal handler reads.
  std::atomic_signal_fence(std::memory_order_seq_cst);
  std::memcpy(dst, src, n);
  std::atomic_signal_fence(std::memory_order_seq_cst);
  t_copy = nullptr;
  return true;
}

}  // namespace oit::detail
