#include "breccia/run/manifest_file.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "breccia/core/interrupt.hpp"
#include "breccia/io/run_folder.hpp"

namespace breccia {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// Rewrites the file in place (rewriting frees the old one's blocks first): for a disk too full
// for a second copy.
void write_in_place(const fs::path& path, const std::string& text) noexcept {
  if (std::FILE* f = std::fopen(path.c_str(), "w")) {
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Through a temporary of this process's own (another process may write the same manifest), and
// only while the file still holds `expected`: the process that owns it may have written its own
// last word since, which this one must not replace.
void write_own_temporary(const fs::path& path, const std::string& text,
                         const std::string& expected) noexcept {
  const fs::path tmp = path.string() + fmt::format(".{}.tmp", static_cast<long>(::getpid()));
  std::error_code ec;
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    out.flush();
    if (!out) {
      fs::remove(tmp, ec);
      return;
    }
  }
  try {
    if (read_text(path) != expected) {
      fs::remove(tmp, ec);
      return;
    }
  } catch (const std::exception&) {
    fs::remove(tmp, ec);
    return;
  }
  fs::rename(tmp, path, ec);
  if (ec) fs::remove(tmp, ec);
}

void mark(json& m, int signal, const fs::path& manifest_path) {
  std::error_code ec;
  const bool checkpointed = fs::exists(manifest_path.parent_path() / "checkpoint.bin", ec);
  m["status"] = "interrupted";
  m["stop_reason"] = signal_mark_reason(signal, checkpointed);
}

}  // namespace

std::string signal_mark_reason(int signal, bool checkpointed) {
  return fmt::format(
      "{} arrived: the run was stopping at its next step with a checkpoint. If the manifest still "
      "says this, the process ended before that (a launcher's kill after its grace time, or a "
      "rank lost): {}",
      signal_name(signal),
      checkpointed ? "`breccia resume` continues from the last complete checkpoint.bin"
                   : "no checkpoint had been written when it arrived (output.checkpoint_interval_s "
                     "sets how often one is), so the run must start again");
}

ManifestFile::ManifestFile(fs::path folder, bool writer)
    : path_(std::move(folder) / "manifest.json"), writer_(writer) {}

void ManifestFile::write(const json& manifest) {
  if (!writer_) return;
  std::lock_guard lock(mutex_);
  write_json(path_, manifest);
  last_ = manifest;
}

void ManifestFile::write_final(const json& manifest) noexcept {
  if (!writer_) return;
  std::lock_guard lock(mutex_);
  try {
    write_json(path_, manifest);
    last_ = manifest;
  } catch (const std::exception&) {
    write_in_place(path_, manifest.dump(2) + "\n");
  }
}

void ManifestFile::mark_signal(int signal) noexcept {
  std::lock_guard lock(mutex_);
  try {
    if (writer_) {
      if (!last_.is_object() || last_.value("status", "") != "running") return;
      json m = last_;
      mark(m, signal, path_);
      write_json(path_, m);
      return;
    }
    // Another rank of a split sample: root's manifest as it is on disk.
    const std::string text = read_text(path_);
    json m = json::parse(text, nullptr, false);
    if (!m.is_object() || m.value("status", "") != "running") return;
    mark(m, signal, path_);
    write_own_temporary(path_, m.dump(2) + "\n", text);
  } catch (const std::exception&) {
    // Nothing more can be said: the run's own stop writes the manifest if it can.
  }
}

SignalWatch::SignalWatch(const std::atomic<bool>* flag, ManifestFile& manifest) {
  if (flag == nullptr) return;
  thread_ = std::thread([this, flag, &manifest] {
    std::unique_lock lock(mutex_);
    while (!done_) {
      if (flag->load()) {
        if (wake_.wait_for(lock, manifest.mark_delay(), [this] { return done_; })) return;
        manifest.mark_signal(interrupt_signal().load());
        return;
      }
      wake_.wait_for(lock, std::chrono::milliseconds(20));
    }
  });
}

SignalWatch::~SignalWatch() {
  {
    std::lock_guard lock(mutex_);
    done_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

}  // namespace breccia
