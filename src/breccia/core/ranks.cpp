#include "breccia/core/ranks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "breccia/core/interrupt.hpp"

#ifdef BRECCIA_HAVE_MPI
#include <mpi.h>
#endif

namespace breccia::ranks {

namespace {

// The world as World set it up; a plain start leaves it at one rank.
struct State {
  int rank = 0, size = 1, local_size = 1;
  bool mpi = false;               // MPI initialised by World
  bool waited = false;            // a collective call has run
  bool shared_failure = false;    // on_root passed a failure to every rank
  double exchange_seconds = 0.0;  // wall time inside exchange() (exchange_seconds())
  std::uint64_t received_bytes = 0;
  std::uint64_t collectives = 0;  // MPI collective calls (collectives())
#ifdef BRECCIA_HAVE_MPI
  MPI_Comm comm = MPI_COMM_WORLD;  // the ranks the collectives reach: the world, or a Group
#endif
};

State& state() noexcept {
  static State s;
  return s;
}

// The states that the Groups now alive replaced, innermost last.
std::vector<State>& outer_states() {
  static std::vector<State> saved;
  return saved;
}

std::optional<int> env_int(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') return std::nullopt;
  char* end = nullptr;
  const long n = std::strtol(v, &end, 10);
  if (*end != '\0' || n < 0 || n > INT_MAX) return std::nullopt;
  return static_cast<int>(n);
}

#ifdef BRECCIA_HAVE_MPI
void check(int rc, const char* call) {
  if (rc == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(rc, text, &length);
  throw std::runtime_error(fmt::format("MPI: {} failed: {}", call, std::string(text, length)));
}

int int_count(std::size_t n) {
  if (n > static_cast<std::size_t>(INT_MAX))
    throw std::runtime_error(fmt::format("MPI: a message of {} bytes is too long", n));
  return static_cast<int>(n);
}
#endif

}  // namespace

Launch launch_from_environment() {
  Launch l;
  const std::optional<int> size =
      env_int("OMPI_COMM_WORLD_SIZE") ? env_int("OMPI_COMM_WORLD_SIZE") : env_int("PMI_SIZE");
  const std::optional<int> rank =
      env_int("OMPI_COMM_WORLD_RANK") ? env_int("OMPI_COMM_WORLD_RANK") : env_int("PMI_RANK");
  const std::optional<int> local = env_int("OMPI_COMM_WORLD_LOCAL_SIZE")
                                       ? env_int("OMPI_COMM_WORLD_LOCAL_SIZE")
                                       : env_int("MPI_LOCALNRANKS");
  // Slurm's srun with PMIx names the rank only; the step's task count is the size.
  const std::optional<int> pmix_rank = env_int("PMIX_RANK");
  if (!size && pmix_rank) {
    l.launched = true;
    l.rank = *pmix_rank;
    l.size = std::max(env_int("SLURM_STEP_NUM_TASKS").value_or(1), l.rank + 1);
    l.local_size = std::clamp(env_int("SLURM_STEP_TASKS_PER_NODE").value_or(1), 1, l.size);
    return l;
  }
  if (!size || *size < 1) return l;
  l.launched = true;
  l.size = *size;
  l.rank = rank.value_or(0);
  l.local_size = std::clamp(local.value_or(1), 1, l.size);
  return l;
}

bool built_with_mpi() noexcept {
#ifdef BRECCIA_HAVE_MPI
  return true;
#else
  return false;
#endif
}

std::optional<std::string> launch_refusal(const Launch& launch, bool with_mpi,
                                          const std::string& command,
                                          const std::vector<std::string>& spread) {
  if (launch.size <= 1) return std::nullopt;
  if (!with_mpi)
    return fmt::format(
        "this breccia was built without MPI, but a launcher started it as one of {} processes: "
        "each would run the whole command alone. Build with MPI (install libopenmpi-dev, then "
        "cmake -DBRECCIA_MPI=ON) or start it without mpirun",
        launch.size);
  if (std::find(spread.begin(), spread.end(), command) != spread.end()) return std::nullopt;
  std::string names;
  for (const std::string& s : spread) names += (names.empty() ? "" : ", ") + s;
  return fmt::format(
      "`breccia {}` runs in one process; on {} ranks it would run {} "
      "times over. Commands that spread over ranks: {}",
      command, launch.size, launch.size, names);
}

World::World([[maybe_unused]] int& argc, [[maybe_unused]] char**& argv) {
#ifdef BRECCIA_HAVE_MPI
  const Launch l = launch_from_environment();
  if (!l.launched) return;
  int provided = 0;
  check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  State& s = state();
  s.mpi = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &s.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &s.size);
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, s.rank, MPI_INFO_NULL, &node);
  MPI_Comm_size(node, &s.local_size);
  MPI_Comm_free(&node);
#endif
}

