#pragma once
// The crack catalogue: every crack of a run in the order the engine recorded it. Held in memory,
// or, once a run gives it a file, only its newest records: the older ones are appended to the
// file and read back in order when a reader walks the catalogue. A record is 248 B in memory; a
// million-grain sample that breaks a third of its three million bonds would otherwise hold a
// gigabyte of them, the largest part of a broken sample's memory.
//
// Readers walk it with `for (const CrackRecord& c : catalogue)` or `visit(from, f)` (records
// [from, size()) in order, the file read in chunks); `operator[]` returns a copy, reading one
// record from the file where it lies there. Records never change once recorded.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <memory>
#include <string_view>
#include <vector>

#include "breccia/core/record_file.hpp"
#include "breccia/engine/events.hpp"

namespace breccia {

class CrackCatalogue {
 public:
  // Records kept in memory before they go to the file: 4 MB of records, read and written a
  // chunk at a time (a run reads its catalogue in order).
  static constexpr std::size_t kResidentRecords = std::size_t{1} << 14;
  static constexpr std::size_t kStoredBytes = 224;  // a record in the file (no padding)

  CrackCatalogue() = default;
  CrackCatalogue(CrackCatalogue&& other) noexcept = default;
  CrackCatalogue& operator=(CrackCatalogue&& other) noexcept = default;
  // A copy holds every record in memory and no file (a second writer of one file would corrupt
  // it).
  CrackCatalogue(const CrackCatalogue& other);
  CrackCatalogue& operator=(const CrackCatalogue& other);

  std::size_t size() const noexcept { return spilled() + tail_.size(); }
  bool empty() const noexcept { return size() == 0; }
  void push_back(const CrackRecord& r);
  // Room for `n` more records in memory (capped at the resident records while spilling), taken
  // once so that the in-memory array never reallocates: a growing array briefly holds two
  // copies. Pages are resident only once written.
  void reserve_more(std::size_t n);

  CrackRecord operator[](std::size_t k) const;
  CrackRecord front() const { return (*this)[0]; }
  CrackRecord back() const { return (*this)[size() - 1]; }

  // Calls f(record) for the records [from, size()) in order.
  template <class F>
  void visit(std::size_t from, F&& f) const {
    std::vector<CrackRecord> chunk;
    const std::size_t spilled = file_.count();
    for (std::size_t k = from; k < spilled; k += chunk.size()) {
      read_spilled(k, std::min(spilled - k, kReadChunk), chunk);
      for (const CrackRecord& c : chunk) f(c);
    }
    for (std::size_t k = from > spilled ? from - spilled : 0; k < tail_.size(); ++k) f(tail_[k]);
  }

  // Indexed reads that are fast while the index ascends (the file read a chunk at a time);
  // what operator[] returns is valid until the next call.
  class Reader {
   public:
    explicit Reader(const CrackCatalogue& c) : c_(c) {}
    std::size_t size() const noexcept { return c_.size(); }
    const CrackRecord& operator[](std::size_t k) {
      const std::size_t spilled = c_.spilled();
      if (k >= spilled) return c_.tail_[k - spilled];
      if (k < begin_ || k >= begin_ + chunk_.size()) {
        begin_ = k;
        c_.read_spilled(k, std::min(spilled - k, kReadChunk), chunk_);
      }
      return chunk_[k - begin_];
    }

   private:
    const CrackCatalogue& c_;
    std::vector<CrackRecord> chunk_;  // spilled records [begin_, ...)
    std::size_t begin_ = 0;
  };
  Reader reader() const { return Reader(*this); }

  // A forward iterator over the records; what it points at is valid until it moves.
  class const_iterator {
   public:
    using value_type = CrackRecord;
    using difference_type = std::ptrdiff_t;
    using reference = const CrackRecord&;
    using pointer = const CrackRecord*;
    using iterator_category = std::forward_iterator_tag;
    const_iterator() = default;
    const_iterator(const CrackCatalogue* c, std::size_t k);
    reference operator*() const;
    pointer operator->() const { return &**this; }
    const_iterator& operator++();
    const_iterator operator++(int) {
      const_iterator old = *this;
      ++*this;
      return old;
    }
    bool operator==(const const_iterator& o) const noexcept { return k_ == o.k_; }

   private:
    const CrackCatalogue* c_ = nullptr;
    std::size_t k_ = 0, chunk_begin_ = 0;
    std::shared_ptr<std::vector<CrackRecord>> chunk_;  // spilled records [chunk_begin_, ...)
  };
  const_iterator begin() const { return {this, 0}; }
  const_iterator end() const { return {this, size()}; }

  // From now on records beyond `resident` go to `file` (created, or emptied). Records already
  // held move there once the resident ones are full.
  void spill_to(const std::filesystem::path& file, std::size_t resident = kResidentRecords);
  bool spilling() const noexcept { return file_.attached(); }
  // Records in the file.
  std::size_t spilled() const noexcept { return file_.count(); }
  // Flushes the file to the disk (a checkpoint refers to the records it holds).
  void sync() const { file_.sync(); }

  // Checkpoints: the records in memory, and the count and hash of those in the file, which
  // stays beside the checkpoint. A catalogue read from a checkpoint whose records were partly in
  // a file has none of them until reattach() opens that file: it checks that the file holds the
  // records the checkpoint counted (their hash), drops any written after the checkpoint, and
  // spills on from there.
  template <class Archive>
  void transfer(Archive& a);
  void reattach(const std::filesystem::path& file, std::size_t resident = kResidentRecords);

 private:
  static constexpr std::size_t kReadChunk = 4096;
  void read_spilled(std::size_t first, std::size_t count, std::vector<CrackRecord>& out) const;
  void spill_tail();
  void read_law_table();
  void keep_room_for_resident();

  std::vector<CrackRecord> tail_;  // records [spilled(), size())
  std::size_t resident_ = 0;       // spill when the tail reaches it (while spilling)
  RecordFile file_{"crack catalogue", kStoredBytes};
  std::vector<std::string_view> laws_;  // law of each code in the file (registry order)
};

}  // namespace breccia
