#pragma once
// Acoustic-emission monitor: a recorder subscribed to the engine's break events (the crack
// catalogue, read after every step). It clusters cracks into events as they happen (Hazzard &
// Young 2000, docs/analysis.md §4.1) and, while an event is open, watches its source particles: the
// change of the contact and bond forces they exert on outside neighbours gives the event's moment
// tensor (Hazzard & Young 2004, §4.2), taken at the maximum scalar moment, and the kinetic energy
// of the particles within r_s of its cracks gives the kinetic-energy event energy (§4.4). When no
// event is open, a step costs one comparison.
//
// Reference forces: the engine computes a step's pair forces from the positions at its start, so
// the forces read right after the step in which a bond broke are those of the particles before
// any crack-induced motion; they serve as the reference of the particles that crack adds to the
// source. Likewise the kinetic-energy baseline of a monitored particle is read after that step.
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <unordered_map>
#include <vector>

#include "breccia/analysis/ae_clustering.hpp"
#include "breccia/core/record_file.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/observe/recorder.hpp"

namespace breccia {

// The monitor's logs in a run folder (keep_logs_in), beside the checkpoint.
inline constexpr const char* kAeEventFile = "checkpoint-ae-events.bin";
inline constexpr const char* kAeContextFile = "checkpoint-ae-context.bin";
// Records of each log held in memory at most (1 MB of events) before they go to the file.
inline constexpr std::size_t kAeResidentRecords = 4096;

struct AeSettings {
  double source_radius = 0.0;         // r_s, m (0: 3 x the largest particle diameter)
  double shear_wave_speed = 0.0;      // v_S, m/s (0: estimated by the run at the first crack)
  std::uint64_t moment_interval = 1;  // steps between moment-tensor evaluations of open events
  bool moment_tensors = true;
  std::uint8_t unused[3]{};  // named, not padding (core/archive.hpp)
  analysis::Linkage linkage = analysis::Linkage::SourceRadius;
};

// One acoustic-emission event (plain data).
struct AeEvent {
  std::uint64_t first_crack = 0, cracks = 0, tensile = 0, shear = 0;
  double t_first = 0.0, t_last = 0.0, strain_first = 0.0, strain_last = 0.0;
  Vec3 position_sum;               // sum of crack midpoints (centroid = sum / cracks)
  double energy = 0.0;             // sum of the released bond energies E_brk, J
  double fracture_energy = 0.0;    // sum of the papers' estimates sigma^2 v / (2 C), J
  std::array<double, 9> moment{};  // tensor at the maximum scalar moment, row-major, N m
  double m0 = 0.0;                 // maximum scalar moment over the evaluations
  double t_star = 0.0, strain_star = 0.0;
  double m0_first = -1.0;  // scalar moment at the first evaluation (noise reference; -1: none)
  std::uint64_t evaluations = 0, source_particles = 0, monitored_particles = 0;
  double ke_gain = 0.0;  // E_KE = max (K_P(t) - K_P(t0)), J
  Vec3 centroid() const noexcept { return position_sum * (1.0 / static_cast<double>(cracks)); }
};

// Per-crack values captured in the step of the break.
struct CrackContext {
  double axial_strain = 0.0;
  double deviatoric = 0.0;       // Pa
  double fracture_energy = 0.0;  // J, docs/analysis.md §2.3
};

class AeMonitor : public Recorder {
 public:
  static constexpr std::string_view kind = "ae monitor";
  // Settings from the experiment's [ae] table, r_s from the sample's largest grain.
  static std::unique_ptr<Recorder> create(const RecorderSetup& setup);
  static std::unique_ptr<Recorder> restore(const RecorderSetup& setup, ArchiveReader& a);

