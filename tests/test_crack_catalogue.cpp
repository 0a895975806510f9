// The crack catalogue with its older records in a file: every way of reading it gives the records
// recorded, to the bit, as the same catalogue held in memory; a checkpoint and the file together
// restore it exactly, and a file that no longer matches the checkpoint is refused.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/engine/crack_catalogue.hpp"
#include "breccia/law/brittle_beam.hpp"
#include "breccia/law/parallel_bond.hpp"

namespace fs = std::filesystem;
using namespace breccia;

namespace {

// A record whose every field depends on k, so that a record read back from the wrong place or
// with a field dropped differs.
CrackRecord record(std::size_t k) {
  const auto x = static_cast<double>(k);
  CrackRecord r;
  r.step = 10 * k + 3;
  r.time = 1e-7 * x + 1e-9;
  r.law = k % 3 == 0 ? BrittleBeam::name : ParallelBond::name;
  r.bond_tag = 7 * k + 1;
  r.id1 = k;
  r.id2 = k + 1000;
  r.R1 = 1e-4 + 1e-7 * x;
  r.R2 = 2e-4 + 1e-7 * x;
  r.position = {x, -x, 0.5 * x};
  r.normal = {0.6, 0.8, 1e-3 * x};
  r.mode = k % 2 == 0 ? CrackMode::Tensile : CrackMode::Shear;
  r.bond_radius = 3e-5 * x;
  r.Fn = -x;
  r.Fs = 2 * x;
  r.Mt = 3 * x;
  r.Mb = 4 * x;
  r.sigma = 5 * x;
  r.tau = 6 * x;
  r.ratio_t = 0.1 * x;
  r.ratio_s = 0.2 * x;
  r.energy = {1 * x, 2 * x, 3 * x, 4 * x, 5 * x};
  return r;
}

bool same(const CrackRecord& a, const CrackRecord& b) {
  CrackRecord pa = a, pb = b;
  if (pa.law != pb.law) return false;
  pa.law = pb.law = {};
  return std::memcmp(&pa, &pb, sizeof pa) == 0;
}

// A file of its own under the temporary folder, removed at the end of the test.
struct TempFile {
  fs::path path;
  explicit TempFile(const char* name) : path(fs::temp_directory_path() / name) { fs::remove(path); }
  ~TempFile() { fs::remove(path); }
};

void expect_records(const CrackCatalogue& c, std::size_t n) {
  ASSERT_EQ(c.size(), n);
  std::size_t k = 0;
  for (const CrackRecord& r : c) EXPECT_TRUE(same(r, record(k++))) << "iterated record " << k - 1;
  EXPECT_EQ(k, n);
  for (std::size_t from : {std::size_t{0}, n / 3, n - 1, n}) {
    std::size_t seen = from;
    c.visit(from, [&](const CrackRecord& r) { EXPECT_TRUE(same(r, record(seen++))); });
    EXPECT_EQ(seen, n);
  }
  auto reader = c.reader();
  for (std::size_t j = 0; j < n; ++j) EXPECT_TRUE(same(reader[j], record(j))) << "read " << j;
  for (std::size_t j : {n - 1, std::size_t{0}, n / 2}) {  // backwards and random
    EXPECT_TRUE(same(reader[j], record(j)));
    EXPECT_TRUE(same(c[j], record(j)));
  }
  EXPECT_TRUE(same(c.back(), record(n - 1)));
}

}  // namespace

TEST(CrackCatalogue, RecordsInAFileReadBackAsRecorded) {
  TempFile f("breccia_cracks_read.bin");
  CrackCatalogue c;
  for (std::size_t k = 0; k < 5; ++k) c.push_back(record(k));
  c.spill_to(f.path, 3);  // the five held go to the file at once: more than three
  for (std::size_t k = 5; k < 10'000; ++k) c.push_back(record(k));
  EXPECT_GT(c.spilled(), 9'000u);
  EXPECT_EQ(c.size(), 10'000u);
  EXPECT_LE(c.size() - c.spilled(), 5u);
  // 224 bytes a record on disk after the header.
  EXPECT_GT(fs::file_size(f.path), c.spilled() * 224);
  EXPECT_LT(fs::file_size(f.path), c.spilled() * 224 + 200);
  expect_records(c, 10'000);

  const CrackCatalogue copy = c;  // all in memory, no file
  EXPECT_EQ(copy.spilled(), 0u);
  EXPECT_FALSE(copy.spilling());
  expect_records(copy, 10'000);
}

TEST(CrackCatalogue, CheckpointAndFileRestoreItExactly) {
  TempFile f("breccia_cracks_restore.bin");
  CrackCatalogue c;
  c.spill_to(f.path, 64);
  for (std::size_t k = 0; k < 1'000; ++k) c.push_back(record(k));
  std::stringstream saved;
  {
    ArchiveWriter w(saved);
    c.transfer(w);
  }
  // The run goes on past its checkpoint, then stops without another one.
  for (std::size_t k = 1'000; k < 1'500; ++k) c.push_back(record(k));
  const auto longer = fs::file_size(f.path);
  c = CrackCatalogue{};

  CrackCatalogue r;
  ArchiveReader a(saved, "test checkpoint");
  r.transfer(a);
  EXPECT_EQ(r.size(), 1'000u);
  r.reattach(f.path, 64);
  EXPECT_LT(fs::file_size(f.path), longer);  // the records after the checkpoint are dropped
  expect_records(r, 1'000);
  for (std::size_t k = 1'000; k < 2'000; ++k) r.push_back(record(k));  // and recorded again
  expect_records(r, 2'000);
}

TEST(CrackCatalogue, AFileThatNoLongerMatchesIsRefused) {
  TempFile f("breccia_cracks_damaged.bin");
  std::stringstream saved;
  {
    CrackCatalogue c;
    c.spill_to(f.path, 8);
    for (std::size_t k = 0; k < 100; ++k) c.push_back(record(k));
    ArchiveWriter w(saved);
    c.transfer(w);
  }
  const std::string checkpoint = saved.str();
  auto restored = [&] {
    std::stringstream in(checkpoint);
    ArchiveReader a(in, "test checkpoint");
    CrackCatalogue r;
    r.transfer(a);
    return r;
  };
  {
    CrackCatalogue r = restored();
    EXPECT_THROW(r.reattach(fs::temp_directory_path() / "breccia_no_such_cracks.bin"), InputError);
  }
  // One byte of a record changed.
  {
    std::fstream io(f.path, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(static_cast<std::streamoff>(fs::file_size(f.path) - 300));
    io.put('x');
  }
  {
    CrackCatalogue r = restored();
    try {
      r.reattach(f.path);
      FAIL() << "a changed record was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("does not hold the records"), std::string::npos)
          << e.what();
    }
  }
  // Cut short.
  fs::resize_file(f.path, 1000);
  {
    CrackCatalogue r = restored();
    EXPECT_THROW(r.reattach(f.path), InputError);
  }
  // Not a catalogue at all.
  {
    std::ofstream(f.path, std::ios::trunc) << "history.csv,perhaps\n";
    CrackCatalogue r = restored();
    EXPECT_THROW(r.reattach(f.path), InputError);
  }
}
