#pragma once
// manifest.json of a run in progress, and what it says the moment a signal arrives.
//
// A signal stops a run at its next step with a checkpoint, and the manifest then says
// "interrupted". A launcher may not wait that long: mpirun passes SIGTERM and SIGINT on to its
// ranks and kills them a set time later (Open MPI's odls_base_sigkill_timeout, 1 s by default),
// srun after its KillWait, and a rank killed outright makes mpirun end the others the same way.
// So a watcher thread marks the manifest at once: "interrupted", the signal, and that the last
// complete checkpoint is what a resume continues from. The run's own stop rewrites it.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

namespace breccia {

class ManifestFile {
 public:
  // `folder`: the run folder. `writer`: this process writes the manifest (one process, or the
  // root of a split sample); the other ranks of a split sample only mark it when a signal comes
  // (their root may be the rank that was killed).
  ManifestFile(std::filesystem::path folder, bool writer);

  // Writes it whole (atomically) and keeps it as the text a signal marks (the writer only).
  void write(const nlohmann::json& manifest);
  // The same at a failure, perhaps of a full disk: never throws (the run's own error is the one
  // to report), and rewrites in place when a whole new file cannot be written.
  void write_final(const nlohmann::json& manifest) noexcept;
  // A signal (its number) reached the process: a manifest that still says "running" says at once
  // that the run is stopping, in case the process ends before it can. Safe beside write().
  void mark_signal(int signal) noexcept;

  const std::filesystem::path& path() const noexcept { return path_; }
  // How long after the signal mark_signal should wait: none for the writer; for the other ranks,
  // long enough that a living root has marked its manifest first, well within a launcher's grace.
  std::chrono::milliseconds mark_delay() const noexcept {
    return std::chrono::milliseconds(writer_ ? 0 : 300);
  }

 private:
  std::filesystem::path path_;
  bool writer_;
  std::mutex mutex_;
  nlohmann::json last_;
};

// The stop_reason a signal's mark gives a manifest; `checkpointed`: the folder then held a
// checkpoint.bin.
std::string signal_mark_reason(int signal, bool checkpointed);

// While it lives, a thread that calls `manifest.mark_signal` once `flag` is set (a signal handler
// cannot write files). It polls every 20 ms: nothing in the run's loop waits for it.
class SignalWatch {
 public:
  SignalWatch(const std::atomic<bool>* flag, ManifestFile& manifest);
  ~SignalWatch();
  SignalWatch(const SignalWatch&) = delete;
  SignalWatch& operator=(const SignalWatch&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;
};

}  // namespace breccia
