#include "breccia/core/record_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

#include "breccia/core/checksum.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/text_file.hpp"

namespace breccia {

namespace {

constexpr char kMagic[] = "breccia record log";
constexpr std::uint32_t kFileFormat = 1;
constexpr std::uint64_t kHashSeed = 1469598103934665603ull;  // FNV-1a of no bytes
constexpr std::size_t kHashChunk = std::size_t{1} << 20;     // bytes read at a time
constexpr std::uint64_t kMaxExtra = std::uint64_t{1} << 20;  // an owner's header part, at most

}  // namespace

std::string io_failure(const std::filesystem::path& file, const char* doing,
                       std::string_view what) {
  return std::string("cannot ") + doing + " the " + std::string(what) + ": " +
         write_failure(errno) + " (" + file.string() + ")";
}

void write_all(int fd, const void* data, std::size_t bytes, std::uint64_t offset,
               const std::filesystem::path& file, std::string_view what) {
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::pwrite(fd, p, bytes, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw InputError(file.string(), "", "", io_failure(file, "write", what));
    p += n;
    bytes -= static_cast<std::size_t>(n);
    offset += static_cast<std::uint64_t>(n);
  }
}

void read_all(int fd, void* data, std::size_t bytes, std::uint64_t offset,
              const std::filesystem::path& file, std::string_view what) {
  char* p = static_cast<char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::pread(fd, p, bytes, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(file.string(), "", "", io_failure(file, "read", what));
    if (n == 0)
      throw InputError(file.string(), "", "(shorter than its records)",
                       "the " + std::string(what) + " was cut short: it no longer matches the run");
    p += n;
    bytes -= static_cast<std::size_t>(n);
    offset += static_cast<std::uint64_t>(n);
  }
}

RecordFile::RecordFile(std::string_view what, std::size_t record_bytes)
    : what_(what), record_bytes_(record_bytes), hash_(kHashSeed) {}

RecordFile::~RecordFile() {
  detach();
}

RecordFile::RecordFile(RecordFile&& o) noexcept {
  *this = std::move(o);
}

RecordFile& RecordFile::operator=(RecordFile&& o) noexcept {
  if (this == &o) return *this;
  detach();
  what_ = std::move(o.what_);
  record_bytes_ = o.record_bytes_;
  fd_ = std::exchange(o.fd_, -1);
  file_ = std::move(o.file_);
  count_ = std::exchange(o.count_, 0);
  hash_ = std::exchange(o.hash_, kHashSeed);
  header_ = std::exchange(o.header_, 0);
  extra_ = std::move(o.extra_);
  return *this;
}

void RecordFile::detach() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

// Magic, format, record size and the log's name; then the size of the owner's part and that part.
std::string RecordFile::fixed_header() const {
  std::string h(kMagic, sizeof(kMagic));
  auto put = [&](std::uint64_t v) { h.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(kFileFormat);
  put(record_bytes_);
  put(what_.size());
  h.append(what_);
  return h;
}

void RecordFile::create(const std::filesystem::path& file, std::string_view extra) {
  if (fd_ >= 0 || count_ > 0)
    throw InternalError("the " + what_ + " already has a file: " + file_.string());
  const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(file.string(), "", "", io_failure(file, "create", what_));
  fd_ = fd;
  file_ = file;
  extra_ = extra;
  std::string h = fixed_header();
  const std::uint64_t extra_bytes = extra_.size();
  h.append(reinterpret_cast<const char*>(&extra_bytes), sizeof extra_bytes);
  h.append(extra_);
  write_all(fd_, h.data(), h.size(), 0, file_, what_);
  header_ = h.size();
  hash_ = kHashSeed;
}

void RecordFile::append(const void* records, std::size_t n) {
  const std::size_t bytes = n * record_bytes_;
  write_all(fd_, records, bytes, header_ + count_ * record_bytes_, file_, what_);
  hash_ = fnv1a64({static_cast<const char*>(records), bytes}, hash_);
  count_ += n;
}

void RecordFile::read(std::size_t first, std::size_t n, void* out) const {
  if (fd_ < 0)
    throw InternalError("the " + what_ + "'s file is not attached (reattach after restore)");
  read_all(fd_, out, n * record_bytes_, header_ + first * record_bytes_, file_, what_);
}

void RecordFile::sync() const {
  if (fd_ >= 0 && ::fdatasync(fd_) != 0)
    throw InputError(file_.string(), "", "", io_failure(file_, "flush", what_));
}

// Checks the fixed part of the open file's header and reads the owner's part.
void RecordFile::read_header() {
  const std::string want = fixed_header();
  std::string got(want.size(), '\0');
  std::uint64_t extra_bytes = 0;
  try {
    read_all(fd_, got.data(), got.size(), 0, file_, what_);
    read_all(fd_, &extra_bytes, sizeof extra_bytes, want.size(), file_, what_);
  } catch (const InputError&) {
    got.clear();
  }
  if (got != want || extra_bytes > kMaxExtra)
    throw InputError(file_.string(), "header", got.empty() ? "(too short)" : "(differs)",
                     "not a " + what_ + " this build of Breccia wrote");
  extra_.assign(static_cast<std::size_t>(extra_bytes), '\0');
  read_all(fd_, extra_.data(), extra_.size(), want.size() + sizeof extra_bytes, file_, what_);
  header_ = want.size() + sizeof extra_bytes + extra_bytes;
}

std::uint64_t RecordFile::hash_of_records(std::size_t n) const {
  std::uint64_t h = kHashSeed;
  std::string chunk;
  const std::uint64_t total = n * record_bytes_;
  for (std::uint64_t at = 0; at < total; at += chunk.size()) {
    chunk.resize(static_cast<std::size_t>(std::min<std::uint64_t>(total - at, kHashChunk)));
    read_all(fd_, chunk.data(), chunk.size(), header_ + at, file_, what_);
    h = fnv1a64(chunk, h);
  }
  return h;
}

void RecordFile::reattach(const std::filesystem::path& file, std::string_view extra) {
  if (fd_ >= 0) throw InternalError("the " + what_ + " already has a file: " + file_.string());
  const int fd = ::open(file.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) {
    if (count_ == 0) return create(file, extra);  // nothing to find in it
    throw InputError(file.string(), "", "(missing)",
                     "the checkpoint's older records of the " + what_ +
                         " are in this file: " + std::string(std::strerror(errno)));
  }
  fd_ = fd;
  file_ = file;
  try {
    read_header();
    if (count_ > 0 && hash_of_records(count_) != hash_)
      throw InputError(file.string(), "", "(records differ)",
                       "the " + what_ + " does not hold the records the checkpoint counted");
    if (::ftruncate(fd_, static_cast<off_t>(header_ + count_ * record_bytes_)) != 0)
      throw InputError(file.string(), "", "", io_failure(file, "truncate", what_));
  } catch (...) {
    detach();
    throw;
  }
}

}  // namespace breccia
