#pragma once
// Plain values packed into and read from the byte strings that ranks exchange (core/ranks.hpp):
// the same binary on every rank, so a value's bytes are its bytes everywhere.
#include <cstddef>
#include <cstring>
#include <string>
#include <type_traits>

namespace breccia::bytes {

template <class T>
void put(std::string& out, const T& v) {
  static_assert(std::is_trivially_copyable_v<T>);
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <class T>
void put_range(std::string& out, const T* from, std::size_t count) {
  static_assert(std::is_trivially_copyable_v<T>);
  out.append(reinterpret_cast<const char*>(from), count * sizeof(T));
}

// The value at `at`, which moves past it.
template <class T>
T take(const std::string& in, std::size_t& at) {
  static_assert(std::is_trivially_copyable_v<T>);
  T v;
  std::memcpy(&v, in.data() + at, sizeof(T));
  at += sizeof(T);
  return v;
}

template <class T>
void take_range(const std::string& in, std::size_t& at, T* to, std::size_t count) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::memcpy(to, in.data() + at, count * sizeof(T));
  at += count * sizeof(T);
}

}  // namespace breccia::bytes
