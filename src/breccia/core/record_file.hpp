#pragma once
// Records on disk for logs that outgrow memory: an append-only file of fixed-size records after a
// header (magic, format, record size, the log's name and what its owner adds: the crack
// catalogue's table of law names), with the FNV-1a hash of the records as written. A checkpoint
// keeps the count and hash of the records in the file; reattach() checks that the file still holds
// them and drops any written after the checkpoint.
//
// RecordLog<T> keeps a log of plain records of one type in memory, or, once given a file, only
// its newest records, the older ones in the file (the acoustic-emission monitor's event catalogue
// and crack contexts: a million-grain test makes hundreds of thousands of each).
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace breccia {

// Whole-buffer positional I/O on a file descriptor; errors name the file and `what` it holds.
void write_all(int fd, const void* data, std::size_t bytes, std::uint64_t offset,
               const std::filesystem::path& file, std::string_view what);
void read_all(int fd, void* data, std::size_t bytes, std::uint64_t offset,
              const std::filesystem::path& file, std::string_view what);
// "cannot <doing> the <what>: <reason> (<file>)" for the last error (errno).
std::string io_failure(const std::filesystem::path& file, const char* doing, std::string_view what);

class RecordFile {
 public:
  // `what` names the log in the header and in errors ("AE event log"); `record_bytes` is the
  // size of one record.
  RecordFile(std::string_view what, std::size_t record_bytes);
  ~RecordFile();
  RecordFile(RecordFile&& other) noexcept;
  RecordFile& operator=(RecordFile&& other) noexcept;
  RecordFile(const RecordFile&) = delete;
  RecordFile& operator=(const RecordFile&) = delete;

  bool attached() const noexcept { return fd_ >= 0; }
  std::size_t count() const noexcept { return count_; }  // records in the file
  const std::filesystem::path& path() const noexcept { return file_; }
  // Creates (or empties) `file` and writes the header, with `extra` (the owner's) at its end.
  void create(const std::filesystem::path& file, std::string_view extra = {});
  // The owner's part of the header, as written or as read by reattach().
  const std::string& extra() const noexcept { return extra_; }
  void append(const void* records, std::size_t n);
  void read(std::size_t first, std::size_t n, void* out) const;
  void sync() const;  // to the disk: a checkpoint refers to the records written
  // A checkpoint's view of the file: the records it holds and their hash.
  template <class Archive>
  void transfer(Archive& a) {
    if constexpr (!Archive::reading) sync();
    a.value(count_);
    a.value(hash_);
    if constexpr (Archive::reading) detach();
  }
  // Opens the file a checkpoint counted records in: checks its header and the hash of those
  // records, and drops any written after them. With none counted, a missing file is created
  // with `extra` in its header.
  void reattach(const std::filesystem::path& file, std::string_view extra = {});
  void detach() noexcept;

 private:
  std::string fixed_header() const;
  void read_header();
  std::uint64_t hash_of_records(std::size_t n) const;

  std::string what_;
  std::size_t record_bytes_ = 0;
  int fd_ = -1;
  std::filesystem::path file_;
  std::uint64_t count_ = 0;
  std::uint64_t hash_ = 0;    // FNV-1a of the records in the file
  std::uint64_t header_ = 0;  // bytes before the first record
  std::string extra_;
};

template <class T>
class RecordLog {
  static_assert(std::is_trivially_copyable_v<T>, "a record log holds plain records");

 public:
  explicit RecordLog(std::string_view what) : file_(what, sizeof(T)) {}

  std::size_t size() const noexcept { return file_.count() + tail_.size(); }
  bool empty() const noexcept { return size() == 0; }
  void push_back(const T& r) {
    if (file_.attached() && tail_.size() >= resident_) spill_tail();
    tail_.push_back(r);
  }
  // Records [from, size()) in order, the file read a chunk at a time.
  template <class F>
  void visit(std::size_t from, F&& f) const {
    std::vector<T> chunk;
    for (std::size_t k = from; k < file_.count(); k += chunk.size()) {
      chunk.resize(std::min<std::size_t>(file_.count() - k, kReadChunk));
      file_.read(k, chunk.size(), chunk.data());
      for (const T& r : chunk) f(r);
    }
    const std::size_t spilled = file_.count();
    for (std::size_t k = from > spilled ? from - spilled : 0; k < tail_.size(); ++k) f(tail_[k]);
  }
  std::vector<T> all() const {
    std::vector<T> out;
    out.reserve(size());
    visit(0, [&](const T& r) { out.push_back(r); });
    return out;
  }

  // From now on records beyond the newest `resident` go to `file` (created, or emptied).
  void spill_to(const std::filesystem::path& file, std::size_t resident) {
    file_.create(file);
    resident_ = std::max<std::size_t>(resident, 1);
    if (tail_.size() >= resident_) spill_tail();
  }
  // After a restore: the file the checkpoint counted records in (RecordFile::reattach).
  void reattach(const std::filesystem::path& file, std::size_t resident) {
    file_.reattach(file);
    resident_ = std::max<std::size_t>(resident, 1);
  }
  bool spilling() const noexcept { return file_.attached(); }
  std::size_t spilled() const noexcept { return file_.count(); }

  // Checkpoints: the records in memory, the count and hash of those in the file.
  template <class Archive>
  void transfer(Archive& a) {
    file_.transfer(a);
    a.vector(tail_);
  }

 private:
  static constexpr std::size_t kReadChunk = 4096;
  void spill_tail() {
    file_.append(tail_.data(), tail_.size());
    tail_.clear();
  }
  RecordFile file_;
  std::vector<T> tail_;  // records [file_.count(), size())
  std::size_t resident_ = 1;
};

}  // namespace breccia
