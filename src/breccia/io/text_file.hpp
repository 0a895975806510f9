#pragma once
// Reading a file the user named: only a regular file is opened (a folder, a FIFO or a device is
// refused by name, never waited on), and a UTF-8 byte-order mark that an editor put in front is
// dropped, so every reader sees the same text.
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

}  // namespace breccia
