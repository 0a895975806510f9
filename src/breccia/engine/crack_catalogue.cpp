#include "breccia/engine/crack_catalogue.hpp"

#include <cstring>
#include <string>
#include <utility>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
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
static_assert(sizeof(StoredCrack) == CrackCatalogue::kStoredBytes &&
              std::is_trivially_copyable_v<StoredCrack>);
static_assert(sizeof(CrackRecord) == 240, "CrackRecord changed: update StoredCrack");

}  // namespace

// A checkpoint holds the records themselves, the law's name blanked: their bytes are the members'
// sum, with no padding between them.
template <>
inline constexpr bool layout_checked_beside_it<CrackRecord> = true;
static_assert(sizeof(CrackRecord) == 2 * 8 + sizeof(std::string_view) + 5 * 8 + 2 * sizeof(Vec3) +
                                         1 + 7 + 9 * 8 + sizeof(BondEnergy),
              "CrackRecord has padding: name it (core/archive.hpp)");

namespace {

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

// The law names the codes of a file stand for, as its header holds them: a count, then each
// name with its length.
std::string law_table(const std::vector<std::string_view>& laws) {
  std::string h;
  auto put = [&](std::uint32_t v) { h.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(static_cast<std::uint32_t>(laws.size()));
  for (std::string_view name : laws) {
    put(static_cast<std::uint32_t>(name.size()));
    h.append(name);
  }
  return h;
}

}  // namespace

CrackCatalogue::CrackCatalogue(const CrackCatalogue& o) {
  *this = o;
}

CrackCatalogue& CrackCatalogue::operator=(const CrackCatalogue& o) {
  if (this == &o) return *this;
  std::vector<CrackRecord> all;
  all.reserve(o.size());
  o.visit(0, [&](const CrackRecord& c) { all.push_back(c); });
  tail_ = std::move(all);
  resident_ = 0;
  file_ = RecordFile{"crack catalogue", kStoredBytes};
  laws_.clear();
  return *this;
}

void CrackCatalogue::push_back(const CrackRecord& r) {
  if (spilling() && tail_.size() >= resident_) spill_tail();
  tail_.push_back(r);
}

void CrackCatalogue::reserve_more(std::size_t n) {
  const std::size_t want = tail_.size() + n;
  tail_.reserve(spilling() ? std::min(want, resident_) : want);
}

CrackRecord CrackCatalogue::operator[](std::size_t k) const {
  if (k >= spilled()) return tail_[k - spilled()];
  std::vector<CrackRecord> one;
  read_spilled(k, 1, one);
  return one.front();
}

void CrackCatalogue::spill_to(const std::filesystem::path& file, std::size_t resident) {
  laws_ = registered_laws();
  file_.create(file, law_table(laws_));
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
      throw InputError(file_.path().string(), "law", std::string(c.law),
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
  file_.append(out.data(), out.size());
  tail_.clear();
}

void CrackCatalogue::read_spilled(std::size_t first, std::size_t count,
                                  std::vector<CrackRecord>& out) const {
  std::vector<StoredCrack> in(count);
  file_.read(first, count, in.data());
  out.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    const StoredCrack& s = in[k];
    if (s.law >= laws_.size() || s.mode > 1)
      throw InputError(file_.path().string(), "record", std::to_string(first + k),
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

// The file's table of law names (each a law of this build): the codes' meanings.
void CrackCatalogue::read_law_table() {
  const std::string& t = file_.extra();
  const auto mismatch = [&](const std::string& what) {
    return InputError(file_.path().string(), "law table", what,
                      "not a crack catalogue this build of Breccia wrote");
  };
  std::size_t at = 0;
  auto get = [&]() {
    std::uint32_t v = 0;
    if (t.size() < at + sizeof v) throw mismatch("(too short)");
    std::memcpy(&v, t.data() + at, sizeof v);
    at += sizeof v;
    return v;
  };
  const std::uint32_t n = get();
  if (n > 64) throw mismatch(std::to_string(n) + " laws");
  laws_.clear();
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::uint32_t length = get();
    if (length > 64 || t.size() < at + length)
      throw mismatch("law name of " + std::to_string(length) + " bytes");
    laws_.push_back(registered_law(t.substr(at, length), file_.path().string()));
    at += length;
  }
}

void CrackCatalogue::reattach(const std::filesystem::path& file, std::size_t resident) {
  file_.reattach(file, law_table(registered_laws()));
  read_law_table();
  resident_ = std::max<std::size_t>(resident, 1);
  keep_room_for_resident();
  tail_.reserve(resident_);
}

template <class Archive>
void CrackCatalogue::transfer(Archive& a) {
  file_.transfer(a);
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
  if constexpr (Archive::reading) laws_.clear();
}

template void CrackCatalogue::transfer(ArchiveWriter&);
template void CrackCatalogue::transfer(ArchiveReader&);

CrackCatalogue::const_iterator::const_iterator(const CrackCatalogue* c, std::size_t k)
    : c_(c), k_(k) {
  if (k_ < c_->spilled()) {
    chunk_ = std::make_shared<std::vector<CrackRecord>>();
    chunk_begin_ = k_;
    c_->read_spilled(k_, std::min(c_->spilled() - k_, kReadChunk), *chunk_);
  }
}

const CrackRecord& CrackCatalogue::const_iterator::operator*() const {
  if (k_ >= c_->spilled()) return c_->tail_[k_ - c_->spilled()];
  return (*chunk_)[k_ - chunk_begin_];
}

CrackCatalogue::const_iterator& CrackCatalogue::const_iterator::operator++() {
  ++k_;
  if (k_ < c_->spilled() && k_ >= chunk_begin_ + chunk_->size()) {
    chunk_ = std::make_shared<std::vector<CrackRecord>>();  // the old chunk stays with copies
    chunk_begin_ = k_;
    c_->read_spilled(k_, std::min(c_->spilled() - k_, kReadChunk), *chunk_);
  }
  return *this;
}

}  // namespace breccia
