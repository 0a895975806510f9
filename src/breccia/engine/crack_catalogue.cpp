#include "breccia/engine/crack_catalogue.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include "breccia/core/archive.hpp"
#include "breccia/core/checksum.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/record_file.hpp"
#include "breccia/core/type_list.hpp"
#include "breccia/law/registry.hpp"

namespace breccia {

namespace {

// A record as the file holds it: the law as a code into the file's table of law names (a
// string_view points into this process), no padding.
struct StoredCrack {
  std::uint64_t step;
  double time;
  std::uint64_t bond_tag, id1, id2;
  double R1, R2;
  Vec3 position, normal;
  std::uint32_t law, mode;
  double bond_radius, Fn, Fs, Mt, Mb, sigma, tau, ratio_t, ratio_s;
  BondEnergy energy;
};
static_assert(sizeof(StoredCrack) == 224 && std::is_trivially_copyable_v<StoredCrack>);
static_assert(sizeof(CrackRecord) == 240, "CrackRecord changed: update StoredCrack");

constexpr char kMagic[] = "breccia crack catalogue";
constexpr std::uint32_t kFileFormat = 1;
constexpr std::uint64_t kHashSeed = 1469598103934665603ull;  // FNV-1a of no bytes

// The bond and joint laws of this build, in registry order: the codes of a new file.
std::vector<std::string_view> registered_laws() {
  std::vector<std::string_view> out;
  auto add = [&]<class... Laws>(TypeList<Laws...>) { (out.push_back(Laws::name), ...); };
  add(BondLaws{});
  add(JointLaws{});
  return out;
}

// This build's static name of the law called `name`; throws naming `where` when there is none.
std::string_view registered_law(const std::string& name, const std::string& where) {
  for (std::string_view s : registered_laws())
    if (s == name) return s;
  throw InputError(where, "crack law", name, "not a bond law of this build of Breccia");
}

constexpr std::string_view kWhat = "crack catalogue";

// The file's header: magic, format, record size and the law names the codes stand for.
std::string header_bytes(const std::vector<std::string_view>& laws) {
  std::string h(kMagic, sizeof(kMagic));
  auto put = [&](std::uint32_t v) { h.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(kFileFormat);
  put(sizeof(StoredCrack));
  put(static_cast<std::uint32_t>(laws.size()));
  for (std::string_view name : laws) {
    put(static_cast<std::uint32_t>(name.size()));
    h.append(name);
  }
  return h;
}

}  // namespace

CrackCatalogue::~CrackCatalogue() {
  close();
}

void CrackCatalogue::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

CrackCatalogue::CrackCatalogue(CrackCatalogue&& o) noexcept {
  *this = std::move(o);
}

CrackCatalogue& CrackCatalogue::operator=(CrackCatalogue&& o) noexcept {
  if (this == &o) return *this;
  close();
  tail_ = std::move(o.tail_);
  spilled_ = std::exchange(o.spilled_, 0);
  resident_ = o.resident_;
  fd_ = std::exchange(o.fd_, -1);
  file_ = std::move(o.file_);
  hash_ = std::exchange(o.hash_, 0);
  laws_ = std::move(o.laws_);
  header_ = std::exchange(o.header_, 0);
  return *this;
}

CrackCatalogue::CrackCatalogue(const CrackCatalogue& o) {
  *this = o;
}

CrackCatalogue& CrackCatalogue::operator=(const CrackCatalogue& o) {
  if (this == &o) return *this;
  std::vector<CrackRecord> all;
  all.reserve(o.size());
  o.visit(0, [&](const CrackRecord& c) { all.push_back(c); });
  close();
  tail_ = std::move(all);
  spilled_ = 0;
  resident_ = 0;
  file_.clear();
  hash_ = 0;
  laws_.clear();
  header_ = 0;
  return *this;
}

void CrackCatalogue::push_back(const CrackRecord& r) {
  if (fd_ >= 0 && tail_.size() >= resident_) spill_tail();
  tail_.push_back(r);
}

void CrackCatalogue::reserve_more(std::size_t n) {
  const std::size_t want = tail_.size() + n;
  tail_.reserve(fd_ >= 0 ? std::min(want, resident_) : want);
}

CrackRecord CrackCatalogue::operator[](std::size_t k) const {
  if (k >= spilled_) return tail_[k - spilled_];
  std::vector<CrackRecord> one;
  read_spilled(k, 1, one);
  return one.front();
}

void CrackCatalogue::spill_to(const std::filesystem::path& file, std::size_t resident) {
  if (spilled_ > 0 || fd_ >= 0)
    throw InternalError("the crack catalogue already has a file: " + file_.string());
  const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(file.string(), "", "", io_failure(file, "create", kWhat));
  fd_ = fd;
  file_ = file;
  laws_ = registered_laws();
  const std::string h = header_bytes(laws_);
  write_all(fd_, h.data(), h.size(), 0, file_, kWhat);
  header_ = h.size();
  hash_ = 0;
  resident_ = std::max<std::size_t>(resident, 1);
  keep_room_for_resident();
  if (tail_.size() >= resident_) spill_tail();
}

// The room taken for every possible crack is given back: only the resident records stay.
void CrackCatalogue::keep_room_for_resident() {
  if (tail_.capacity() <= std::max(resident_, tail_.size())) return;
  std::vector<CrackRecord> kept;
  kept.reserve(std::max(resident_, tail_.size()));
  kept.assign(tail_.begin(), tail_.end());
  tail_.swap(kept);
}

void CrackCatalogue::spill_tail() {
  std::vector<StoredCrack> out(tail_.size());
  for (std::size_t k = 0; k < tail_.size(); ++k) {
    const CrackRecord& c = tail_[k];
    std::uint32_t law = 0;
    while (law < laws_.size() && laws_[law] != c.law) ++law;
    if (law == laws_.size())
      throw InputError(file_.string(), "law", std::string(c.law),
                       "not a law of the crack catalogue's file (written by another build)");
    StoredCrack& s = out[k];
    s = {c.step,
         c.time,
         c.bond_tag,
         c.id1,
         c.id2,
         c.R1,
         c.R2,
         c.position,
         c.normal,
         law,
         static_cast<std::uint32_t>(c.mode),
         c.bond_radius,
         c.Fn,
         c.Fs,
         c.Mt,
         c.Mb,
         c.sigma,
         c.tau,
         c.ratio_t,
         c.ratio_s,
         c.energy};
  }
  const std::size_t bytes = out.size() * sizeof(StoredCrack);
  write_all(fd_, out.data(), bytes, header_ + spilled_ * sizeof(StoredCrack), file_, kWhat);
  hash_ = fnv1a64({reinterpret_cast<const char*>(out.data()), bytes},
                  spilled_ == 0 ? kHashSeed : hash_);
  spilled_ += tail_.size();
  tail_.clear();
}

void CrackCatalogue::read_spilled(std::size_t first, std::size_t count,
                                  std::vector<CrackRecord>& out) const {
  if (fd_ < 0)
    throw InternalError("the crack catalogue's file is not attached (reattach after restore)");
  std::vector<StoredCrack> in(count);
  read_all(fd_, in.data(), count * sizeof(StoredCrack), header_ + first * sizeof(StoredCrack),
           file_, kWhat);
  out.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    const StoredCrack& s = in[k];
    if (s.law >= laws_.size() || s.mode > 1)
      throw InputError(file_.string(), "record", std::to_string(first + k),
                       "a damaged record: the crack catalogue no longer matches the run");
    CrackRecord& c = out[k];
    c.step = s.step;
    c.time = s.time;
    c.law = laws_[s.law];
    c.bond_tag = s.bond_tag;
    c.id1 = s.id1;
    c.id2 = s.id2;
    c.R1 = s.R1;
    c.R2 = s.R2;
    c.position = s.position;
    c.normal = s.normal;
    c.mode = static_cast<CrackMode>(s.mode);
    c.bond_radius = s.bond_radius;
    c.Fn = s.Fn;
    c.Fs = s.Fs;
    c.Mt = s.Mt;
    c.Mb = s.Mb;
    c.sigma = s.sigma;
    c.tau = s.tau;
    c.ratio_t = s.ratio_t;
    c.ratio_s = s.ratio_s;
    c.energy = s.energy;
  }
}

void CrackCatalogue::sync() const {
  if (fd_ >= 0 && ::fdatasync(fd_) != 0)
    throw InputError(file_.string(), "", "", io_failure(file_, "flush", kWhat));
}

// Reads the header of the open file: checks its magic, format and record size, and takes its
// table of law names (each a law of this build) as the codes' meanings.
void CrackCatalogue::read_header() {
  const auto mismatch = [&](const std::string& what) {
    return InputError(file_.string(), "header", what,
                      "not a crack catalogue this build of Breccia wrote");
  };
  char magic[sizeof(kMagic)] = {};
  std::uint32_t fixed[3] = {};
  try {
    read_all(fd_, magic, sizeof magic, 0, file_, kWhat);
    read_all(fd_, fixed, sizeof fixed, sizeof magic, file_, kWhat);
  } catch (const InputError&) {
    throw mismatch("(too short)");
  }
  if (std::memcmp(magic, kMagic, sizeof magic) != 0) throw mismatch("(wrong magic)");
  if (fixed[0] != kFileFormat || fixed[1] != sizeof(StoredCrack) || fixed[2] > 64)
    throw mismatch("format " + std::to_string(fixed[0]));
  std::uint64_t at = sizeof magic + sizeof fixed;
  laws_.clear();
  for (std::uint32_t k = 0; k < fixed[2]; ++k) {
    std::uint32_t length = 0;
    read_all(fd_, &length, sizeof length, at, file_, kWhat);
    if (length > 64) throw mismatch("law name of " + std::to_string(length) + " bytes");
    std::string name(length, '\0');
    read_all(fd_, name.data(), length, at + sizeof length, file_, kWhat);
    at += sizeof length + length;
    laws_.push_back(registered_law(name, file_.string()));
  }
  header_ = at;
}

// FNV-1a of the first `count` records in the file.
std::uint64_t CrackCatalogue::hash_of_records(std::size_t count) const {
  std::uint64_t h = kHashSeed;
  std::vector<StoredCrack> chunk;
  for (std::size_t k = 0; k < count; k += chunk.size()) {
    chunk.resize(std::min(count - k, kReadChunk));
    const std::size_t bytes = chunk.size() * sizeof(StoredCrack);
    read_all(fd_, chunk.data(), bytes, header_ + k * sizeof(StoredCrack), file_, kWhat);
    h = fnv1a64({reinterpret_cast<const char*>(chunk.data()), bytes}, h);
  }
  return h;
}

void CrackCatalogue::reattach(const std::filesystem::path& file, std::size_t resident) {
  if (fd_ >= 0) throw InternalError("the crack catalogue already has a file: " + file_.string());
  const int fd = ::open(file.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) {
    if (spilled_ == 0) return spill_to(file, resident);  // nothing to find in it
    throw InputError(file.string(), "", "(missing)",
                     "the checkpoint's older crack records are in this file: " +
                         std::string(std::strerror(errno)));
  }
  fd_ = fd;
  file_ = file;
  resident_ = std::max<std::size_t>(resident, 1);
  try {
    read_header();
    // The records the checkpoint counted, by their hash; any later ones are dropped.
    if (spilled_ > 0 && hash_of_records(spilled_) != hash_)
      throw InputError(file.string(), "", "(records differ)",
                       "the crack catalogue does not hold the records the checkpoint counted");
    if (::ftruncate(fd_, static_cast<off_t>(header_ + spilled_ * sizeof(StoredCrack))) != 0)
      throw InputError(file.string(), "", "", io_failure(file, "truncate", kWhat));
  } catch (...) {
    close();
    throw;
  }
  keep_room_for_resident();
  tail_.reserve(resident_);
}

template <class Archive>
void CrackCatalogue::transfer(Archive& a) {
  if constexpr (!Archive::reading) sync();
  a.value(spilled_);
  a.value(hash_);
  a.sized(tail_, sizeof(CrackRecord));
  for (CrackRecord& c : tail_) {
    std::string name(c.law);
    a.string(name);
    CrackRecord plain = c;
    plain.law = {};  // a pointer into this process: restored from the name
    a.value(plain);
    if constexpr (Archive::reading) {
      c = plain;
      c.law = registered_law(name, a.where());
    }
  }
  if constexpr (Archive::reading) {
    close();
    file_.clear();
    laws_.clear();
  }
}

template void CrackCatalogue::transfer(ArchiveWriter&);
template void CrackCatalogue::transfer(ArchiveReader&);

CrackCatalogue::const_iterator::const_iterator(const CrackCatalogue* c, std::size_t k)
    : c_(c), k_(k) {
  if (k_ < c_->spilled_) {
    chunk_ = std::make_shared<std::vector<CrackRecord>>();
    chunk_begin_ = k_;
    c_->read_spilled(k_, std::min(c_->spilled_ - k_, kReadChunk), *chunk_);
  }
}

const CrackRecord& CrackCatalogue::const_iterator::operator*() const {
  if (k_ >= c_->spilled_) return c_->tail_[k_ - c_->spilled_];
  return (*chunk_)[k_ - chunk_begin_];
}

CrackCatalogue::const_iterator& CrackCatalogue::const_iterator::operator++() {
  ++k_;
  if (k_ < c_->spilled_ && k_ >= chunk_begin_ + chunk_->size()) {
    chunk_ = std::make_shared<std::vector<CrackRecord>>();  // the old chunk stays with copies
    chunk_begin_ = k_;
    c_->read_spilled(k_, std::min(c_->spilled_ - k_, kReadChunk), *chunk_);
  }
  return *this;
}

}  // namespace breccia
