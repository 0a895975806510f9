#pragma once
// Reading a file the user named: only a regular file is opened (a folder, a FIFO or a device is
// refused by name, never waited on), and a UTF-8 byte-order mark that an editor put in front is
// dropped, so every reader sees the same text. Writing a file whole or not at all: every write
// is checked (a full disk, a file-size limit), and a file appears under its name only once all
// of it is written.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <streambuf>
#include <string>
#include <system_error>
#include <vector>

#include "breccia/core/checksum.hpp"
#include "breccia/core/error.hpp"

namespace breccia {

// Throws InputError naming `path` and `what` ("the experiment file") unless it is a regular file
// that can be opened.
inline void require_regular_file(const std::string& path, const std::string& what) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status))
    throw InputError(path, "", "", "cannot open " + what + ": no such file");
  if (std::filesystem::is_directory(status))
    throw InputError(path, "", "", "is a folder; expected " + what);
  if (!std::filesystem::is_regular_file(status))
    throw InputError(path, "", "",
                     "is not a regular file (a pipe, socket or device); expected " + what);
}

inline std::string read_text_file(const std::string& path, const std::string& what) {
  require_regular_file(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "", "cannot open " + what);
  std::stringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "", "cannot read " + what);
  std::string text = ss.str();
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
  return text;
}

// Why a write failed, for the message: the system's reason and what usually causes it.
inline std::string write_failure(int err) {
  return std::string(std::strerror(err)) +
         (err == ENOSPC || err == EFBIG || err == EDQUOT
              ? " (the disk is full, or a file-size or quota limit was reached)"
              : "");
}

// A file written through a temporary and renamed over its path once whole, streamed (no copy of
// its bytes in memory, which for a million-grain checkpoint or snapshot would be hundreds of
// megabytes) and hashed on the way (FNV-1a, core/checksum.hpp). Not committed (an exception on
// the way), the temporary goes and the old file stays.
class AtomicFileWriter {
 public:
  // Opens `path`.tmp; throws InputError naming `path` when it cannot.
  explicit AtomicFileWriter(std::filesystem::path path)
      : path_(std::move(path)), tmp_(path_.string() + ".tmp"), buf_(this), out_(&buf_) {
    file_ = std::fopen(tmp_.c_str(), "wb");
    if (!file_)
      throw InputError(path_.string(), "", "", "cannot write the file: " + write_failure(errno));
  }
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  // Not committed (an exception on the way): the temporary goes, the old file stays.
  ~AtomicFileWriter() {
    if (file_) std::fclose(file_);
    if (!committed_) {
      std::error_code ec;
      std::filesystem::remove(tmp_, ec);
    }
  }

  std::ostream& stream() noexcept { return out_; }
  // FNV-1a of every byte written so far.
  std::uint64_t hash() {
    out_.flush();
    return hash_;
  }
  // Flushes, closes and renames the temporary over the path; throws InputError naming the path
  // when any write failed.
  void commit() {
    out_.flush();
    const bool written = out_.good() && error_ == 0 && std::fflush(file_) == 0;
    const int err = error_ != 0 ? error_ : errno;
    const bool closed = std::fclose(file_) == 0;
    file_ = nullptr;
    if (!written || !closed)
      throw InputError(path_.string(), "", "", "cannot write the file: " + write_failure(err));
    std::error_code ec;
    std::filesystem::rename(tmp_, path_, ec);
    if (ec) throw InputError(path_.string(), "", "", "cannot write the file: " + ec.message());
    committed_ = true;
  }

 private:
  // Buffers 1 MiB, hashes it and hands it to the file.
  class Buffer : public std::streambuf {
   public:
    explicit Buffer(AtomicFileWriter* owner) : owner_(owner), data_(1 << 20) {
      setp(data_.data(), data_.data() + data_.size());
    }

   protected:
    int_type overflow(int_type c) override {
      if (!drain()) return traits_type::eof();
      if (!traits_type::eq_int_type(c, traits_type::eof())) {
        *pptr() = traits_type::to_char_type(c);
        pbump(1);
      }
      return traits_type::not_eof(c);
    }
    int sync() override { return drain() ? 0 : -1; }

   private:
    bool drain() {
      const std::size_t n = static_cast<std::size_t>(pptr() - pbase());
      if (n == 0) return true;
      owner_->hash_ = fnv1a64({pbase(), n}, owner_->hash_);
      errno = 0;
      if (std::fwrite(pbase(), 1, n, owner_->file_) != n) {
        owner_->error_ = errno != 0 ? errno : EIO;
        return false;
      }
      setp(data_.data(), data_.data() + data_.size());
      return true;
    }
    AtomicFileWriter* owner_;
    std::vector<char> data_;
  };

  std::filesystem::path path_, tmp_;
  std::FILE* file_ = nullptr;
  std::uint64_t hash_ = fnv1a64({});
  int error_ = 0;
  bool committed_ = false;
  Buffer buf_;
  std::ostream out_;
};

// Writes `bytes` to `path` through a temporary file renamed over it once written and closed;
// throws InputError naming `path` (the temporary is removed) when any write fails.
inline void write_file_atomically(const std::filesystem::path& path, const std::string& bytes) {
  AtomicFileWriter file(path);
  file.stream().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  file.commit();
}

}  // namespace breccia
