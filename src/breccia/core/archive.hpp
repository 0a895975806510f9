#pragma once
// A minimal binary archive for checkpoints: plain values and vectors of trivially copyable types
// are written as raw bytes in this machine's byte order, strings with their length. A checkpoint
// is read back by the same build of Breccia on the same kind of machine (the header records both),
// which is what restarting a test needs; it is not an exchange format.
//
// A type written raw has no padding: padding bytes hold whatever the memory held before, so the
// same state would give different files from run to run (and from rank to rank). The check is at
// compile time: `raw_bytes_are_values<T>()` reads every byte of a default T in a constant
// expression, which the compiler refuses ("accessing uninitialized array element", from a
// static_assert below) where a byte is padding or a member has no initialiser. Such a type fills
// its holes with named members (a `std::uint8_t unused[k]{}`), widens a member or orders its
// members so that none is needed. (GCC 12's __builtin_clear_padding misplaces the bytes it clears
// in some structs with arrays of structs, so padding cannot be cleared when writing instead.)
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <istream>
#include <ostream>
#include <string>
#include <type_traits>
#include <vector>

#include "breccia/core/error.hpp"

namespace breccia {

// A type holding a pointer cannot be read in a constant expression; one that is written raw all
// the same (the pointer blanked, restored on reading) checks its layout beside the code that
// writes it and says so by specialising this to true.
template <class T>
inline constexpr bool layout_checked_beside_it = false;

// True when every byte of a default T is a member's value (no padding, no member left without an
// initialiser); otherwise not a constant expression, so a static_assert on it fails to compile.
template <class T>
consteval bool raw_bytes_are_values() {
  if constexpr (layout_checked_beside_it<T>) {
    return true;
  } else {
    const auto bytes = std::bit_cast<std::array<unsigned char, sizeof(T)>>(T{});
    unsigned read = 0;
    for (const unsigned char b : bytes) read |= b;
    return read <= 0xffu;
  }
}

// Both archives offer the same calls (value, vector, string, label, sized), so that one template
// field list serves writing and reading (`reading` tells them apart where they must differ).
class ArchiveWriter {
 public:
  static constexpr bool reading = false;
  explicit ArchiveWriter(std::ostream& out) : out_(out) {}

  template <class T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>, "only plain data is written raw");
    static_assert(raw_bytes_are_values<T>(), "a type written raw has no padding (see above)");
    out_.write(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  template <class T>
  void vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>, "only plain data is written raw");
    static_assert(raw_bytes_are_values<T>(), "a type written raw has no padding (see above)");
    value(static_cast<std::uint64_t>(v.size()));
    if (!v.empty())
      out_.write(reinterpret_cast<const char*>(v.data()),
                 static_cast<std::streamsize>(v.size() * sizeof(T)));
  }
  void string(const std::string& s) {
    value(static_cast<std::uint64_t>(s.size()));
    out_.write(s.data(), static_cast<std::streamsize>(s.size()));
  }
  // The element count of a container whose elements follow one by one.
  template <class Container>
  void sized(Container& c, std::size_t /*min_bytes_each*/) {
    value(static_cast<std::uint64_t>(c.size()));
  }
  // A section label, checked on reading: a mismatch says where the layouts diverge.
  void label(const char* name) { string(name); }
  std::string where() const { return "checkpoint being written"; }
  bool good() const { return static_cast<bool>(out_); }

 private:
  std::ostream& out_;
};

class ArchiveReader {
 public:
  static constexpr bool reading = true;
  // `where` names the file in error messages.
  ArchiveReader(std::istream& in, std::string where) : in_(in), where_(std::move(where)) {
    const auto here = in_.tellg();
    in_.seekg(0, std::ios::end);
    size_ = static_cast<std::uint64_t>(in_.tellg());
    in_.seekg(here);
  }

  template <class T>
  void value(T& v) {
    static_assert(std::is_trivially_copyable_v<T>, "only plain data is read raw");
    read(reinterpret_cast<char*>(&v), sizeof(T));
  }
  template <class T>
  T get() {
    T v{};
    value(v);
    return v;
  }
  template <class T>
  void vector(std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>, "only plain data is read raw");
    const std::uint64_t n = length(sizeof(T));
    v.resize(n);
    if (n) read(reinterpret_cast<char*>(v.data()), n * sizeof(T));
  }
  void string(std::string& s) {
    const std::uint64_t n = length(1);
    s.resize(n);
    if (n) read(s.data(), n);
  }
  std::string string() {
    std::string s;
    string(s);
    return s;
  }
  void label(const char* name) {
    const std::string got = string();
    if (got != name)
      throw InputError(where_, "section", got,
                       std::string("expected section '") + name +
                           "': the checkpoint was written by a different layout");
  }
  // Reads an element count and resizes `c`; each element takes at least `min_bytes_each` bytes
  // in the file, so a corrupt count cannot trigger a huge allocation.
  template <class Container>
  void sized(Container& c, std::size_t min_bytes_each) {
    c.resize(length(min_bytes_each));
  }
  const std::string& where() const { return where_; }

 private:
  // A length prefix, refused when the bytes it announces are not in the file (a corrupt or
  // truncated checkpoint must not trigger a huge allocation).
  std::uint64_t length(std::size_t element) {
    const std::uint64_t n = get<std::uint64_t>();
    const auto pos = static_cast<std::uint64_t>(in_.tellg());
    if (element != 0 && n > (size_ - pos) / element)
      throw InputError(where_, "length", std::to_string(n),
                       "larger than the rest of the file: the checkpoint is truncated or corrupt");
    return n;
  }
  void read(char* p, std::size_t n) {
    in_.read(p, static_cast<std::streamsize>(n));
    if (static_cast<std::size_t>(in_.gcount()) != n)
      throw InputError(where_, "data", "end of file",
                       "the checkpoint is truncated (was it written completely?)");
  }

  std::istream& in_;
  std::string where_;
  std::uint64_t size_ = 0;
};

}  // namespace breccia
