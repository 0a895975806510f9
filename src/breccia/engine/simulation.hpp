#pragma once
// The engine: particles, bonds of every registered law, the contact law, walls, neighbour search
// and the leapfrog integrator with local damping (docs/physics.md §1-§4, §6.1). It knows nothing
// about lab tests: protocols drive it through walls, driven particles and external forces, and read
// it through const views, the crack catalogue and the energy ledger.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <tuple>
#include <variant>
#include <vector>

#include "breccia/boundary/wall.hpp"
#include "breccia/core/instruction_set.hpp"
#include "breccia/engine/crack_catalogue.hpp"
#include "breccia/engine/domain.hpp"
#include "breccia/engine/events.hpp"
#include "breccia/law/registry.hpp"
#include "breccia/state/bond_set.hpp"
#include "breccia/state/joint_plane.hpp"
#include "breccia/state/particle_store.hpp"

namespace breccia {

class ArchiveWriter;
class ArchiveReader;

struct EngineConfig {
  double time_step = 0.0;              // s; 0 = use the critical estimate times safety_factor
  double safety_factor = 0.3;          // S of §1.5
  double hertz_rayleigh_factor = 0.2;  // fraction of the Rayleigh time step for Hertz contacts
  double local_damping = 0.0;          // Cundall alpha (§2.1)
  // Dynamic damping (§2.1): for dynamic_damping_time after a crack, the free grains within
  // dynamic_damping_radius of it are damped with dynamic_damping_alpha instead of local_damping,
  // so that the crack's stored energy leaves as waves. Off while either is 0.
  double dynamic_damping_alpha = 0.0;
  double dynamic_damping_radius = 0.0;  // m
  double dynamic_damping_time = 0.0;    // s
  // Dashpots in parallel with every intact bond, as critical-damping ratios of its normal and
  // shear stiffness (§2.2); 0 = none.
  double bond_normal_damping_ratio = 0.0;
  double bond_shear_damping_ratio = 0.0;
  Vec3 gravity;                         // m/s^2
  double skin = 0.0;                    // m; 0 = 0.4 x the mean radius
  std::uint64_t seed = 1;               // strengths and anything else random
  std::uint64_t energy_interval = 100;  // steps between energy-ledger samples (0 = on demand)
  // The reference path of Simulation::pair_force: the pair pass keeps every pair's force in an
  // array even where the laws' states give it back (tests compare the two).
  bool keep_pair_forces = false;
  // The instruction set of the pair pass and the integrator (core/instruction_set.hpp); none =
  // the best this CPU runs.
  std::optional<InstructionSet> instruction_set;
};

// One sample of the energy budget at time t_n (docs/physics.md §2.4). Cumulative terms count from
// the start of the run; the balance residual is taken against the first sample (the baseline).
struct EnergyLedger {
  std::uint64_t step = 0;
  double time = 0.0;
  // Stored at t_n.
  double kinetic_translational = 0.0;
  double kinetic_rotational = 0.0;
  BondEnergy bond;       // intact bonds, by component
  double contact = 0.0;  // particle-particle and particle-wall contacts
  // Cumulative.
  double boundary_work = 0.0;    // walls and driven particles
  double body_force_work = 0.0;  // gravity
  double external_work = 0.0;    // external per-particle loads (membranes)
  double joint_dilation = 0.0;   // work into smooth joints' normal springs by dilation (§5)
  double friction = 0.0;         // Coulomb sliding, smooth joints included
  double joint_slip = 0.0;       // the part of `friction` that slid on smooth joints
  double local_damping = 0.0;
  double viscous_damping = 0.0;
  double deleted = 0.0;  // springs lost without work
  BondEnergy released;   // energy released by broken bonds, by component
  std::uint64_t broken_bonds = 0;
  // Balance against the baseline sample: work in minus (change of stored + dissipated).
  double residual = 0.0;
  double residual_relative = 0.0;  // residual / max(|work in|, change of stored energy)

