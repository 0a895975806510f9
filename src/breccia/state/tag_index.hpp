#pragma once
// From a particle's tag to its index in the store. Samples number their grains 0..N or 1..N
// nearly always, so tags below twice the count live in a plain table (4 bytes per tag); others
// (a file with tags in the billions) go to a hash map. A hash map for every grain cost about 60
// bytes per particle, a sixth of the whole particle state.
#include <cstdint>
#include <limits>
#include <optional>
#include <unordered_map>
#include <vector>

namespace breccia {

class TagIndex {
 public:
  static constexpr std::uint32_t kAbsent = std::numeric_limits<std::uint32_t>::max();

  void clear() {
    dense_.clear();
    sparse_.clear();
    count_ = 0;
  }
  std::size_t size() const noexcept { return count_; }
  // Room for tags 0..n-1 in the table.
  void reserve(std::size_t n) { dense_.reserve(n); }
  bool contains(std::uint64_t tag) const { return find(tag).has_value(); }
  std::optional<std::size_t> find(std::uint64_t tag) const {
    if (tag < dense_.size()) {
      if (dense_[tag] == kAbsent) return std::nullopt;
      return dense_[tag];
    }
    const auto it = sparse_.find(tag);
    if (it == sparse_.end()) return std::nullopt;
    return it->second;
  }
  // Records `tag` at `index` (the caller has checked that the tag is new).
  void insert(std::uint64_t tag, std::size_t index) {
    ++count_;
    const auto i = static_cast<std::uint32_t>(index);
    if (tag < dense_limit()) {
      if (tag >= dense_.size()) grow_dense(tag);
      dense_[tag] = i;
    } else {
      sparse_.emplace(tag, i);
    }
  }

 private:
  // The table may reach twice the count (plus a start), so it never costs more than 8 bytes a
  // particle.
  std::uint64_t dense_limit() const noexcept {
    return 2 * static_cast<std::uint64_t>(count_) + 1024;
  }
  void grow_dense(std::uint64_t tag) {
    const std::size_t old = dense_.size();
    dense_.resize(static_cast<std::size_t>(tag) + 1, kAbsent);
    // Tags parked in the map that the table now covers move to it.
    if (sparse_.empty()) return;
    for (auto it = sparse_.begin(); it != sparse_.end();) {
      if (it->first >= old && it->first < dense_.size()) {
        dense_[it->first] = it->second;
        it = sparse_.erase(it);
      } else {
        ++it;
      }
    }
  }

  std::vector<std::uint32_t> dense_;
  std::unordered_map<std::uint64_t, std::uint32_t> sparse_;
  std::size_t count_ = 0;
};

}  // namespace breccia
