#include "breccia/run/rank_pool.hpp"

#include <algorithm>
#include <chrono>
#include <exception>
#include <nlohmann/json.hpp>
#include <thread>

#include "breccia/core/error.hpp"
#include "breccia/core/ranks.hpp"

namespace breccia {

using json = nlohmann::json;

namespace {

constexpr const char* kStop = "stop";

// One run of a batch on this rank's group, split over the group's ranks when it has several.
PooledRun run_one(const json& entry, const RunOptions& opt, int threads) {
  PooledRun r;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    ExperimentSpec spec = parse_experiment(entry.at("experiment").get<std::string>(),
                                           entry.at("source").get<std::string>(), {});
    if (spec.threads == 0) spec.threads = threads;
    RunOptions mine = opt;
    mine.split_over_ranks = ranks::size() > 1;
    if (!ranks::root()) mine.log = nullptr;
    const RunResult result = run_experiment(spec, mine);
    r.folder = result.folder;
    r.status = result.status;
    r.stop_reason = result.stop_reason;
  } catch (const std::exception& e) {
    r.status = "failed";
    r.error = "rank " + std::to_string(ranks::launch_rank()) + ": " + e.what();
    ranks::abort_unless_shared(dynamic_cast<const InputError*>(&e) != nullptr, r.error);
  }
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

// This rank's share of a batch: the ranks form groups of `ranks_per_run` consecutive ranks, and
// the k-th run goes to group k mod G, split over its ranks (in groups of one, whole on one rank).
// A run's threads: its own, or this machine's cores shared among its ranks. The group's first
// rank reports its runs.
json run_share(const json& batch, const RunOptions& opt) {
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int threads = ranks::size() > 1 ? std::max(1, cores / ranks::local_size()) : 0;
  const json& runs = batch.at("runs");
  json out = json::array();
  ranks::Group group(batch.at("ranks_per_run").get<int>());
  for (std::size_t k = static_cast<std::size_t>(group.index()); k < runs.size();
       k += static_cast<std::size_t>(group.count())) {
    group.begin_task();
    const PooledRun r = run_one(runs[k], opt, threads);
    if (ranks::root())
      out.push_back({{"index", k},
                     {"folder", r.folder},
                     {"status", r.status},
                     {"stop_reason", r.stop_reason},
                     {"wall_seconds", r.wall_seconds},
                     {"error", r.error}});
  }
  return out;
}

}  // namespace

RankPool::~RankPool() {
  if (ranks::size() == 1 || !ranks::root()) return;
  try {
    ranks::broadcast(kStop);
  } catch (const std::exception&) {
    ranks::abort(1);  // MPI itself failed: nothing else ends the serving ranks
  }
  if (std::uncaught_exceptions() > 0) ranks::failure_released_the_others();
}

std::vector<PooledRun> RankPool::run(const std::vector<ExperimentSpec>& specs,
                                     const RunOptions& opt) {
  json batch = {{"ranks_per_run", ranks_per_run_}, {"runs", json::array()}};
  for (const ExperimentSpec& s : specs)
    batch["runs"].push_back({{"experiment", to_toml(s)}, {"source", s.source}});
  if (ranks::size() > 1) ranks::broadcast(batch.dump());
  const json mine = run_share(batch, opt);
  std::vector<PooledRun> runs(specs.size());
  for (const std::string& text : ranks::gather(mine.dump()))
    for (const json& o : json::parse(text)) {
      PooledRun& r = runs.at(o.at("index").get<std::size_t>());
      r.folder = o.at("folder").get<std::string>();
      r.status = o.at("status").get<std::string>();
      r.stop_reason = o.at("stop_reason").get<std::string>();
      r.wall_seconds = o.at("wall_seconds").get<double>();
      r.error = o.at("error").get<std::string>();
    }
  return runs;
}

void RankPool::serve(const RunOptions& opt) {
  for (std::string batch = ranks::broadcast(""); batch != kStop; batch = ranks::broadcast(""))
    ranks::gather(run_share(json::parse(batch), opt).dump());
}

}  // namespace breccia