  double kinetic() const noexcept { return kinetic_translational + kinetic_rotational; }
  double stored() const noexcept { return kinetic() + bond.total() + contact; }
  double work_in() const noexcept {
    return boundary_work + body_force_work + external_work + joint_dilation;
  }
  double dissipated() const noexcept {
    return friction + local_damping + viscous_damping + deleted + released.total();
  }
};

// The contact law in use, chosen at run time from the registry.
template <class List>
struct ContactVariantOf;
template <class... Laws>
struct ContactVariantOf<TypeList<Laws...>> {
  using type = std::variant<ContactSet<Laws>...>;
};
using ContactModel = ContactVariantOf<EngineContactLaws>::type;

template <class List>
struct BondTupleOf;
template <class... Laws>
struct BondTupleOf<TypeList<Laws...>> {
  using type = std::tuple<BondSet<Laws>...>;
};
using BondSets = BondTupleOf<BondLaws>::type;
// The joint elements of each joint law: pairs cut by a joint plane, in the bond-set layout. A
// joint element is never removed: a bonded joint that breaks goes on unbonded, and an unbonded
// one whose pair separates waits, stress-free, until the pair touches again.
using JointSets = BondTupleOf<JointLaws>::type;

template <class List>
struct WallContactVariantOf;
template <class... Laws>
struct WallContactVariantOf<TypeList<Laws...>> {
  using type = std::variant<std::vector<WallContacts<Laws>>...>;
};

// Builds the contact model for a law with its particle and wall parameters: the law's state
// layout with the rolling and twisting moments when either set of parameters turns them on.
template <class Law>
ContactModel make_contact_model(const typename Law::Params& particle,
                                const typename Law::Params& wall) {
  auto make = [&]<class Layout>() {
    ContactSet<Layout> c;
    c.params = particle;
    c.wall_params = wall;
    return ContactModel{std::in_place_type<ContactSet<Layout>>, std::move(c)};
  };
  if (rolling_limits(particle).on() || rolling_limits(wall).on())
    return make.template operator()<typename Law::template with_rolling<true>>();
  return make.template operator()<typename Law::template with_rolling<false>>();
}

// Per-block partial sums of the integrator (kept in a member: no allocation per step).
struct IntegrateBlock {
  double local_damping = 0.0, gravity = 0.0, drive = 0.0, external = 0.0;
  double ke_t = 0.0, ke_r = 0.0;
  double max_disp2 = 0.0;
  // Half-step terms that belong to the next interval, removed from a sample (see integrate()).
  double damping_boundary = 0.0, external_boundary = 0.0;
};

// Per-block partial sums of the wall pass, for one wall (kept in a member: no allocation per step).
struct WallBlock {
  PairDissipation dissipation;
  Vec3 force;                            // on the grains
  double radial = 0.0, stiffness = 0.0;  // normal force, contact stiffness
  std::size_t touching = 0;
};

// A sample split over the ranks of an MPI launch (engine/rank_split.cpp; ARCHITECTURE.md, "Ranks
// (MPI)"): every rank keeps the whole particle store, but steps only its own particles, keeps
// only the bonds, pairs and wall contacts whose first grain is its own, and keeps its ghosts (the
// later ranks' grains its pairs reach) current from their owners every step. The other grains'
// entries are stale between gathers (Simulation::gather_particles).
struct RankSplit {
  std::vector<IndexRange> ranges;  // every rank's particles
  IndexRange own;
  GhostPlan plan;  // at the last neighbour rebuild
  // Loads received for the own grains from pairs of earlier ranks (in the order they came, then
  // by grain).
  std::vector<Share<CrossSlot>> received;
  std::size_t shares_sent = 0;  // in the last step
  // The shares each rank sends this one a step: fixed from one ghost plan to the next (the pairs
  // are), counted once after each plan is made (empty until then), so that a step's loads travel
  // in one exchange of known sizes.
  std::vector<std::uint64_t> shares_from;
  IncomingShares<CrossSlot> incoming;
  std::vector<CrackRecord> cracks;  // this rank's cracks of the step, in pair order
  bool bonds_anywhere = false;      // a bond or joint on some rank (central_forces_only)
  bool particles_whole = true;      // every grain's entries current (gathered since the step)
  // The integrator's block partials of the last step travel with the next step's ghosts, and are
  // added then (Simulation::finish_integration), in step order, as one process adds them.
  bool integration_pending = false;
  bool stop_here = false;      // this rank's stop request, sent with the next step's loads
  bool stop_anywhere = false;  // some rank's, received with the last step's loads
};

// The grains a reader of a split sample needs current besides its own and the walls: none, a
// few (ascending indexes), or all of them. Readers declare them so that a run brings only those
// from their owners (Simulation::gather_grains) instead of every grain after every step.
struct GrainReads {
  bool all = false;
  std::span<const std::uint32_t> some;  // when not all
  static GrainReads every() { return {.all = true, .some = {}}; }
};

// Stress carried by the pair forces (docs/physics.md §6.5): the sum over interacting pairs of l (x)
// F, with l = x2 - x1 and F the force on particle 2, so a repulsion counts compression-positive.
// Divide by the sample volume for the average stress tensor.
struct PairStress {
  std::array<double, 9> lf{};  // row-major sum of l_i F_j, N m
  double radius_stiffness =
      0.0;  // sum over touching pairs of k_n (R1 + R2) d (docs/physics.md §7.2)
  // Per axis a, the sum over touching pairs of k_n l_a^4 / |l|^2, N m: V times the stiffness
  // d sigma_aa / d eps_aa of the normal springs under an affine strain along a.
  std::array<double, 3> axial_stiffness{};
  std::size_t touching = 0;                 // pairs in contact (overlapping), bonded or not
  std::vector<std::uint32_t> coordination;  // touching pairs per particle

