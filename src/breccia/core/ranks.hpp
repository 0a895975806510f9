#pragma once
// The processes of an MPI launch (`mpirun -np N`, `srun`). A build without MPI, or a command
// started without a launcher, is rank 0 of 1, and every function below then does what one
// process alone would, so callers have one path. Only this module includes <mpi.h>.
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace breccia::ranks {

// What a launcher told the process through its environment, read before any MPI call: Open MPI
// (OMPI_COMM_WORLD_*), MPICH's Hydra and Slurm's PMI (PMI_SIZE, PMI_RANK, MPI_LOCALNRANKS), and
// PMIx under srun (PMIX_RANK, with Slurm's SLURM_STEP_NUM_TASKS for the size).
struct Launch {
  bool launched = false;  // started by a launcher, even as 1 process
  int size = 1, rank = 0;
  int local_size = 1;  // ranks on this machine
};
Launch launch_from_environment();

// True when this build links MPI (cmake -DBRECCIA_MPI=ON, or AUTO with Open MPI installed).
bool built_with_mpi() noexcept;

// Why a command cannot run as launched (empty: it can): a build without MPI started as one of
// several processes would run the whole command in each and write as many folders, and a command
// that does not spread over ranks must not run N times over. `command` is the subcommand's name;
// `spread` the commands that run on several ranks.
std::optional<std::string> launch_refusal(const Launch& launch, bool with_mpi,
                                          const std::string& command,
                                          const std::vector<std::string>& spread);

// Initialises MPI for the life of the command when a launcher started it (a plain start touches
// no MPI), with one thread per rank calling MPI (the OpenMP threads never do).
class World {
 public:
  World(int& argc, char**& argv);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;
};

// The launch's ranks cut into groups of `ranks_each` consecutive ranks, which must divide size()
// (std::invalid_argument otherwise). While a Group lives, everything below speaks of this rank's
// group: rank() and size() within it, root() its first rank, collectives among its ranks only,
// so that a command run inside it runs on the group as it would on a launch of that size (a
// sweep's runs each split over a group). Every rank makes and ends its Group at the same point.
class Group {
 public:
  explicit Group(int ranks_each);
  ~Group();
  Group(const Group&) = delete;
  Group& operator=(const Group&) = delete;
  int index() const noexcept { return index_; }  // 0 .. count() - 1
  int count() const noexcept { return count_; }
  int first_rank() const noexcept { return first_rank_; }  // in the launch
  // A new piece of work for the group: whether a failure is shared (failure_is_shared) is judged
  // from here on.
  void begin_task() noexcept;

 private:
  int index_ = 0, count_ = 1, first_rank_ = 0;
};

int rank() noexcept;
int size() noexcept;
int local_size() noexcept;  // ranks on this machine, to share its cores
// The whole launch's, whatever Group is alive.
int launch_rank() noexcept;
int launch_size() noexcept;
inline bool root() noexcept {
  return rank() == 0;
}

void barrier();
// The flags any rank set (a bitwise or over the ranks), on every rank: decisions that every rank
// must take at the same point, such as stopping on a signal that reached some ranks first.
std::uint32_t any_flags(std::uint32_t mine);
// Root's text, on every rank.
std::string broadcast(const std::string& from_root);
// Every rank's text, in rank order, on root (empty on the others).
std::vector<std::string> gather(const std::string& mine);

// Every rank sends outgoing[r] to rank r and gets what each rank sent it, in rank order (one
// MPI_Alltoallv). outgoing must hold size() entries; a rank's entry to itself comes back as it is.
std::vector<std::string> exchange(const std::vector<std::string>& outgoing);
// The same when the receiver knows the size of each incoming message (`expected`, per rank): one
// collective instead of two. A message of another size is an error of the caller.
std::vector<std::string> exchange(const std::vector<std::string>& outgoing,
                                  const std::vector<std::size_t>& expected);
// Wall time this rank has spent in exchange() and all_gather() so far, waiting included: the
// communication share of a split run (bench/bench_engine.cpp).
double exchange_seconds() noexcept;
// Bytes this rank has received from the other ranks in exchange() and all_gather() so far.
std::uint64_t received_bytes() noexcept;
// MPI collective calls this rank has made so far (each a point where every rank of the group
// waits for the others): their count per step bounds a split run's latency.
std::uint64_t collectives() noexcept;
// Every rank's text, in rank order, on every rank (`expected`: their sizes, when known).
std::vector<std::string> all_gather(const std::string& mine);
std::vector<std::string> all_gather(const std::string& mine,
                                    const std::vector<std::size_t>& expected);

// An error that root met and passed on: the other ranks raise it too, and do not print it (root
// does).
class RootFailed : public std::runtime_error {
 public:
  RootFailed(const std::string& what, bool interrupted)
      : std::runtime_error(what), interrupted_(interrupted) {}
  // Root stopped at a signal (Interrupted), not at an error: every rank ends as interrupted.
  bool interrupted() const noexcept { return interrupted_; }

 private:
  bool interrupted_;
};

// Runs `work` on root only and gives its text to every rank. If it throws, every rank throws:
// root its own exception, the others RootFailed with root's message, so that no rank waits for
// a root that has given up.
std::string on_root(const std::function<std::string()>& work);

// Whether a rank that failed may end as usual (true) or must abort the launch (false). The other
// ranks end the same way when the failure was shared through on_root, or was a bad input met
// before any rank waited on another (every rank read the same input); any other failure may
// leave ranks waiting for this one forever.
bool failure_is_shared(bool bad_input) noexcept;
// Root, failing, has released the other ranks (told them to stop): its failure ends no rank in
// waiting.
void failure_released_the_others() noexcept;

// Ends every rank of the launch (MPI_Abort) with `code`; a single process exits with it.
[[noreturn]] void abort(int code);

// For a failure caught where the work goes on (a sweep's or a calibration's run in a Group):
// when the other ranks did not meet it too (failure_is_shared), they would wait for this one
// forever, so it prints `what` and ends the launch.
void abort_unless_shared(bool bad_input, const std::string& what);

}  // namespace breccia::ranks
