#pragma once
// Ctrl-C and SIGTERM. The command's signal handler sets one process-wide flag (signals are
// process-wide too) and notes which signal it was. The run loop polls the flag between steps and
// stops with a checkpoint; the long loops before a run folder exists (packing, consolidation)
// poll it through throw_if_interrupted, so that a signal never waits for them to finish.
#include <atomic>
#include <csignal>
#include <stdexcept>
#include <string>

namespace breccia {

inline std::atomic<bool>& interrupt_flag() noexcept {
  static std::atomic<bool> flag{false};
  return flag;
}

// The number of the last signal that set the flag (0: none, or the flag was set otherwise).
inline std::atomic<int>& interrupt_signal() noexcept {
  static std::atomic<int> number{0};
  return number;
}

// "SIGTERM", "SIGINT", ... for a message; "a signal" when the number is not known.
inline std::string signal_name(int number) {
  switch (number) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGUSR1:
      return "SIGUSR1";
    default:
      return number > 0 ? "signal " + std::to_string(number) : "a signal";
  }
}

// Thrown when a signal arrives during a stage that has nothing to checkpoint.
class Interrupted : public std::runtime_error {
 public:
  explicit Interrupted(const std::string& stage)
      : std::runtime_error("interrupted by a signal while " + stage) {}
};

inline void throw_if_interrupted(const char* stage) {
  if (interrupt_flag().load(std::memory_order_relaxed)) throw Interrupted(stage);
}

}  // namespace breccia