  double mean(int dimension, double volume) const noexcept {
    double tr = 0.0;
    for (int k = 0; k < dimension; ++k) tr += lf[static_cast<std::size_t>(4 * k)];
    return tr / (dimension * volume);
  }
};

class Simulation {
 public:
  Simulation(ParticleStore particles, EngineConfig config, ContactModel contact);
  // Bond laws start with their default parameters (prepared).

  // --- set-up (before initialise) ---
  // Adds a bond of `Law` between two particles by tag; installed (stress-free at the current
  // geometry) by initialise(). Returns the bond tag.
  template <class Law>
  std::uint64_t add_bond(std::uint64_t tag1, std::uint64_t tag2);
  template <class Law>
  void set_bond_params(const typename Law::Params& p);
  // Bonds every pair whose gap is at most gap_tolerance (docs/physics.md §7.6). Returns the count.
  template <class Law>
  std::size_t bond_touching_pairs(double gap_tolerance);
  // Adds a wall; before initialise() or between two steps (its contacts are then found at once;
  // the time step stays as estimated: a wall contact adds about one grain contact's stiffness
  // to the particles it touches, well inside the safety factor's margin).
  std::size_t add_wall(Wall w);
  // Adds a joint plane (docs/physics.md §5): at initialise() the bonds it cuts are replaced by
  // joints of the joint law (bonded joints when its parameters say so), and every neighbour pair it
  // cuts that is not yet in contact becomes an unbonded joint, at every neighbour-list rebuild.
  void add_joint_plane(JointPlane plane);
  template <class Law>
  void set_joint_params(const typename Law::Params& p);
  // Installs bonds, builds neighbour lists and fixes the time step. Throws InputError on an
  // inconsistent set-up (for example Hertz contacts on 2D disks).
  void initialise();

  // --- stepping ---
  void step();
  void run(std::uint64_t steps);
  void request_energy_sample() noexcept { sample_requested_ = true; }
  // Multiplies every radius by `factor` at constant density (masses follow). For packing by
  // radius expansion (docs/physics.md §7.2) only: it is refused once bonds exist, and the energy
  // ledger restarts its baseline because stored energy changes without work.
  void scale_radii(double factor);
  // Sets one particle's radius at constant density (packing: growing floaters). Same rules as
  // scale_radii.
  void set_radius(std::size_t index, double radius);
  // Moves one particle to `position` with `radius` (at rest), before bonds exist (packing: a
  // floater placed snug in its cage). The neighbour lists are rebuilt before the next step.
  void place_particle(std::size_t index, const Vec3& position, double radius);
  // Moves one particle by `dx` between two steps, keeping its velocity (packing: an affine
  // compaction imposed on every grain at once). Same rules as scale_radii; the neighbour lists
  // see the move through their skin test.
  void displace_particle(std::size_t index, const Vec3& dx);
  // Ends the stepping of a finished run: frees the neighbour list with its contact histories and
  // any pair forces, the pair-to-bond indexes and the pair pass's scratch (about 300 B a grain of a
  // bonded 3D sample), so that the analysis that follows has that room. What it reads stays: the
  // grains, bonds, joints, walls, ledger and cracks. A retired simulation refuses to step or to
  // write a checkpoint, and reports no contacts or pair forces.
  void retire_interactions();
  bool retired() const noexcept { return retired_; }
  // Estimates the time step again for the current geometry (packing stages, whose radii and
  // contacts change a lot between the start and the end); refused once bonds exist.
  void refresh_time_step();
  // Changes the particle-particle friction coefficient of the contact law (packing stages).
  void set_contact_friction(double mu) {
    std::visit([&](auto& c) { c.params.friction = mu; }, contact_);
  }
  // Changes the local damping coefficient between two steps (scripted stages); throws
  // InputError outside 0 <= alpha < 1.
  void set_local_damping(double alpha);
  // Turns dynamic damping on (radius and time > 0) or off (both 0) between two steps; throws
  // InputError outside 0 <= alpha < 1 or for a negative radius or time.
  void set_dynamic_damping(double alpha, double radius, double time);
  // Until when grain i is damped with the dynamic-damping coefficient (-inf: not since the last
  // crack near it, or dynamic damping off).
  double dynamically_damped_until(std::size_t i) const noexcept;

  // The engine's own arrays per particle besides the store (run/memory_budget.cpp): positions at
  // the last rebuild and the pair list's two offsets (driver loads only with driven grains).
  static constexpr std::size_t kScratchBytesPerParticle = sizeof(Vec3) + 2 * sizeof(std::uint32_t);