  AeMonitor() = default;
  // `source_radius` resolved (> 0); clustering starts once the wave speed is set.
  explicit AeMonitor(AeSettings s) : s_(s) {}
  // The clusterer calls back into its monitor; a move rebinds those calls to the new object (a
  // monitor restored from a checkpoint is moved into the run's session).
  AeMonitor(AeMonitor&& other) noexcept { *this = std::move(other); }
  AeMonitor& operator=(AeMonitor&& other) noexcept;
  AeMonitor(const AeMonitor&) = delete;
  AeMonitor& operator=(const AeMonitor&) = delete;
  bool configured() const noexcept { return clusterer_.has_value(); }
  // Fixes v_S (and with it T_d = 4 r_s / v_S) before the first crack is processed.
  void configure(double shear_wave_speed);
  // After every step: captures the context of new cracks, clusters them, updates open events.
  void after_step(const Simulation& sim, double axial_strain, double deviatoric);
  // Closes the open events (end of the test).
  void finish();

  // The finished events in closing order and the context of each crack, read back whole (from
  // the run folder's files where the monitor keeps them there).
  std::vector<AeEvent> events() const { return done_.all(); }
  std::size_t event_count() const noexcept { return done_.size(); }
  std::vector<CrackContext> crack_context() const { return context_.all(); }
  // From now on the finished events and the crack contexts beyond the newest `resident` go to
  // files in `folder` (a run's), as the crack catalogue's older records do: a million-grain
  // test closes about 0.1 event and makes 0.4 crack a grain. reattach_logs() reopens them after
  // a restore.
  void keep_logs_in(const std::filesystem::path& folder, std::size_t resident);
  void reattach_logs(const std::filesystem::path& folder, std::size_t resident);
  // Event (index into events()) of each crack, after finish().
  std::vector<std::size_t> crack_events() const;
  const AeSettings& settings() const noexcept { return s_; }
  double duration() const noexcept { return duration_; }
  bool has_open_events() const noexcept { return !open_.empty(); }
  std::size_t cracks_seen() const noexcept { return context_.size(); }

  void save(ArchiveWriter& a) const;
  void load(ArchiveReader& a);

  // As a recorder: v_S comes from `source` at the first crack unless the experiment gave it (the
  // run estimates it from the rows recorded so far).
  void set_wave_speed_source(std::function<double()> source) {
    wave_speed_source_ = std::move(source);
  }
  std::string_view name() const noexcept override { return kind; }
  // Cheap unless bonds broke in the step or an event is open.
  void after_step(const Simulation& sim, const Protocol& test) override;
  // In steps with new cracks or open events: the test's measured grains, the new cracks' grains
  // and those within the source radius of them, the open events' sources and watched grains,
  // and the grains in touch with the sources (collective on a split sample; every grain in one
  // process, where nothing is gathered).
  GrainReads grains_read_after_step(const Simulation& sim, const Protocol& test) override;
  void finish(const Simulation&) override { finish(); }
  void save_state(ArchiveWriter& a) const override { save(a); }
  std::vector<std::string> files() const override { return {}; }  // events.csv: the analysis

 private:
  struct Ref {
    std::uint64_t key = 0;      // (p << 32) | q: force exerted by source particle p on q
    Vec3 force, contact_point;  // the contact point as last seen
  };
  struct Watched {
    std::uint32_t particle = 0;
    std::uint32_t unused = 0;  // named, not padding (core/archive.hpp)
    double ke0 = 0.0;          // kinetic energy when it joined
  };
  struct Open {
    AeEvent ev;
    std::vector<std::uint32_t> source;  // sorted
    std::vector<Ref> refs;              // sorted by key
    std::vector<Watched> watched;       // sorted by particle
    double ke_baseline = 0.0;
    std::uint64_t created = 0;  // monitor step of the first crack
  };
  template <class Archive>
  void transfer(Archive& a);
  void bind_clusterer();
  void add_source(const Simulation& sim, Open& o, std::uint32_t p);
  void watch_near(const Simulation& sim, Open& o, const Vec3& x);
  void evaluate(const Simulation& sim, Open& o, double strain);
  void merge(std::size_t kept, std::size_t gone);
  void close(std::size_t root);
  void build_grid(const Simulation& sim);
  // The grid of `count` grains, the k-th being at(k), in ascending order.
  template <class IndexAt>
  void fill_grid(const ParticleStore& p, std::size_t count, IndexAt at);
  // Calls f(i) for each grain i of the grid within the source radius of x, in the grid's order.
  template <class F>
  void for_grains_near(const ParticleStore& p, const Vec3& x, F&& f) const;
  void find_near_new_cracks(const Simulation& sim, CrackCatalogue::Reader& cracks);
  void find_incoming(const Simulation& sim, CrackCatalogue::Reader& cracks);

