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
#include <sstream>
#include <string>
#include <system_error>

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

// Writes `bytes` to `path` through a temporary file renamed over it once written and closed;
// throws InputError naming `path` (the temporary is removed) when any write fails.
inline void write_file_atomically(const std::filesystem::path& path, const std::string& bytes) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw InputError(path.string(), "", "", "cannot write the file: " + write_failure(errno));
  errno = 0;
  const bool written =
      std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size() && std::fflush(f) == 0;
  const int err = errno;
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed) {
    const int why = err != 0 ? err : errno;
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw InputError(path.string(), "", "", "cannot write the file: " + write_failure(why));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw InputError(path.string(), "", "", "cannot write the file: " + ec.message());
}

}  // namespace breccia