  // --- ranks (engine/rank_split.cpp) ---
  // Splits the sample over the ranks of the launch (collective; nothing with one rank): from now
  // on each rank steps its own particles (split_indexes) with the results of one process to the
  // bit. Between steps the particle store is current for the own particles and the ghosts only;
  // counts and views of bonds, contacts and pairs cover the own ones. Initialises first.
  void split_over_ranks();
  bool split() const noexcept { return split_ != nullptr; }
  // What this rank exchanges each step (zeros when not split): its ghosts, and the shares of the
  // last step it sent and received.
  struct SplitTraffic {
    std::size_t ghosts = 0, shares_sent = 0, shares_received = 0;
  };
  SplitTraffic split_traffic() const noexcept {
    if (!split_) return {};
    return {split_->plan.ghosts.size(), split_->shares_sent, split_->received.size()};
  }
  // The particles this rank steps (all of them when the sample is not split).
  IndexRange owned_particles() const noexcept {
    return split_ ? split_->own : IndexRange{0, p_.size()};
  }
  // Every rank's particles, in rank order (empty when the sample is not split).
  const std::vector<IndexRange>& rank_ranges() const noexcept;
  // Makes every rank's particle store whole and current (collective): positions, velocities,
  // orientations, displacements and the last step's loads. Nothing when it is current already
  // (no step since the last gather).
  void gather_particles();
  // Makes the grains a reader declares current on every rank (collective: every rank passes the
  // same): all of them through gather_particles, or the listed ones from their owners.
  void gather_grains(const GrainReads& reads);
  // Gathers a split sample back whole on every rank (collective): the particles, the lists, the
  // contact histories, the bonds and joints and the wall contacts, each in the order one process
  // holds them, so that the state is that one process would hold at this step to the bit (its
  // checkpoint is that process's). Afterwards every rank steps the whole sample; split_over_ranks
  // splits it again. Nothing when not split.
  void unsplit();
  // The ranks of a split sample stop at one step: each passes its own request (a signal that
  // reached it) before a step, the step carries it to every rank with its loads, and after it
  // stop_requested_anywhere() is the same on all of them. A sample not split: nothing, and false.
  void request_stop(bool stop) noexcept;
  bool stop_requested_anywhere() const noexcept;

  // The bonds of the whole sample, in one process's order (collective on a split sample; a copy
  // of the sets, without their pair index, otherwise).
  BondSets whole_bonds() const;
  // The whole sample's intact bonds and contacts in touch (collective on a split sample).
  struct SampleCounts {
    std::size_t intact_bonds = 0, active_contacts = 0;
  };
  SampleCounts sample_counts() const;
  // Whether this process writes what a run records: every process of an unsplit sample (a
  // sweep's runs under mpirun write their own folders), only root of a split one.
  bool lead_rank() const noexcept;

