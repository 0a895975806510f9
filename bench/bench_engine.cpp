// Engine throughput on a bonded sample between two platens (bench/run drives it).
//
//   bench_engine --dim 3 --particles 100000 --phase elastic --threads 1 --steps 300 --repeats 3
//   bench_engine --sample cylinder --bond brittle_beam --particles 100000 ...
//
// Samples: "block", an FCC (3D) or hexagonal (2D) lattice of equal grains; "cylinder" (3D), a
// GenGeo-style random cylinder twice as tall as wide, packed by insertion (radii 0.25-1 mm, the
// 1:4 range of ESyS-Particle's GenGeo examples), the kind of sample the ESyS-Particle, YADE and
// LAMMPS BPM figures are quoted on. Bonds: "parallel_bond", "brittle_beam" (ESyS conventions) or
// "quaternion_bond" (LAMMPS bpm/rotational, no contact between bonded grains).
//
// Phases: "elastic" loads intact bonds (strong bonds, slow platens); "broken" measures the
// contact-dominated phase after breakage: weak bonds (10 kPa) are broken by random particle
// velocities (0.01 m/s) while the platens compress, then the measurement starts. Prints a readable
// line and one JSON object per case on its own line.
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <type_traits>
#include <vector>

#include "breccia/core/allocator.hpp"
#include "breccia/core/float_mode.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/core/rng.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/io/run_folder.hpp"
#include "breccia/protocol/compression.hpp"
#include "breccia/sample/lattice.hpp"
#include "breccia/sample/packing.hpp"
#include "breccia/sample/spatial_order.hpp"
#include "breccia/version.hpp"

using namespace breccia;

namespace {

long peak_rss_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss * 1024L;
}

// Lattice dimensions close to `target` particles, roughly twice as tall as wide.
std::array<int, 3> cells_for(int dim, long target) {
  if (dim == 3) {
    const int n =
        std::max(1, static_cast<int>(std::lround(std::cbrt(static_cast<double>(target) / 8.0))));
    return {
        n, n,
        std::max(1, static_cast<int>(std::lround(static_cast<double>(target) / (4.0 * n * n))))};
  }
  const int n =
      std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(target) / 2.0))));
  return {n, std::max(1, static_cast<int>(std::lround(static_cast<double>(target) / n))), 1};
}

// GenGeo-style random cylinder of about `target` grains (insertion packing, radii 0.25-1 mm):
// 1.43 grains per mm^3 is the density Breccia's insertion packing reaches with 1000 failures.
ParticleStore random_cylinder(long target) {
  PackingSettings s;
  s.shape = SampleShape::Cylinder;
  s.method = PackingMethod::Insertion;
  s.radii.r_min = 0.25e-3;
  s.radii.r_max = 1.0e-3;
  const double volume_mm3 = static_cast<double>(target) / 1.43;
  s.diameter = 1e-3 * std::cbrt(2.0 * volume_mm3 / std::numbers::pi);
  s.height = 2.0 * s.diameter;
  s.insertion_failures = 1000;  // GenGeo's example value
  s.max_particles = static_cast<std::size_t>(3 * target + 1000);
  GeometryData g = pack_sample(s).geometry;
  sort_spatially(g);  // as a run does
  return g.make_store();
}

// A run sorts every sample along a Morton curve before the engine sees it (run/sample_build.cpp);
// so does the benchmark, for the lattice blocks too (their lattice order puts a grain's upper
// neighbours a layer away in memory).
ParticleStore sorted_as_a_run_does(const ParticleStore& ps) {
  GeometryData g = GeometryData::of_store(ps);
  sort_spatially(g);
  return g.make_store();
}

template <class Bond>
void bond_sample(Simulation& sim, bool broken, double gap_tolerance) {
  typename Bond::Params bp;
  if constexpr (std::is_same_v<Bond, ParallelBond>) {
    if (broken) bp.tensile_strength = bp.cohesion = 1e4;
  } else if constexpr (std::is_same_v<Bond, QuaternionBond>) {
    bp.contact_while_bonded = false;  // as LAMMPS bpm/rotational without overlay/pair
    if (broken) bp.tensile_strength = bp.shear_strength = 1e4;
  } else {
    bp.bending_factor = 0.5;  // ESyS-Particle's conventions
    bp.contact_while_bonded = false;
    if (broken) bp.cohesion = 1e4;
  }
  sim.set_bond_params<Bond>(bp);
  sim.bond_touching_pairs<Bond>(gap_tolerance);
}

}  // namespace

