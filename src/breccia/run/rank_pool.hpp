#pragma once
// Batches of runs shared out over the ranks of an MPI launch, for a driver that decides on root
// what to run next (a calibration's trials). Root hands a batch to every rank; the k-th run goes
// to rank k mod N, which runs it in its own process with its share of its machine's cores, or,
// with groups of ranks (`ranks_per_run`), to group k mod (N / ranks_per_run), which splits it
// over its ranks; root gets every outcome back in the batch's order. The other ranks serve batches
// until root's pool ends. A run does not depend on where it ran, so each run folder is the one a
// single process writes.
#include <string>
#include <vector>

#include "breccia/run/run.hpp"
#include "breccia/spec/experiment.hpp"

namespace breccia {

// How a run of a batch ended, as its rank tells root.
struct PooledRun {
  std::string folder, status, stop_reason;
  double wall_seconds = 0.0;
  std::string error;  // what the run threw (empty: it ended, in any status)
};

class RankPool {
 public:
  // `ranks_per_run` divides the launch's rank count (1: every rank runs whole runs).
  explicit RankPool(int ranks_per_run = 1) : ranks_per_run_(ranks_per_run) {}
  ~RankPool();  // root: the serving ranks stop
  RankPool(const RankPool&) = delete;
  RankPool& operator=(const RankPool&) = delete;

  // Root: runs the batch over every rank (in this process alone, in order, without MPI).
  std::vector<PooledRun> run(const std::vector<ExperimentSpec>& specs, const RunOptions& opt);

  // The other ranks: runs root's batches until its pool ends. `opt` as RankPool::run's.
  static void serve(const RunOptions& opt);

 private:
  int ranks_per_run_ = 1;
};

}  // namespace breccia