  // --- views ---
  const ParticleStore& particles() const noexcept { return p_; }
  ParticleStore& particles_mut() noexcept { return p_; }  // protocols: drives and fixities only
  const EngineConfig& config() const noexcept { return cfg_; }
  // The instruction set the hot kernels run in (the config's, or the best this CPU runs).
  InstructionSet instruction_set() const noexcept { return isa_; }
  double time_step() const noexcept { return dt_; }
  double critical_time_step() const noexcept { return dt_crit_; }
  double time() const noexcept { return time_; }
  std::uint64_t step_count() const noexcept { return step_; }
  std::vector<Wall>& walls() noexcept { return walls_; }
  const std::vector<Wall>& walls() const noexcept { return walls_; }
  const CrackCatalogue& cracks() const noexcept { return cracks_; }
  // From now on the crack catalogue keeps only its newest records in memory and appends the
  // older ones to `file` (a run's folder); reattach_cracks() reopens that file after a restore.
  void record_cracks_in(const std::filesystem::path& file,
                        std::size_t resident = CrackCatalogue::kResidentRecords) {
    cracks_.spill_to(file, resident);
  }
  void reattach_cracks(const std::filesystem::path& file,
                       std::size_t resident = CrackCatalogue::kResidentRecords) {
    cracks_.reattach(file, resident);
  }
  const std::vector<std::string>& warnings() const noexcept { return warnings_; }
  const EnergyLedger& ledger() const noexcept { return ledger_; }
  const BondSets& bonds() const noexcept { return bonds_; }
  const JointSets& joints() const noexcept { return joints_; }
  const std::vector<JointPlane>& joint_planes() const noexcept { return joint_planes_; }
  // Joint elements (bonded or not) and the bonded ones among them.
  std::size_t joint_count() const noexcept;
  std::size_t bonded_joints() const noexcept;
  const ContactModel& contact_model() const noexcept { return contact_; }
  std::size_t intact_bonds() const noexcept;
  // The places where bonds can still break, each a crack: an intact bond, or a bonded element of
  // a law that breaks element by element (the flat joint).
  std::size_t intact_bond_sites() const noexcept;
  // The radii of the grains of pair (i, j): what a bond's section follows from.
  BondRadii bond_radii(std::uint32_t i, std::uint32_t j) const noexcept {
    return {p_.pos_rad[i].r, p_.pos_rad[j].r};
  }
  // Calls f(first, second) with the particle indexes of each intact bond of every law, in law
  // and bond order (fragments, wear); collective on a split sample, whose whole bonds it visits.
  void for_each_intact_bond(const std::function<void(std::uint32_t, std::uint32_t)>& f) const;
  // The moduli of the bond law called `law` with this simulation's parameters (crack records
  // name their law); zero for a name that is not a bond law.
  BondModuli bond_moduli(std::string_view law) const noexcept;
  std::size_t active_contacts() const noexcept;
  std::size_t neighbour_pairs() const noexcept;
  // Pairs whose second grain lies in a later particle block of the pair pass (pair_list.hpp).
  std::size_t cross_block_pairs() const noexcept;
  // The force on pair k's second grain in the last step, for the contact set in use (k below its
  // pair count). Where every law in use keeps its force in its state (has_state_force), it is the
  // sum of the pair's bond, joint and contact state forces in the pair pass's order, the pass's
  // number to the bit, and the engine holds no array of pair forces (24 B a pair); otherwise
  // (dashpots, beams, laws judged on the interface) the pass keeps one and this reads it.
  // The sum runs in the pass's instruction set: the pass's fused multiply-adds are its rounding.
  template <class CL>
  Vec3 pair_force(const ContactSet<CL>& c, std::size_t k) const noexcept {
    if (keep_pair_forces_) return c.kept_force[k];
    Vec3 f;
    with_instruction_set(isa_, [&] {
      std::apply([&](const auto&... set) { (add_state_force(set, k, true, f), ...); }, bonds_);
      std::apply([&](const auto&... set) { (add_state_force(set, k, false, f), ...); }, joints_);
      if constexpr (has_state_force<CL>)
        if (c.history[k] != kNoHistory) f += CL::state_force(c.state(k));
    });
    return f;
  }
  // Whether the pair pass keeps the array of pair forces (above).
  bool keeps_pair_forces() const noexcept { return keep_pair_forces_; }
  // The loads of the neighbour pairs of each grain of `grains` (ascending), as one process lists
  // them: for grain p, (q, the force p exerts on q) for the pairs where p is first in list order,
  // then for those where it is second in ascending slot order. Grain a's loads are
  // loads[offsets[a], offsets[a + 1]). A scan of the list; collective on a split sample, where
  // every rank gets the whole answer.
  struct PairLoad {
    std::uint32_t other = 0;
    Vec3 force;
  };
  void pair_loads_around(const std::vector<std::uint32_t>& grains,
                         std::vector<std::uint32_t>& offsets, std::vector<PairLoad>& loads) const;
  // Pair forces of the last step as a stress sum and contact counts (docs/physics.md §6.5, §7.2).
  PairStress pair_stress() const;
  // Per-particle stress of the last step's forces (docs/physics.md §6.5), compression-positive,
  // row-major 3x3 in Pa: -(1/V_p) sum (x_c - x_p) (x) F over the particle's pairs and wall
  // contacts, symmetrised (bond couples only add an antisymmetric part); V_p is the sphere's
  // volume, or pi R^2 t in 2D. Loads applied at the centres (membranes) have no lever arm and
  // add nothing.
  std::vector<std::array<double, 9>> particle_stress() const;
  // particle_stress() one particle at a time, in increasing index order, with the same sums in
  // the same order, without holding a tensor for every particle (72 B a grain in a snapshot).
  class ParticleStressStream {
   public:
    // Particles' incoming pairs are indexed `chunk` particles at a time.
    static constexpr std::size_t kChunk = std::size_t{1} << 16;
    explicit ParticleStressStream(const Simulation& sim, std::size_t chunk = kChunk);
    std::array<double, 9> at(std::size_t p);  // p ascending from one call to the next

   private:
    const Simulation& sim_;
    std::vector<std::size_t> wall_at_;  // per wall: the first contact entry not yet passed
    // The pairs where each particle of [chunk_begin_, chunk_end_) is second, in ascending slot
    // order (the neighbour list keeps no such index; one for every grain would cost 4 B a pair
    // while a snapshot is written): particle p's are in_slot_[in_offsets_[p - chunk_begin_] ...).
    void read_chunk(std::size_t begin);
    std::size_t chunk_ = kChunk, chunk_begin_ = 0, chunk_end_ = 0;
    std::vector<std::uint32_t> in_offsets_, in_slot_;
  };
  std::uint64_t neighbour_rebuilds() const noexcept { return rebuilds_; }
  // External per-particle load for the coming step (membranes, follower loads); its work is
  // booked as external work. Allocated on first use; cleared after each step.
  std::vector<Vec3>& external_force() {
    user_force_.resize(p_.size());
    return user_force_;
  }