namespace {

// Every rank's count, in rank order (each rank's own part of a split sample).
std::vector<std::size_t> each_rank(std::size_t mine) {
  std::vector<std::size_t> counts;
  for (const std::string& s : ranks::all_gather(std::to_string(mine)))
    counts.push_back(std::stoull(s));
  return counts;
}

// A count summed over the ranks.
std::size_t over_ranks(std::size_t mine) {
  std::size_t total = 0;
  for (const std::size_t n : each_rank(mine)) total += n;
  return total;
}

// Every rank's work, in rank order (what a balance by grain count leaves unequal), with its share
// of the timed steps spent inside exchanges. `shares` returns those shares, lowest first: the
// lowest is the slowest rank's, which waits for no one, so it bounds the exchanges' own cost; what
// the others spend beyond it is waiting for that rank (load imbalance, or a core shared with other
// work).
nlohmann::json work_of_each_rank(const Simulation& sim, double my_exchange_share,
                                 std::vector<double>& shares) {
  shares.clear();
  for (const std::string& r : ranks::all_gather(std::to_string(my_exchange_share)))
    shares.push_back(std::stod(r));
  const nlohmann::json per_rank{{"exchange_share", shares},
                                {"grains", each_rank(sim.owned_particles().size())},
                                {"intact_bonds", each_rank(sim.intact_bonds())},
                                {"contacts", each_rank(sim.active_contacts())},
                                {"neighbour_pairs", each_rank(sim.neighbour_pairs())},
                                {"ghosts", each_rank(sim.split_traffic().ghosts)},
                                {"shares_sent", each_rank(sim.split_traffic().shares_sent)}};
  std::sort(shares.begin(), shares.end());
  return per_rank;
}

}  // namespace