World::~World() {
#ifdef BRECCIA_HAVE_MPI
  if (state().mpi) MPI_Finalize();
  state() = State{};
#endif
}

Group::Group(int ranks_each) {
  State& s = state();
  if (ranks_each < 1 || s.size % ranks_each != 0)
    throw std::invalid_argument(
        fmt::format("groups of {} ranks do not divide the {} ranks", ranks_each, s.size));
  index_ = s.rank / ranks_each;
  count_ = s.size / ranks_each;
  first_rank_ = index_ * ranks_each;
  const State outer = s;
#ifdef BRECCIA_HAVE_MPI
  if (s.mpi) {
    MPI_Comm group;
    check(MPI_Comm_split(s.comm, index_, s.rank, &group), "MPI_Comm_split");
    s.comm = group;
    MPI_Comm_rank(group, &s.rank);
    MPI_Comm_size(group, &s.size);
  }
#endif
  outer_states().push_back(outer);
  begin_task();
}

Group::~Group() {
  State& s = state();
#ifdef BRECCIA_HAVE_MPI
  if (s.mpi) MPI_Comm_free(&s.comm);
#endif
  State outer = outer_states().back();
  outer_states().pop_back();
  outer.exchange_seconds = s.exchange_seconds;  // the counters keep counting
  outer.received_bytes = s.received_bytes;
  outer.collectives = s.collectives;
  s = outer;
}

void Group::begin_task() noexcept {
  state().waited = false;
  state().shared_failure = false;
}

int rank() noexcept {
  return state().rank;
}

int size() noexcept {
  return state().size;
}

int local_size() noexcept {
  return state().local_size;
}

int launch_rank() noexcept {
  return outer_states().empty() ? state().rank : outer_states().front().rank;
}

int launch_size() noexcept {
  return outer_states().empty() ? state().size : outer_states().front().size;
}

void barrier() {
  state().waited = true;
#ifdef BRECCIA_HAVE_MPI
  if (state().mpi) {
    ++state().collectives;
    check(MPI_Barrier(state().comm), "MPI_Barrier");
  }
#endif
}

std::uint32_t any_flags(std::uint32_t mine) {
  state().waited = true;
#ifdef BRECCIA_HAVE_MPI
  if (!state().mpi) return mine;
  std::uint32_t all = 0;
  ++state().collectives;
  check(MPI_Allreduce(&mine, &all, 1, MPI_UINT32_T, MPI_BOR, state().comm), "MPI_Allreduce");
  return all;
#else
  return mine;
#endif
}

std::string broadcast(const std::string& from_root) {
  state().waited = true;
#ifdef BRECCIA_HAVE_MPI
  if (!state().mpi) return from_root;
  std::uint64_t n = from_root.size();
  ++state().collectives;
  check(MPI_Bcast(&n, 1, MPI_UINT64_T, 0, state().comm), "MPI_Bcast");
  std::string text = root() ? from_root : std::string(n, '\0');
  ++state().collectives;
  check(MPI_Bcast(text.data(), int_count(n), MPI_CHAR, 0, state().comm), "MPI_Bcast");
  return text;
#else
  return from_root;
#endif
}

std::vector<std::string> gather(const std::string& mine) {
  state().waited = true;
#ifdef BRECCIA_HAVE_MPI
  if (!state().mpi) return {mine};
  const int n = int_count(mine.size());
  std::vector<int> lengths(root() ? size() : 0), offsets(lengths.size());
  ++state().collectives;
  check(MPI_Gather(&n, 1, MPI_INT, lengths.data(), 1, MPI_INT, 0, state().comm), "MPI_Gather");
  std::size_t total = 0;
  for (std::size_t r = 0; r < lengths.size(); ++r) {
    offsets[r] = int_count(total);
    total += static_cast<std::size_t>(lengths[r]);
  }
  std::string all(total, '\0');
  ++state().collectives;
  check(MPI_Gatherv(mine.data(), n, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR,
                    0, state().comm),
        "MPI_Gatherv");
  std::vector<std::string> out;
  for (std::size_t r = 0; r < lengths.size(); ++r)
    out.push_back(
        all.substr(static_cast<std::size_t>(offsets[r]), static_cast<std::size_t>(lengths[r])));
  return out;
#else
  return {mine};
#endif
}