  // --- checkpoints (engine/checkpoint.cpp) ---
  // Writes the complete state between two steps: a simulation restored from it continues
  // exactly, bit for bit, as this one would have (same neighbour lists in the same order, same
  // contact histories, ledger accumulators and crack catalogue).
  void save_state(ArchiveWriter& a) const;
  static Simulation restore(ArchiveReader& a);

 private:
  struct RestoreTag {};
  explicit Simulation(RestoreTag) {}
  template <class Archive>
  void transfer(Archive& a);  // the checkpoint's field list (engine/checkpoint.cpp)
  template <class Archive>
  void transfer_contacts(Archive& a);
  template <class Archive>
  void transfer_cracks(Archive& a);
  // The stages of a step, each in its own file of engine/: the neighbour list (neighbours.cpp),
  // the pass over pairs (pair_pass.cpp), the walls (wall_pass.cpp), the integrator
  // (integrator.cpp) and the ledger's stored energies (energy_ledger.cpp). Each dispatches once on
  // the contact law in use and runs its loops for that law (`*_for`), without virtual calls.
  void rebuild();
  // The rank's pairs: its own grains' pairs with its own grains and its ghosts, by global index
  // (a new ghost plan, the ghosts' values sent).
  void build_own_pairs(PairList& out);
  std::vector<std::uint32_t> bond_partners_beyond() const;
  // The ghosts' values from their owners (collective), and with them, when `with_integration`,
  // every rank's integrator block partials of the last step to all.
  void refresh_ghosts(bool with_integration = false);
  // After the pair and wall passes (collective): the shares of cross pairs to their grains'
  // owners, and every rank's block partials of the two passes, stop request and crack count to
  // all; the cracks themselves in a second exchange, in the steps that have any.
  void exchange_step_loads(const PairList& pairs);
  void exchange_step_cracks(const std::vector<std::uint64_t>& crack_counts);
  // The integrator's sums of a step: its block partials added in block order into the work,
  // damping and largest-displacement totals (and the kinetic energy of a sampled step).
  void add_integration_totals(bool sample);
  // A split sample's integrator partials still waiting for the next step's ghost exchange, made
  // whole and added now (collective; nothing otherwise): before a rebuild or a gather reads the
  // totals.
  void finish_integration();
  void add_pair_dissipation();
  // Whether this rank, or any rank, holds a bond or joint element (bonds_anywhere is noted at
  // every rebuild, where the sets change).
  void refuse_on_split_sample(const char* what) const;
  bool bonds_here() const noexcept;
  bool bonds_anywhere() const noexcept;
  void note_bonds_anywhere();
  void compute_pairs();
  void compute_walls();
  void integrate(bool sample);
  // Dynamic damping (engine/dynamic_damping.cpp): the rank's own grains within the radius of the
  // cracks [first_crack, end) of the catalogue are damped less until each crack's time plus the
  // window; called once the step's cracks of every rank are in the catalogue.
  void mark_dynamic_damping(std::size_t first_crack);
  void build_dynamic_damping_grid();
  void sample_stored_energy();
  void advance_walls();
  template <class CL>
  void rebuild_for(ContactSet<CL>& contacts);
  template <class CL>
  void compute_pairs_for(ContactSet<CL>& contacts);
  template <class CL>
  void compute_pair_block(ContactSet<CL>& contacts, std::size_t block);
  template <class CL>
  class PairWalk;  // one block's walk of the pair pass (pair_pass.cpp)
  void process_failures(std::size_t first_block, std::size_t last_block);
  template <class Law>
  void process_failure(BondSet<Law>& set, std::uint32_t bond, const BondFailure& info);
  template <class Law>
  void record_crack(const BondSet<Law>& set, std::uint32_t bond, const BondFailure& info);
  void joints_replace_bonds();
  void install_pending_joints();
  int cutting_plane(std::uint32_t i, std::uint32_t j) const noexcept;
  // Calls f(set) for the joint law in use.
  template <class F>
  void with_joint_set(F&& f) {
    std::uint32_t index = 0;
    std::apply([&](auto&... set) { ((index++ == joint_law_ ? f(set) : void()), ...); }, joints_);
  }
  void assign_joints();
  template <class CL>
  void assign_joints_for(ContactSet<CL>& contacts);
  template <class CL>
  void compute_walls_for(ContactSet<CL>& contacts);
  template <class CL>
  void integrate_for(ContactSet<CL>& contacts, bool sample);
  [[gnu::always_inline]] inline void total_loads(const PairList& pairs, std::size_t i,
                                                 bool has_user_force, Vec3& f, Vec3& t,
                                                 Vec3& f_user);
  // Central forces only: no bond or joint, no driven grain, and contacts with grains and walls
  // that read only the pair's shape, whose forces act along the line through the centres. Their
  // torques are zero but for rounding, so the pair pass leaves them out and the integrator
  // turns no grain; the translations are those of the full computation to the bit (the
  // packing vessel runs so).
  template <class CL>
  bool central_forces_only(const ContactSet<CL>& c) const noexcept {
    if (contact_needs_motion<CL>(c.params) || contact_needs_motion<CL>(c.wall_params) ||
        p_.has_drives())
      return false;
    return !bonds_anywhere();
  }
  // Whether the pair pass must keep the array of pair forces: a law in use whose state does not
  // give its force back, bond dashpots, or the reference path asked for.
  template <class CL>
  bool pair_forces_needed(const ContactSet<CL>& c) const noexcept {
    if (cfg_.keep_pair_forces || cfg_.bond_normal_damping_ratio > 0.0 ||
        cfg_.bond_shear_damping_ratio > 0.0)
      return true;
    if constexpr (!has_state_force<CL>)
      return true;
    else if (!CL::state_holds_force(c.params))
      return true;
    bool needed = false;
    const auto check = [&]<class Law>(const BondSet<Law>& set) {
      if constexpr (has_state_force<Law>)
        needed = needed || (set.size() > 0 && !Law::state_holds_force(set.params));
      else
        needed = needed || set.size() > 0;
    };
    std::apply([&](const auto&... set) { (check(set), ...); }, bonds_);
    std::apply([&](const auto&... set) { (check(set), ...); }, joints_);
    return needed;
  }
  // Adds the state force of pair k's bond of this law (intact: a broken bond's force was not
  // applied) or joint (bonded or not: a joint acts either way), if it has one.
  template <class Law>
  static void add_state_force(const BondSet<Law>& set, std::size_t k, bool intact_only,
                              Vec3& f) noexcept {
    if constexpr (has_state_force<Law>) {
      const std::uint32_t b = set.bond_at_pair(k);
      if (b != BondSet<Law>::kNoBond && (set.intact[b] || !intact_only))
        f += Law::state_force(set.state[b]);
    }
  }
  template <class CL>
  void sample_stored_energy_for(ContactSet<CL>& contacts);
  template <class Law>
  void install_bonds(BondSet<Law>& set);
  template <class Law>
  void compact_bonds(BondSet<Law>& set);
  void estimate_time_step();
  void reserve_crack_catalogue();
  // Its stages: the stiffness each particle sees from its bonds and joints, then from its
  // contacts and walls (returning the Rayleigh bound of Hertz contacts, or infinity), then the
  // step taken from the critical one.
  void add_bond_stiffness(std::vector<double>& k_tr, std::vector<double>& k_rot);
  double add_contact_stiffness(std::vector<double>& k_tr, std::vector<double>& k_rot);
  void adopt_time_step(double crit, double dt_rayleigh);
  bool needs_rebuild() const noexcept;
  // A law's parameters made ready for the kernels: the run's geometry (for the laws that derive
  // their section from it), then the law's derived values (prepare()).
  template <class Law>
  void prepare_params(typename Law::Params& params) const noexcept {
    if constexpr (requires { params.run; })
      params.run = {.planar = p_.planar(),
                    .planar_sphere = p_.planar() && p_.planar_body() == PlanarBody::PlanarSphere,
                    .thickness = p_.thickness()};
    if constexpr (requires { Law::prepare(params); }) Law::prepare(params);
  }
  // Orientations for the bond laws that need them (2D: rotations about z by the angles).
  Quat body_orientation(std::uint32_t i) const noexcept {
    if (!p_.planar()) return p_.orientation[i];
    const double half = 0.5 * p_.angle[i];
    return {std::cos(half), 0.0, 0.0, std::sin(half)};
  }
  template <class Law>
  BodyFrames frames(std::uint32_t i, std::uint32_t j) const noexcept {
    if constexpr (Law::needs_frames)
      return {body_orientation(i), body_orientation(j)};
    else
      return {};
  }
  // Geometry of particle pair (i, j) at the current state. Kept out of line: inlined into the
  // pair pass it made that loop 15-20 % slower (bench_engine, 100k-grain bonded FCC block,
  // elastic phase, one thread; perf showed the whole pass in one function).
  [[gnu::noinline]] PairGeometry geometry(std::uint32_t i, std::uint32_t j) const noexcept {
    PairGeometry g = shape_inline(i, j);
    add_motion(g, i, j);
    return g;
  }
  // The pair's shape alone (the pair pass adds the motion when a law needs it: loading the
  // velocities of a pair's second grain is a cache miss the beam bonds need not pay).
  [[gnu::noinline]] PairGeometry shape(std::uint32_t i, std::uint32_t j) const noexcept {
    return shape_inline(i, j);
  }
  [[gnu::always_inline]] PairGeometry shape_inline(std::uint32_t i,
                                                   std::uint32_t j) const noexcept {
    const PosRad& a = p_.pos_rad[i];
    const PosRad& b = p_.pos_rad[j];
    PairGeometry g = pair_shape(a.x, a.r, b.x, b.r, p_.planar(), p_.thickness());
    g.planar_sphere = p_.planar() && p_.planar_body() == PlanarBody::PlanarSphere;
    return g;
  }
  [[gnu::always_inline]] void add_motion(PairGeometry& g, std::uint32_t i,
                                         std::uint32_t j) const noexcept {
    add_pair_motion(g, p_.vel[i], p_.angvel[i], p_.vel[j], p_.angvel[j], p_.mass[i], p_.mass[j]);
  }

