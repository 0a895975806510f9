#pragma once
// Recorders: they read the simulation (never change it) and write tables that are flushed as they
// go, so an interrupted run keeps everything recorded up to then.
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "breccia/engine/simulation.hpp"
#include "breccia/observe/recorder.hpp"
#include "breccia/protocol/protocol.hpp"

namespace breccia {

// A CSV file written row by row and flushed on request.
class CsvFile {
 public:
  CsvFile() = default;
  CsvFile(const std::string& path, const std::vector<std::string>& columns);
  // Continues a file written earlier: cut back to its first `bytes` bytes (rows a crashed run
  // wrote after its last checkpoint are dropped), then appended to.
  CsvFile(const std::string& path, std::uint64_t bytes);
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  CsvFile(CsvFile&& o) noexcept : f_(o.f_), path_(std::move(o.path_)) { o.f_ = nullptr; }
  ~CsvFile();
  void write_line(const std::string& line);
  void flush() const;
  // Bytes written so far (after a flush).
  std::uint64_t bytes() const;
  const std::string& path() const { return path_; }

 private:
  std::FILE* f_ = nullptr;
  std::string path_;
};

// history.csv: one row per sample with the axial state, counts and the energy ledger, then the
// test's own columns (Protocol::history_columns).
class HistoryRecorder : public Recorder {
 public:
  static constexpr std::string_view kind = "history";
  static std::unique_ptr<Recorder> create(const RecorderSetup& setup);
  static std::unique_ptr<Recorder> restore(const RecorderSetup& setup, ArchiveReader& a);

  explicit HistoryRecorder(const std::string& path, const std::vector<std::string>& extra = {});
  // Resumes the table of a checkpoint (see save_state).
  HistoryRecorder(const std::string& path, ArchiveReader& a);
  void record(const Simulation& sim, const AxialState& axial,
              const std::vector<double>& extra = {});
  void flush() { csv_.flush(); }

  std::string_view name() const noexcept override { return kind; }
  void at_row(const Simulation& sim, const Protocol&, const RecordedRow& row) override {
    record(sim, row.axial, row.test_values);
    flush();
  }
  void finish(const Simulation&) override { flush(); }
  void save_state(ArchiveWriter& a) const override;
  std::vector<std::string> files() const override { return {"history.csv"}; }

 private:
  CsvFile csv_;
  std::uint64_t cracks_seen_ = 0, tensile_ = 0;  // running count: no rescan of the catalogue
};

// The columns and one row of the crack table (docs/physics.md §4.0 fields).
std::vector<std::string> crack_columns();
std::string crack_row(const CrackRecord& c);

// cracks.csv: one row per broken bond with the fields of docs/physics.md §4.0.
class CrackRecorder : public Recorder {
 public:
  static constexpr std::string_view kind = "crack table";
  static std::unique_ptr<Recorder> create(const RecorderSetup& setup);
  static std::unique_ptr<Recorder> restore(const RecorderSetup& setup, ArchiveReader& a);

  explicit CrackRecorder(const std::string& path);
  CrackRecorder(const std::string& path, ArchiveReader& a);
  // Writes the cracks recorded since the last call.
  void record(const Simulation& sim);
  void flush() { csv_.flush(); }
  std::size_t written() const noexcept { return written_; }

  std::string_view name() const noexcept override { return kind; }
  void at_row(const Simulation& sim, const Protocol&, const RecordedRow&) override {
    record(sim);
    flush();
  }
  void finish(const Simulation& sim) override {
    record(sim);
    flush();
  }
  void save_state(ArchiveWriter& a) const override;
  std::vector<std::string> files() const override { return {"cracks.csv"}; }

 private:
  CsvFile csv_;
  std::uint64_t written_ = 0;
};

}  // namespace breccia