namespace {

// The exchange itself; `expected` holds the sizes of the incoming messages when the receiver
// knows them (one collective then), or is empty (they are sent first).
std::vector<std::string> exchange_messages(const std::vector<std::string>& outgoing,
                                           const std::vector<std::size_t>& expected) {
  state().waited = true;
  if (outgoing.size() != static_cast<std::size_t>(size()) ||
      (!expected.empty() && expected.size() != outgoing.size()))
    throw std::logic_error(
        fmt::format("ranks::exchange: {} messages for {} ranks", outgoing.size(), size()));
#ifdef BRECCIA_HAVE_MPI
  if (!state().mpi) return outgoing;
  const std::size_t n = outgoing.size();
  std::vector<int> send_counts(n), send_offsets(n), recv_counts(n), recv_offsets(n);
  std::string sent;
  for (std::size_t r = 0; r < n; ++r) {
    send_counts[r] = int_count(outgoing[r].size());
    send_offsets[r] = int_count(sent.size());
    sent += outgoing[r];
  }
  ++state().collectives;
  if (expected.empty()) {
    ++state().collectives;
    check(
        MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, state().comm),
        "MPI_Alltoall");
  } else {
    for (std::size_t r = 0; r < n; ++r) recv_counts[r] = int_count(expected[r]);
  }
  std::size_t total = 0;
  for (std::size_t r = 0; r < n; ++r) {
    recv_offsets[r] = int_count(total);
    total += static_cast<std::size_t>(recv_counts[r]);
  }
  std::string received(total, '\0');
  check(
      MPI_Alltoallv(sent.data(), send_counts.data(), send_offsets.data(), MPI_CHAR, received.data(),
                    recv_counts.data(), recv_offsets.data(), MPI_CHAR, state().comm),
      "MPI_Alltoallv");
  std::vector<std::string> incoming;
  for (std::size_t r = 0; r < n; ++r)
    incoming.push_back(received.substr(static_cast<std::size_t>(recv_offsets[r]),
                                       static_cast<std::size_t>(recv_counts[r])));
  return incoming;
#else
  return outgoing;
#endif
}

}  // namespace

std::vector<std::string> exchange(const std::vector<std::string>& outgoing) {
  return exchange(outgoing, {});
}

std::vector<std::string> exchange(const std::vector<std::string>& outgoing,
                                  const std::vector<std::size_t>& expected) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::string> in = exchange_messages(outgoing, expected);
  State& s = state();
  s.exchange_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t r = 0; r < in.size(); ++r)
    if (r != static_cast<std::size_t>(s.rank)) s.received_bytes += in[r].size();
  return in;
}

double exchange_seconds() noexcept {
  return state().exchange_seconds;
}

std::uint64_t received_bytes() noexcept {
  return state().received_bytes;
}

std::uint64_t collectives() noexcept {
  return state().collectives;
}

std::vector<std::string> all_gather(const std::string& mine) {
  return exchange(std::vector<std::string>(static_cast<std::size_t>(size()), mine));
}

std::vector<std::string> all_gather(const std::string& mine,
                                    const std::vector<std::size_t>& expected) {
  return exchange(std::vector<std::string>(static_cast<std::size_t>(size()), mine), expected);
}

std::string on_root(const std::function<std::string()>& work) {
  if (size() == 1) return work();
  std::string text;
  std::exception_ptr failure;
  char flag = 'K';  // K: done, E: failed, I: stopped by a signal
  if (root()) {
    try {
      text = work();
    } catch (const Interrupted& e) {
      failure = std::current_exception();
      flag = 'I';
      text = e.what();
    } catch (const std::exception& e) {
      failure = std::current_exception();
      flag = 'E';
      text = e.what();
    }
  }
  const std::string flagged = broadcast(flag + text);
  if (flagged.front() != 'K') state().shared_failure = true;
  if (failure) std::rethrow_exception(failure);
  if (flagged.front() != 'K') throw RootFailed(flagged.substr(1), flagged.front() == 'I');
  return flagged.substr(1);
}

bool failure_is_shared(bool bad_input) noexcept {
  const State& s = state();
  return s.size == 1 || s.shared_failure || (bad_input && !s.waited);
}

void failure_released_the_others() noexcept {
  state().shared_failure = true;
}

void abort_unless_shared(bool bad_input, const std::string& what) {
  if (failure_is_shared(bad_input)) return;
  std::fprintf(stderr, "error: %s (met on this rank only: ending every rank)\n", what.c_str());
  abort(1);
}

void abort(int code) {
#ifdef BRECCIA_HAVE_MPI
  if (state().mpi) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::exit(code);
}

}  // namespace breccia::ranks