  ParticleStore p_;
  EngineConfig cfg_;
  InstructionSet isa_ = InstructionSet::baseline;
  ContactModel contact_;
  BondSets bonds_;
  JointSets joints_;
  std::vector<JointPlane> joint_planes_;
  // Bonded joints waiting for initialise(): particle indexes and the plane that cuts them.
  struct PendingJoint {
    std::uint32_t i, j, plane;
    BondTag tag;
  };
  // The next bond's tag; throws once the 32-bit tags are used up.
  BondTag take_bond_tag();
  std::uint32_t joint_law_ = 0;  // position in JointLaws of the law that new joints get
  std::vector<PendingJoint> pending_joints_;
  std::vector<Wall> walls_;
  WallContactVariantOf<EngineContactLaws>::type wall_contacts_;

  double dt_ = 0.0, dt_crit_ = 0.0, time_ = 0.0, skin_ = 0.0;
  std::uint64_t step_ = 0, rebuilds_ = 0, next_bond_tag_ = 1;
  bool initialised_ = false, sample_requested_ = false, retired_ = false;
  bool keep_pair_forces_ = true;  // the pair pass keeps ContactSet::kept_force (pair_force())
  std::vector<Vec3> x_at_build_;
  std::vector<CrossSlot> cross_slots_;  // the pair pass's cross pairs (pair_list.hpp)
  std::vector<Vec3> user_force_;        // external loads (empty when unused)
  // Driver force and moment of driven particles in the previous step (empty without drives).
  std::vector<Vec3> drive_force_prev_;
  double max_disp2_ = 0.0;
  double radius_growth_ = 0.0;  // largest radius increase since the last neighbour rebuild

