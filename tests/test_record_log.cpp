// A record log with its older records in a file (the AE monitor's event catalogue and crack
// contexts): every record reads back as recorded, a checkpoint and the file together restore the
// log exactly, and a file that no longer matches the checkpoint is refused.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/record_file.hpp"

namespace fs = std::filesystem;
using namespace breccia;

namespace {

struct Sample {
  std::uint64_t index = 0;
  double value = 0.0;
  std::uint32_t code = 0;
  std::uint32_t unused = 0;  // named, not padding: written raw
};

Sample sample(std::size_t k) {
  return {.index = k,
          .value = 0.5 * static_cast<double>(k) - 3.0,
          .code = static_cast<std::uint32_t>(7 * k + 1)};
}

void expect_samples(const RecordLog<Sample>& log, std::size_t n) {
  ASSERT_EQ(log.size(), n);
  const std::vector<Sample> all = log.all();
  ASSERT_EQ(all.size(), n);
  for (std::size_t k = 0; k < n; ++k) {
    EXPECT_EQ(all[k].index, k);
    EXPECT_EQ(all[k].value, sample(k).value);
    EXPECT_EQ(all[k].code, sample(k).code);
  }
  for (std::size_t from : {std::size_t{0}, n / 3, n}) {
    std::size_t seen = from;
    log.visit(from, [&](const Sample& s) { EXPECT_EQ(s.index, seen++); });
    EXPECT_EQ(seen, n);
  }
}

struct TempFile {
  fs::path path;
  explicit TempFile(const char* name) : path(fs::temp_directory_path() / name) { fs::remove(path); }
  ~TempFile() { fs::remove(path); }
};

}  // namespace

TEST(RecordLog, RecordsInAFileReadBackAsRecorded) {
  TempFile f("breccia_log_read.bin");
  RecordLog<Sample> log("test log");
  for (std::size_t k = 0; k < 5; ++k) log.push_back(sample(k));
  expect_samples(log, 5);   // in memory
  log.spill_to(f.path, 3);  // the five held go to the file at once: more than three
  EXPECT_EQ(log.spilled(), 5u);
  for (std::size_t k = 5; k < 10'000; ++k) log.push_back(sample(k));
  EXPECT_GT(log.spilled(), 9'990u);
  EXPECT_LE(log.size() - log.spilled(), 3u);
  EXPECT_GT(fs::file_size(f.path), log.spilled() * sizeof(Sample));
  EXPECT_LT(fs::file_size(f.path), log.spilled() * sizeof(Sample) + 100);
  expect_samples(log, 10'000);
}

TEST(RecordLog, CheckpointAndFileRestoreItExactly) {
  TempFile f("breccia_log_restore.bin");
  std::stringstream saved;
  std::uintmax_t longer = 0;
  {
    RecordLog<Sample> log("test log");
    log.spill_to(f.path, 16);
    for (std::size_t k = 0; k < 1'000; ++k) log.push_back(sample(k));
    ArchiveWriter w(saved);
    log.transfer(w);
    // The run goes on past its checkpoint, then stops without another one.
    for (std::size_t k = 1'000; k < 1'500; ++k) log.push_back(sample(k));
    longer = fs::file_size(f.path);
  }
  RecordLog<Sample> r("test log");
  ArchiveReader a(saved, "test checkpoint");
  r.transfer(a);
  EXPECT_EQ(r.size(), 1'000u);
  r.reattach(f.path, 16);
  EXPECT_LT(fs::file_size(f.path), longer);  // the records after the checkpoint are dropped
  expect_samples(r, 1'000);
  for (std::size_t k = 1'000; k < 2'000; ++k) r.push_back(sample(k));  // and recorded again
  expect_samples(r, 2'000);
}

TEST(RecordLog, AFileThatNoLongerMatchesIsRefused) {
  TempFile f("breccia_log_damaged.bin");
  std::stringstream saved;
  {
    RecordLog<Sample> log("test log");
    log.spill_to(f.path, 8);
    for (std::size_t k = 0; k < 100; ++k) log.push_back(sample(k));
    ArchiveWriter w(saved);
    log.transfer(w);
  }
  const std::string checkpoint = saved.str();
  auto restored = [&] {
    std::stringstream in(checkpoint);
    ArchiveReader a(in, "test checkpoint");
    RecordLog<Sample> r("test log");
    r.transfer(a);
    return r;
  };
  {  // a record changed on disk: its hash no longer matches
    std::fstream io(f.path, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(-static_cast<std::streamoff>(sizeof(Sample)), std::ios::end);
    io.put('\x7f');
  }
  RecordLog<Sample> damaged = restored();
  EXPECT_THROW(damaged.reattach(f.path, 8), InputError);
  // Another log's file (its name in the header differs).
  RecordLog<Sample> other = restored();
  RecordLog<Sample> writer("other log");
  writer.spill_to(f.path, 1);
  for (std::size_t k = 0; k < 100; ++k) writer.push_back(sample(k));
  EXPECT_THROW(other.reattach(f.path, 8), InputError);
  // No file where the checkpoint counted records in one.
  fs::remove(f.path);
  RecordLog<Sample> missing = restored();
  EXPECT_THROW(missing.reattach(f.path, 8), InputError);
}