  AeSettings s_;
  std::function<double()> wave_speed_source_;
  double duration_ = 0.0;
  std::optional<analysis::EventClusterer> clusterer_;
  std::map<std::size_t, Open> open_;  // by clusterer root
  RecordLog<AeEvent> done_{"AE event log"};
  std::vector<std::size_t> done_root_;  // clusterer root of each finished event
  RecordLog<CrackContext> context_{"AE crack context log"};
  std::uint64_t seen_ = 0, steps_ = 0;
  std::vector<char> visited_;  // evaluate(): the refs met in the current evaluation (scratch)
  // Particle grid (cell size r_s) for the monitored set, rebuilt in steps with new cracks: cells
  // (a, b, c) = floor(x / r_s) from `lo` on, with their particles in index order (CSR). A
  // million-grain sample cracks at nearly every step near its peak, so the grid is built by one
  // counting pass rather than a map of vectors.
  struct Grid {
    std::array<long long, 3> lo{}, size{};
    std::vector<std::uint32_t> start, items;
    // Particles of cell (a, b, c), empty outside the grid.
    std::pair<const std::uint32_t*, const std::uint32_t*> at(long long a, long long b,
                                                             long long c) const noexcept;
  } grid_;
  // The neighbour pairs where a grain the monitor reads is second, in ascending slot order (the
  // engine's list keeps no transposed index): read for the grains of new cracks and open events,
  // forgotten at a neighbour rebuild and once no event is open. Not saved: read again after a
  // restore. One sorted array of (grain << 32 | slot), 8 B a pair, and a bit a grain for the
  // grains read: a large event reads tens of thousands of grains.
  struct Incoming {
    std::uint64_t rebuilds = ~std::uint64_t{0};  // the list they index
    std::vector<std::uint64_t> entries;          // (grain << 32) | slot, ascending
    std::vector<bool> read;                      // per grain: its entries are in
    std::vector<bool> fresh;                     // per grain: wanted by this step (scratch)
    std::size_t grains = 0;                      // grains read
  } incoming_;
  using IncomingSlots = std::pair<const std::uint64_t*, const std::uint64_t*>;
  IncomingSlots incoming(std::uint32_t p) const;
  void forget_incoming(std::size_t particles);
  // On a sample split over ranks the pairs live with their first grains' owners: the loads of
  // every grain the step reads (the new cracks' and the open events' sources) are gathered
  // whole each step instead (Simulation::pair_loads_around). Scratch, not saved.
  struct GatheredLoads {
    std::vector<std::uint32_t> grains, offsets;
    std::vector<Simulation::PairLoad> loads;
  } gathered_;
  void gather_loads(const Simulation& sim, CrackCatalogue::Reader& cracks);
  // Of a split sample, read at the step given before after_step (scratch, not saved): every
  // rank's grains within the source radius of the step's new cracks, ascending (the grid of
  // after_step holds these alone), and the grains the step reads.
  std::vector<std::uint32_t> near_, reads_;
  std::uint64_t prepared_step_ = ~std::uint64_t{0};
  void expect_prepared(const Simulation& sim) const;
  // Calls f(q, force exerted by p on q) for every neighbour pair of p, in the list's order.
  template <class F>
  void for_pairs_of(const Simulation& sim, std::uint32_t p, F&& f) const;
};

// The fracture-energy estimate of docs/analysis.md §2.3 for a bond crack: sigma^2 V / (2 E_b) in
// tension, tau^2 V / (2 G_b) in shear, over the bond volume V = A (R1 + R2).
double fracture_energy(const CrackRecord& c, const BondModuli& moduli, bool planar,
                       double thickness);

}  // namespace breccia