  CrackCatalogue cracks_;
  // Per grain: until when dynamic damping applies (empty while it is off or before any crack).
  std::vector<double> damped_less_until_;
  // The own grains binned by their positions at the last rebuild, for the dynamic-damping
  // regions (rebuilt after each neighbour rebuild; not saved: it follows from x_at_build_).
  struct RegionGrid {
    Vec3 lo;
    double inv_h = 0.0;
    std::int64_t nx = 1, ny = 1, nz = 1;
    std::vector<std::uint32_t> start, items;
    std::uint64_t built_at = ~std::uint64_t{0};  // rebuilds_ when built
    std::size_t own_begin = 0, own_end = 0;
  } region_grid_;
  std::vector<std::string> warnings_;
  EnergyLedger ledger_;
  std::optional<EnergyLedger> baseline_;
  // Cumulative accumulators.
  double w_walls_ = 0.0, w_drive_ = 0.0, w_gravity_ = 0.0, w_external_ = 0.0;
  double d_local_ = 0.0;
  double d_local_boundary_ = 0.0, w_external_boundary_ = 0.0;
  PairDissipation d_pairs_;
  double d_joint_slip_ = 0.0;
  BondEnergy released_;
  // Per-block scratch (reused every step; no allocation in steady state).
  std::vector<PairDissipation> block_dis_, block_joint_dis_;
  std::vector<IntegrateBlock> block_int_;
  std::vector<std::size_t> wall_block_starts_;  // a wall's contacts per particle block
  std::vector<WallBlock> wall_blocks_;          // every wall's, wall after wall
  std::unique_ptr<RankSplit> split_;            // null: one rank steps every particle
  struct Failure {
    std::uint32_t law;  // position in BondLaws, then BondLaws::size + position in JointLaws
    std::uint32_t bond;
    BondFailure info;
  };
  std::vector<std::vector<Failure>> block_failures_;
};

}  // namespace breccia

#include "breccia/engine/simulation_impl.hpp"
