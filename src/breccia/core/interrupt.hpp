#pragma once
// Ctrl-C and SIGTERM. The command's signal handler sets one process-wide flag (signals are
// process-wide too). The run loop polls it between steps and stops with a checkpoint; the long
// loops before a run folder exists (packing, consolidation) poll it through
// throw_if_interrupted, so that a signal never waits for them to finish.
#include <atomic>
#include <stdexcept>
#include <string>

namespace breccia {

inline std::atomic<bool>& interrupt_flag() noexcept {
  static std::atomic<bool> flag{false};
  return flag;
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