int main(int argc, char** argv) {
  const ranks::World world(argc, argv);
  breccia::configure_allocator();
  CLI::App app{"Breccia engine benchmark"};
  int dim = 3, threads = 1, steps = 200, repeats = 3, warmup = 200;
  long particles = 100000;
  std::string phase = "elastic", sample = "block", bond = "parallel_bond";
  app.add_option("--dim", dim)->check(CLI::IsMember({2, 3}));
  app.add_option("--sample", sample)->check(CLI::IsMember({"block", "cylinder"}));
  app.add_option("--bond", bond)
      ->check(CLI::IsMember({"parallel_bond", "brittle_beam", "quaternion_bond"}));
  app.add_option("--particles", particles, "approximate particle count");
  app.add_option("--phase", phase)->check(CLI::IsMember({"elastic", "broken"}));
  app.add_option("--threads", threads);
  app.add_option("--steps", steps, "steps per timed repeat");
  app.add_option("--repeats", repeats, "timed repeats (the median is reported)");
  app.add_option("--warmup", warmup, "steps before timing");
  double skin = 0.0;
  app.add_option("--skin", skin, "neighbour-list skin in m (0: the engine's default)");
  bool keep_pair_forces = false;
  app.add_flag("--keep-pair-forces", keep_pair_forces,
               "keep every pair's force in an array even where the laws' states give it back "
               "(the reference path, for comparison)");
  bool keep_subnormals = false;
  app.add_flag("--keep-subnormals", keep_subnormals,
               "compute with subnormal numbers as the hardware does by default (breccia flushes "
               "them to zero; for comparison)");
  bool split = false;
  app.add_flag("--split", split,
               "under mpirun: split the sample over the ranks (each steps its own particles)");
  std::string instruction_set = "auto";
  app.add_option("--instruction-set", instruction_set,
                 "the kernels' instruction set (engine.instruction_set): auto, baseline or "
                 "x86-64-v3")
      ->check(CLI::IsMember({"auto", "baseline", "x86-64-v3"}));
  CLI11_PARSE(app, argc, argv);
  if (sample == "cylinder" && dim != 3) {
    std::fprintf(stderr, "bench_engine: --sample cylinder is 3D only (got --dim %d)\n", dim);
    return 2;
  }
  if (!keep_subnormals) flush_subnormals();  // as breccia's main does, before the threads start
  set_threads(threads);

  const double R = 0.5e-3;
  const auto c = cells_for(dim, particles);
  const auto t_pack = std::chrono::steady_clock::now();
  ParticleStore ps = sample == "cylinder" ? random_cylinder(particles)
                     : dim == 3           ? fcc_block(c[0], c[1], c[2], R, 2650)
                                          : hex_block(c[0], c[1], R, 2650, 2 * R);
  const double pack_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_pack).count();
  const bool broken = phase == "broken";
  if (broken)
    for (std::size_t i = 0; i < ps.size(); ++i)
      for (int k = 0; k < dim; ++k) ps.vel[i][k] = 0.01 * standard_normal(99, k, i);
  if (sample == "block") ps = sorted_as_a_run_does(ps);
  EngineConfig cfg;
  cfg.local_damping = 0.7;
  cfg.energy_interval = 100;
  cfg.skin = skin;
  cfg.keep_pair_forces = keep_pair_forces;
  if (instruction_set != "auto") cfg.instruction_set = instruction_set_from_name(instruction_set);
  LinearContact::Params lp, wall;
  wall.friction = 0.0;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>(lp, wall));
  const auto t_setup = std::chrono::steady_clock::now();
  const double gap_tolerance = sample == "cylinder" ? 1e-8 : 1e-9;
  if (bond == "parallel_bond")
    bond_sample<ParallelBond>(sim, broken, gap_tolerance);
  else if (bond == "quaternion_bond")
    bond_sample<QuaternionBond>(sim, broken, gap_tolerance);
  else
    bond_sample<BrittleBeam>(sim, broken, gap_tolerance);
  PlatenCompressionSettings ls;
  ls.platen_speed = broken ? 0.5 : 0.05;
  ls.ramp_time = 1e-12;
  PlatenCompression platens(sim, ls);
  sim.initialise();
  if (split) sim.split_over_ranks();
  // Crack records as a run keeps them: the newest in memory, the older ones in a file.
  const std::filesystem::path crack_file = std::filesystem::temp_directory_path() /
                                           fmt::format("bench-engine-cracks-{}.bin", ::getpid());
  sim.record_cracks_in(crack_file);
  struct RemoveAtExit {
    std::filesystem::path path;
    ~RemoveAtExit() { std::filesystem::remove(path); }
  } remove_crack_file{crack_file};
  const double setup_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_setup).count();
  const std::size_t bonds0 = over_ranks(sim.intact_bonds());
  sim.run(static_cast<std::uint64_t>(warmup));

  std::vector<double> rates;
  std::size_t bond_steps_total = 0;
  std::vector<double> bond_rates, exchange_shares;
  double exchanged_all = 0.0, timed_all = 0.0;  // this rank's, over every repeat
  for (int r = 0; r < repeats; ++r) {
    const std::size_t bonds_before = over_ranks(sim.intact_bonds());
    ranks::barrier();
    const auto t0 = std::chrono::steady_clock::now();
    const double exchanged0 = ranks::exchange_seconds();
    sim.run(static_cast<std::uint64_t>(steps));
    const double exchanged = ranks::exchange_seconds() - exchanged0;
    ranks::barrier();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    exchange_shares.push_back(exchanged / s);
    exchanged_all += exchanged;
    timed_all += s;
    rates.push_back(static_cast<double>(sim.particles().size()) * steps / s);
    // Bond-steps: intact bonds evaluated per step (mean of the bounds of the repeat).
    const double mean_bonds =
        0.5 * static_cast<double>(bonds_before + over_ranks(sim.intact_bonds()));
    bond_rates.push_back(mean_bonds * steps / s);
    bond_steps_total += static_cast<std::size_t>(mean_bonds * steps);
  }
  std::sort(rates.begin(), rates.end());
  std::sort(exchange_shares.begin(), exchange_shares.end());
  const double exchange_share = exchange_shares[exchange_shares.size() / 2];
  const int n_ranks = ranks::size();
  const std::size_t intact_end = over_ranks(sim.intact_bonds());
  const std::size_t contacts_end = over_ranks(sim.active_contacts());
  const std::size_t pairs_end = over_ranks(sim.neighbour_pairs());
  const std::size_t cross_end = over_ranks(sim.cross_block_pairs());
  std::size_t peak_rss = 0;  // the largest rank's
  for (const std::string& r : ranks::all_gather(std::to_string(peak_rss_bytes())))
    peak_rss = std::max<std::size_t>(peak_rss, std::stoull(r));
  std::vector<double> rank_exchange_shares;
  const nlohmann::json per_rank =
      work_of_each_rank(sim, exchanged_all / timed_all, rank_exchange_shares);
  const Simulation::SplitTraffic traffic = sim.split_traffic();
  const std::size_t ghosts = over_ranks(traffic.ghosts), shares = over_ranks(traffic.shares_sent);
  if (!ranks::root()) return 0;
  const int cores = n_ranks * threads;
  std::sort(bond_rates.begin(), bond_rates.end());
  const double rate = rates[rates.size() / 2], bond_rate = bond_rates[bond_rates.size() / 2];
  // Block and parallel-bond cases keep their historical names ("3d-99k-elastic").
  std::string name = fmt::format("{}d-{}k-{}", dim, (sim.particles().size() + 500) / 1000, phase);
  if (sample == "cylinder") name = "cyl-" + name;
  if (bond == "brittle_beam") name += "-beam";
  if (bond == "quaternion_bond") name += "-quat";
  if (keep_pair_forces) name += "-kept";
  if (keep_subnormals) name += "-subnormals";
  if (n_ranks > 1) name += fmt::format("-{}ranks{}", n_ranks, sim.split() ? "" : "-unsplit");
  std::fprintf(stderr,
               "%-16s ranks %d x threads %d: %zu particles, %zu/%zu bonds intact, %zu contacts, "
               "%zu pairs (%zu across blocks); %.3g particle-steps/s (%.3g per core), %.3g "
               "bond-steps/s, %.0f%% of the time in exchanges (ranks: %.0f-%.0f%%; %zu ghosts, %zu "
               "shares a step), %.0f B/particle peak (largest rank)\n",
               name.c_str(), n_ranks, threads, sim.particles().size(), intact_end, bonds0,
               contacts_end, pairs_end, cross_end, rate, rate / cores, bond_rate,
               100.0 * exchange_share, 100.0 * rank_exchange_shares.front(),
               100.0 * rank_exchange_shares.back(), ghosts, shares,
               static_cast<double>(peak_rss) / static_cast<double>(sim.particles().size()));
  nlohmann::json j{{"case", name},
                   {"dim", dim},
                   {"phase", phase},
                   {"sample", sample},
                   {"bond_law", bond},
                   {"keep_pair_forces", keep_pair_forces},
                   {"subnormals_flushed", subnormals_flushed()},
                   {"pack_s", pack_s},
                   {"particles", sim.particles().size()},
                   {"bonds", bonds0},
                   {"bonds_intact_end", intact_end},
                   {"contacts_end", contacts_end},
                   {"neighbour_pairs_end", pairs_end},
                   {"cross_block_pairs_end", cross_end},
                   {"ranks", n_ranks},
                   {"split", sim.split()},
                   {"threads", threads},
                   {"instruction_set", instruction_set_name(sim.instruction_set())},
                   {"steps", steps},
                   {"repeats", repeats},
                   {"particle_steps_per_s", rate},
                   {"particle_steps_per_s_per_thread", rate / cores},
                   {"bond_steps_per_s", bond_rate},
                   {"bond_steps_per_s_per_thread", bond_rate / cores},
                   {"all_particle_steps_per_s", rates},
                   {"exchange_share", exchange_share},
                   {"exchange_share_lowest_rank", rank_exchange_shares.front()},
                   {"exchange_share_highest_rank", rank_exchange_shares.back()},
                   {"per_rank", per_rank},
                   {"ghosts", ghosts},
                   {"shares_per_step", shares},
                   {"setup_s", setup_s},
                   {"peak_rss_bytes", peak_rss},
                   {"peak_rss_bytes_per_particle",
                    static_cast<double>(peak_rss) / static_cast<double>(sim.particles().size())},
                   {"version", kVersion},
                   {"machine", machine_description()}};
  std::printf("%s\n", j.dump().c_str());
  (void)bond_steps_total;
  return 0;
}
