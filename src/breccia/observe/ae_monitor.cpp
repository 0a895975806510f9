#include "breccia/observe/ae_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "breccia/core/archive.hpp"
#include "breccia/core/byte_text.hpp"
#include "breccia/core/cell_walk.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/spec/experiment.hpp"

namespace breccia {

double fracture_energy(const CrackRecord& c, const BondModuli& moduli, bool planar,
                       double thickness) {
  const double L = c.R1 + c.R2, R = c.bond_radius;
  const double v = planar ? 2.0 * R * thickness * L : std::numbers::pi * R * R * L;
  const bool tensile = c.mode == CrackMode::Tensile;
  const double s = tensile ? c.sigma : c.tau;
  const double C = tensile ? moduli.young : moduli.shear;
  return C > 0.0 ? s * s * v / (2.0 * C) : 0.0;
}

namespace {

double kinetic(const ParticleStore& p, std::uint32_t i) {
  return 0.5 * p.mass[i] * norm2(p.vel[i]) + 0.5 * p.inertia[i] * norm2(p.angvel[i]);
}

// Contact point of pair (i, j) (docs/physics.md §0.2: middle of the overlap or gap).
Vec3 contact_point(const ParticleStore& p, std::uint32_t i, std::uint32_t j) {
  const PosRad& a = p.pos_rad[i];
  const PosRad& b = p.pos_rad[j];
  const Vec3 d = b.x - a.x;
  const double dist = norm(d);
  const double delta = a.r + b.r - dist;
  return a.x + d * ((a.r - 0.5 * delta) / dist);
}

bool contains(const std::vector<std::uint32_t>& v, std::uint32_t x) {
  return std::binary_search(v.begin(), v.end(), x);
}

std::uint64_t ref_key(std::uint32_t p, std::uint32_t q) {
  return (static_cast<std::uint64_t>(p) << 32) | q;
}

// Calls f(q, force exerted by p on q) for every neighbour pair of p (the pair's force is the
// force on the pair's second particle): those where p is first, then `incoming`, the slots of
// those where it is second, ascending.
template <class F>
void for_pairs(const Simulation& sim,
               std::pair<const std::uint64_t*, const std::uint64_t*> incoming, std::uint32_t p,
               F&& f) {
  std::visit(
      [&](const auto& c) {
        const PairList& l = c.pairs;
        if (l.offsets.size() <= p + 1) return;
        for (std::uint32_t k = l.offsets[p]; k < l.offsets[p + 1]; ++k)
          f(l.second[k], sim.pair_force(c, k));
        for (const std::uint64_t* e = incoming.first; e != incoming.second; ++e) {
          const auto k = static_cast<std::uint32_t>(*e & 0xffffffffu);
          f(l.first[k], -sim.pair_force(c, k));
        }
      },
      sim.contact_model());
}

// Records of each log kept in memory: the run's resident crack records, at most
// kAeResidentRecords.
std::size_t resident_records(const ExperimentSpec& spec) {
  return std::min(static_cast<std::size_t>(spec.resident_cracks), kAeResidentRecords);
}

bool is_zero(const Vec3& v) {
  return v.x == 0.0 && v.y == 0.0 && v.z == 0.0;
}

}  // namespace

void AeMonitor::configure(double vs) {
  if (!(vs > 0.0) || !std::isfinite(vs))
    throw InputError("acoustic emission", "shear_wave_speed", num(vs), "must be > 0 m/s");
  if (!(s_.source_radius > 0.0))
    throw InputError("acoustic emission", "source_radius", num(s_.source_radius), "must be > 0 m");
  s_.shear_wave_speed = vs;
  duration_ = analysis::event_duration(s_.source_radius, vs);
  clusterer_.emplace(analysis::ClusterSettings{s_.source_radius, duration_, s_.linkage});
  bind_clusterer();
}

void AeMonitor::bind_clusterer() {
  if (!clusterer_) return;
  clusterer_->merged = [this](std::size_t kept, std::size_t gone) { merge(kept, gone); };
  clusterer_->closed = [this](std::size_t root) { close(root); };
}

std::unique_ptr<Recorder> AeMonitor::create(const RecorderSetup& setup) {
  const ExperimentSpec& spec = setup.spec;
  double r_max = 0.0;
  const ParticleStore& p = setup.sim.particles();
  for (std::size_t i = 0; i < setup.test.rock_particles(setup.sim); ++i)
    r_max = std::max(r_max, p.pos_rad[i].r);
  AeSettings s;
  s.source_radius = spec.ae_source_radius > 0.0 ? spec.ae_source_radius : 3.0 * (2.0 * r_max);
  s.shear_wave_speed = spec.ae_shear_wave_speed;
  s.moment_tensors = spec.ae_moment_tensors;
  s.moment_interval = static_cast<std::uint64_t>(spec.ae_moment_interval);
  s.linkage = spec.ae_clustering == "grain"           ? analysis::Linkage::Grain
              : spec.ae_clustering == "source_region" ? analysis::Linkage::SourceRegion
                                                      : analysis::Linkage::SourceRadius;
  auto ae = std::make_unique<AeMonitor>(s);
  if (spec.ae_shear_wave_speed > 0.0) ae->configure(spec.ae_shear_wave_speed);
  if (!setup.folder.empty()) ae->keep_logs_in(setup.folder, resident_records(spec));
  return ae;
}

std::unique_ptr<Recorder> AeMonitor::restore(const RecorderSetup& setup, ArchiveReader& a) {
  auto ae = std::make_unique<AeMonitor>();
  ae->load(a);
  if (!setup.folder.empty()) ae->reattach_logs(setup.folder, resident_records(setup.spec));
  return ae;
}

void AeMonitor::keep_logs_in(const std::filesystem::path& folder, std::size_t resident) {
  done_.spill_to(folder / kAeEventFile, resident);
  context_.spill_to(folder / kAeContextFile, resident);
}

void AeMonitor::reattach_logs(const std::filesystem::path& folder, std::size_t resident) {
  done_.reattach(folder / kAeEventFile, resident);
  context_.reattach(folder / kAeContextFile, resident);
}

void AeMonitor::after_step(const Simulation& sim, const Protocol& test) {
  if (sim.cracks().size() <= cracks_seen() && !has_open_events()) return;
  const AxialState now = test.measure(sim);
  if (!configured()) {
    if (!wave_speed_source_)
      throw std::logic_error("AeMonitor: no shear-wave speed and no source to estimate it");
    configure(wave_speed_source_());
  }
  after_step(sim, now.strain, now.deviatoric);
}

AeMonitor& AeMonitor::operator=(AeMonitor&& o) noexcept {
  s_ = o.s_;
  duration_ = o.duration_;
  clusterer_ = std::move(o.clusterer_);
  o.clusterer_.reset();
  open_ = std::move(o.open_);
  done_ = std::move(o.done_);
  done_root_ = std::move(o.done_root_);
  context_ = std::move(o.context_);
  seen_ = o.seen_;
  steps_ = o.steps_;
  grid_ = std::move(o.grid_);
  incoming_ = std::move(o.incoming_);
  gathered_ = std::move(o.gathered_);
  near_ = std::move(o.near_);
  reads_ = std::move(o.reads_);
  prepared_step_ = o.prepared_step_;
  wave_speed_source_ = std::move(o.wave_speed_source_);
  bind_clusterer();  // the moved callbacks still point at `o`
  return *this;
}

std::pair<const std::uint32_t*, const std::uint32_t*> AeMonitor::Grid::at(
    long long a, long long b, long long c) const noexcept {
  a -= lo[0];
  b -= lo[1];
  c -= lo[2];
  if (a < 0 || b < 0 || c < 0 || a >= size[0] || b >= size[1] || c >= size[2]) return {};
  const auto k = static_cast<std::size_t>((a * size[1] + b) * size[2] + c);
  return {items.data() + start[k], items.data() + start[k + 1]};
}

template <class IndexAt>
void AeMonitor::fill_grid(const ParticleStore& p, std::size_t n, IndexAt at) {
  const double h = s_.source_radius;
  const auto& pr = p.pos_rad;
  auto key = [h](const Vec3& x, int k) { return static_cast<long long>(std::floor(x[k] / h)); };
  std::array<long long, 3> lo{}, hi{};
  if (n > 0)
    for (int k = 0; k < 3; ++k) lo[k] = hi[k] = key(pr[at(0)].x, k);
  for (std::size_t m = 0; m < n; ++m)
    for (std::size_t k = 0; k < 3; ++k) {
      const long long c = key(pr[at(m)].x, static_cast<int>(k));
      lo[k] = std::min(lo[k], c);
      hi[k] = std::max(hi[k], c);
    }
  Grid& g = grid_;
  g.lo = lo;
  for (std::size_t k = 0; k < 3; ++k) g.size[k] = hi[k] - lo[k] + 1;
  g.start.assign(static_cast<std::size_t>(g.size[0] * g.size[1] * g.size[2]) + 1, 0);
  // Cell of a particle, computed in both passes rather than kept (4 bytes a grain).
  auto cell_of = [&](const Vec3& x) {
    const long long a = key(x, 0) - lo[0], b = key(x, 1) - lo[1], c = key(x, 2) - lo[2];
    return static_cast<std::size_t>((a * g.size[1] + b) * g.size[2] + c);
  };
  for (std::size_t m = 0; m < n; ++m) ++g.start[cell_of(pr[at(m)].x) + 1];
  for (std::size_t k = 1; k < g.start.size(); ++k) g.start[k] += g.start[k - 1];
  g.items.resize(n);
  // A stable fill: each cell lists its particles in index order.
  std::vector<std::uint32_t> fill(g.start.begin(), g.start.end() - 1);
  for (std::size_t m = 0; m < n; ++m) {
    const std::uint32_t i = at(m);
    g.items[fill[cell_of(pr[i].x)]++] = i;
  }
}

// Of a split sample, the grid holds the grains near the step's new cracks alone (found by their
// owners, whose positions are current): what a query near a new crack meets in it is what it
// meets in the whole sample's grid, in the same order.
void AeMonitor::build_grid(const Simulation& sim) {
  const ParticleStore& p = sim.particles();
  if (sim.split()) {
    expect_prepared(sim);
    fill_grid(p, near_.size(), [&](std::size_t k) { return near_[k]; });
    return;
  }
  fill_grid(p, p.size(), [](std::size_t k) { return static_cast<std::uint32_t>(k); });
}

template <class F>
void AeMonitor::for_grains_near(const ParticleStore& p, const Vec3& x, F&& f) const {
  const double h = s_.source_radius;
  for_each_cell_around(x, h, [&](long long a, long long b, long long c) {
    const auto [first, last] = grid_.at(a, b, c);
    for (const std::uint32_t* it = first; it != last; ++it)
      if (norm2(p.pos_rad[*it].x - x) <= h * h) f(*it);
  });
}

void AeMonitor::watch_near(const Simulation& sim, Open& o, const Vec3& x) {
  const ParticleStore& p = sim.particles();
  std::vector<Watched> add;
  for_grains_near(p, x,
                  [&](std::uint32_t i) { add.push_back({.particle = i, .ke0 = kinetic(p, i)}); });
  for (const Watched& w : add) {
    const auto pos =
        std::lower_bound(o.watched.begin(), o.watched.end(), w.particle,
                         [](const Watched& u, std::uint32_t i) { return u.particle < i; });
    if (pos != o.watched.end() && pos->particle == w.particle) continue;
    o.watched.insert(pos, w);
    o.ke_baseline += w.ke0;
  }
}

void AeMonitor::find_near_new_cracks(const Simulation& sim, CrackCatalogue::Reader& cracks) {
  near_.clear();
  if (cracks.size() <= seen_) return;  // alike on every rank: no exchange
  const ParticleStore& p = sim.particles();
  const IndexRange own = sim.owned_particles();
  fill_grid(p, own.size(),
            [&](std::size_t k) { return static_cast<std::uint32_t>(own.begin + k); });
  std::vector<std::uint32_t> mine;
  for (std::size_t k = seen_; k < cracks.size(); ++k)
    for_grains_near(p, cracks[k].position, [&](std::uint32_t i) { mine.push_back(i); });
  std::sort(mine.begin(), mine.end());
  mine.erase(std::unique(mine.begin(), mine.end()), mine.end());
  std::string bytes;
  bytes::put_range(bytes, mine.data(), mine.size());
  // The ranks' parts in rank order: ascending.
  for (const std::string& part : ranks::all_gather(bytes)) {
    const std::size_t count = part.size() / sizeof(std::uint32_t), at = near_.size();
    near_.resize(at + count);
    std::size_t from = 0;
    bytes::take_range(part, from, near_.data() + at, count);
  }
}

GrainReads AeMonitor::grains_read_after_step(const Simulation& sim, const Protocol& test) {
  if (sim.cracks().size() <= cracks_seen() && !has_open_events()) return {};
  if (!sim.split()) return GrainReads::every();
  auto cracks = sim.cracks().reader();
  find_near_new_cracks(sim, cracks);
  gather_loads(sim, cracks);
  prepared_step_ = sim.step_count();
  const GrainReads measured = test.grains_read_by_measure();
  if (measured.all) return GrainReads::every();
  const ParticleStore& ps = sim.particles();
  reads_.assign(measured.some.begin(), measured.some.end());
  reads_.insert(reads_.end(), near_.begin(), near_.end());
  for (std::size_t k = seen_; k < cracks.size(); ++k) {
    reads_.push_back(static_cast<std::uint32_t>(ps.index_of(cracks[k].id1)));
    reads_.push_back(static_cast<std::uint32_t>(ps.index_of(cracks[k].id2)));
  }
  for (const auto& [root, o] : open_) {
    reads_.insert(reads_.end(), o.source.begin(), o.source.end());
    for (const Watched& w : o.watched) reads_.push_back(w.particle);
  }
  reads_.insert(reads_.end(), gathered_.grains.begin(), gathered_.grains.end());
  for (const Simulation::PairLoad& l : gathered_.loads) reads_.push_back(l.other);
  std::sort(reads_.begin(), reads_.end());
  reads_.erase(std::unique(reads_.begin(), reads_.end()), reads_.end());
  return {.all = false, .some = reads_};
}

void AeMonitor::expect_prepared(const Simulation& sim) const {
  if (prepared_step_ != sim.step_count())
    throw std::logic_error(
        "AeMonitor: on a split sample, grains_read_after_step comes before after_step");
}

AeMonitor::IncomingSlots AeMonitor::incoming(std::uint32_t p) const {
  if (p >= incoming_.read.size() || !incoming_.read[p])
    throw InternalError("AeMonitor: the pairs of particle " + std::to_string(p) + " were not read");
  const std::uint64_t* first = incoming_.entries.data();
  const std::uint64_t* last = first + incoming_.entries.size();
  const std::uint64_t key = std::uint64_t{p} << 32;
  const std::uint64_t* lo = std::lower_bound(first, last, key);
  return {lo, std::lower_bound(lo, last, key + (std::uint64_t{1} << 32))};
}

void AeMonitor::forget_incoming(std::size_t particles) {
  incoming_.entries = {};
  if (incoming_.grains > 0 || incoming_.read.size() != particles) {
    incoming_.read.assign(particles, false);
    incoming_.fresh.assign(particles, false);
  }
  incoming_.grains = 0;
}

// Of a split sample: the loads of the pairs of the grains this step reads, gathered by
// gather_loads; of one process: read in the list through `incoming`.
template <class F>
void AeMonitor::for_pairs_of(const Simulation& sim, std::uint32_t p, F&& f) const {
  if (!sim.split()) {
    for_pairs(sim, incoming(p), p, f);
    return;
  }
  const GatheredLoads& g = gathered_;
  const auto at = std::lower_bound(g.grains.begin(), g.grains.end(), p);
  if (at == g.grains.end() || *at != p)
    throw InternalError("AeMonitor: the pairs of particle " + std::to_string(p) + " were not read");
  const auto a = static_cast<std::size_t>(at - g.grains.begin());
  for (std::uint32_t k = g.offsets[a]; k < g.offsets[a + 1]; ++k)
    f(g.loads[k].other, g.loads[k].force);
}

void AeMonitor::gather_loads(const Simulation& sim, CrackCatalogue::Reader& cracks) {
  const ParticleStore& ps = sim.particles();
  std::vector<std::uint32_t>& grains = gathered_.grains;
  grains.clear();
  // Every rank decides alike (the settings and the cracks are the same on all): no pair is read
  // without moment tensors or grain linkage.
  if (!s_.moment_tensors && s_.linkage != analysis::Linkage::Grain) return;
  for (std::size_t k = seen_; k < cracks.size(); ++k) {
    grains.push_back(static_cast<std::uint32_t>(ps.index_of(cracks[k].id1)));
    grains.push_back(static_cast<std::uint32_t>(ps.index_of(cracks[k].id2)));
  }
  for (const auto& [root, o] : open_) grains.insert(grains.end(), o.source.begin(), o.source.end());
  std::sort(grains.begin(), grains.end());
  grains.erase(std::unique(grains.begin(), grains.end()), grains.end());
  sim.pair_loads_around(grains, gathered_.offsets, gathered_.loads);
}

// The grains of the new cracks (from seen_ on) and the sources of the open events: those the
// step reads the pairs of. Their pairs as second particle are found by one scan of the list;
// a neighbour rebuild makes a new list, whose slots are read afresh.
void AeMonitor::find_incoming(const Simulation& sim, CrackCatalogue::Reader& cracks) {
  if (sim.split()) {
    expect_prepared(sim);  // gathered there, with the grains the step reads
    return;
  }
  const ParticleStore& ps = sim.particles();
  if (incoming_.rebuilds != sim.neighbour_rebuilds() || incoming_.read.size() != ps.size()) {
    forget_incoming(ps.size());
    incoming_.rebuilds = sim.neighbour_rebuilds();
  }
  std::vector<std::uint32_t> wanted;
  auto want = [&](std::uint32_t p) {
    if (incoming_.read[p]) return;  // read already (or wanted twice)
    incoming_.read[p] = true;
    incoming_.fresh[p] = true;
    wanted.push_back(p);
  };
  for (std::size_t k = seen_; k < cracks.size(); ++k) {
    const CrackRecord& c = cracks[k];
    want(static_cast<std::uint32_t>(ps.index_of(c.id1)));
    want(static_cast<std::uint32_t>(ps.index_of(c.id2)));
  }
  for (const auto& [root, o] : open_)
    for (std::uint32_t p : o.source) want(p);
  if (wanted.empty()) return;
  incoming_.grains += wanted.size();
  std::vector<std::uint64_t> found;
  std::visit(
      [&](const auto& c) {
        const PairList& l = c.pairs;
        for (std::size_t k = 0; k < l.size(); ++k)
          if (incoming_.fresh[l.second[k]]) found.push_back((std::uint64_t{l.second[k]} << 32) | k);
      },
      sim.contact_model());
  for (std::uint32_t p : wanted) incoming_.fresh[p] = false;
  std::sort(found.begin(), found.end());
  const auto middle = static_cast<std::ptrdiff_t>(incoming_.entries.size());
  incoming_.entries.insert(incoming_.entries.end(), found.begin(), found.end());
  std::inplace_merge(incoming_.entries.begin(), incoming_.entries.begin() + middle,
                     incoming_.entries.end());
}

void AeMonitor::add_source(const Simulation& sim, Open& o, std::uint32_t p) {
  const auto pos = std::lower_bound(o.source.begin(), o.source.end(), p);
  if (pos != o.source.end() && *pos == p) return;
  o.source.insert(pos, p);
  if (!s_.moment_tensors) return;
  // Reference forces of p on its outside neighbours, as they are now (before the crack acts).
  const ParticleStore& ps = sim.particles();
  for_pairs_of(sim, p, [&](std::uint32_t q, const Vec3& f) {
    if (is_zero(f) || contains(o.source, q)) return;
    const std::uint64_t key = ref_key(p, q);
    const auto at = std::lower_bound(o.refs.begin(), o.refs.end(), key,
                                     [](const Ref& r, std::uint64_t k) { return r.key < k; });
    if (at != o.refs.end() && at->key == key) return;
    o.refs.insert(at, Ref{key, f, contact_point(ps, std::min(p, q), std::max(p, q))});
  });
}

void AeMonitor::evaluate(const Simulation& sim, Open& o, double strain) {
  const ParticleStore& ps = sim.particles();
  // Kinetic energy of the monitored particles against their baseline.
  double k = 0.0;
  for (const Watched& w : o.watched) k += kinetic(ps, w.particle);
  o.ev.ke_gain = std::max(o.ev.ke_gain, k - o.ke_baseline);
  if (!s_.moment_tensors) return;
  visited_.assign(o.refs.size(), 0);
  const Vec3 xe = o.ev.centroid();
  std::array<double, 9> m{};
  auto add = [&](const Vec3& df, const Vec3& xc) {
    const Vec3 r = xc - xe;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[static_cast<std::size_t>(3 * i + j)] += df[i] * r[j];
  };
  for (std::uint32_t p : o.source)
    for_pairs_of(sim, p, [&](std::uint32_t q, const Vec3& f) {
      if (contains(o.source, q)) return;  // internal to the source
      const std::uint64_t key = ref_key(p, q);
      const auto at = std::lower_bound(o.refs.begin(), o.refs.end(), key,
                                       [](const Ref& r, std::uint64_t kk) { return r.key < kk; });
      const bool has_ref = at != o.refs.end() && at->key == key;
      if (is_zero(f) && !has_ref) return;
      const Vec3 xc = contact_point(ps, std::min(p, q), std::max(p, q));
      if (has_ref) {
        visited_[static_cast<std::size_t>(at - o.refs.begin())] = 1;
        at->contact_point = xc;
        if (!is_zero(f))
          add(f - at->force, xc);
        else
          add(-at->force, xc);
      } else {
        add(f, xc);  // a contact created since: zero reference force
      }
    });
  // Refs to a grain that has joined the source are internal for good (the source only grows):
  // they are dropped here, the others kept in order.
  std::size_t kept = 0;
  for (std::size_t n = 0; n < o.refs.size(); ++n) {
    const Ref& r = o.refs[n];
    if (contains(o.source, static_cast<std::uint32_t>(r.key & 0xffffffffu))) continue;
    if (!visited_[n]) add(-r.force, r.contact_point);  // the contact is gone from the list
    o.refs[kept++] = r;
  }
  o.refs.resize(kept);
  if (o.refs.capacity() > 2 * kept + 64) o.refs.shrink_to_fit();
  // Scalar moment of the symmetrised tensor: sqrt(sum M_ij^2 / 2).
  double s2 = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double v =
          0.5 * (m[static_cast<std::size_t>(3 * i + j)] + m[static_cast<std::size_t>(3 * j + i)]);
      s2 += v * v;
    }
  const double m0 = std::sqrt(0.5 * s2);
  ++o.ev.evaluations;
  if (o.ev.m0_first < 0.0) o.ev.m0_first = m0;
  if (m0 > o.ev.m0) {
    o.ev.m0 = m0;
    o.ev.moment = m;
    o.ev.t_star = sim.time();
    o.ev.strain_star = strain;
  }
}

void AeMonitor::merge(std::size_t kept, std::size_t gone) {
  auto gi = open_.find(gone);
  auto ki = open_.find(kept);
  if (gi == open_.end() || ki == open_.end()) return;
  Open& k = ki->second;
  Open& g = gi->second;
  AeEvent& a = k.ev;
  const AeEvent& b = g.ev;
  a.first_crack = std::min(a.first_crack, b.first_crack);
  a.cracks += b.cracks;
  a.tensile += b.tensile;
  a.shear += b.shear;
  a.t_first = std::min(a.t_first, b.t_first);
  a.strain_first = std::min(a.strain_first, b.strain_first);
  a.t_last = std::max(a.t_last, b.t_last);
  a.strain_last = std::max(a.strain_last, b.strain_last);
  a.position_sum += b.position_sum;
  a.energy += b.energy;
  a.fracture_energy += b.fracture_energy;
  if (b.m0 > a.m0) {
    a.m0 = b.m0;
    a.moment = b.moment;
    a.t_star = b.t_star;
    a.strain_star = b.strain_star;
  }
  a.evaluations += b.evaluations;
  a.ke_gain = std::max(a.ke_gain, b.ke_gain);
  for (std::uint32_t p : g.source) {
    const auto pos = std::lower_bound(k.source.begin(), k.source.end(), p);
    if (pos == k.source.end() || *pos != p) k.source.insert(pos, p);
  }
  for (const Ref& r : g.refs) {
    const auto at = std::lower_bound(k.refs.begin(), k.refs.end(), r.key,
                                     [](const Ref& x, std::uint64_t kk) { return x.key < kk; });
    if (at == k.refs.end() || at->key != r.key) k.refs.insert(at, r);
  }
  for (const Watched& w : g.watched) {
    const auto pos =
        std::lower_bound(k.watched.begin(), k.watched.end(), w.particle,
                         [](const Watched& u, std::uint32_t i) { return u.particle < i; });
    if (pos != k.watched.end() && pos->particle == w.particle) continue;
    k.watched.insert(pos, w);
    k.ke_baseline += w.ke0;
  }
  open_.erase(gi);
}

void AeMonitor::close(std::size_t root) {
  const auto it = open_.find(root);
  if (it == open_.end()) return;
  AeEvent ev = it->second.ev;
  ev.source_particles = it->second.source.size();
  ev.monitored_particles = it->second.watched.size();
  done_.push_back(ev);
  done_root_.push_back(root);
  open_.erase(it);
}

void AeMonitor::after_step(const Simulation& sim, double strain, double deviatoric) {
  ++steps_;
  auto cracks = sim.cracks().reader();
  if (cracks.size() > seen_) {
    if (!clusterer_)
      throw InputError("acoustic emission", "shear_wave_speed", "unset",
                       "the monitor must be configured before the first crack");
    build_grid(sim);
    const ParticleStore& ps = sim.particles();
    find_incoming(sim, cracks);
    for (; seen_ < cracks.size(); ++seen_) {
      const CrackRecord& c = cracks[seen_];
      const double ef = fracture_energy(c, sim.bond_moduli(c.law), ps.planar(), ps.thickness());
      context_.push_back({strain, deviatoric, ef});
      std::size_t root;
      const auto i1 = static_cast<std::uint32_t>(ps.index_of(c.id1));
      const auto i2 = static_cast<std::uint32_t>(ps.index_of(c.id2));
      if (s_.linkage == analysis::Linkage::Grain) {
        // The crack's grains and those in contact with them; window 2 D_c / v_S.
        std::vector<std::uint32_t> touched{i1, i2};
        for (std::uint32_t p : {i1, i2})
          for_pairs_of(sim, p, [&](std::uint32_t q, const Vec3& f) {
            if (!is_zero(f)) touched.push_back(q);
          });
        const double tc = 2.0 * (2.0 * std::max(c.R1, c.R2)) / s_.shear_wave_speed;
        root = clusterer_->add_grain(seen_, c.time, tc, {i1, i2}, touched);
      } else {
        root = clusterer_->add(seen_, c.time, c.position);
      }
      Open& o = open_[root];
      if (o.ev.cracks == 0) {
        o.created = steps_;
        o.ev.first_crack = seen_;
        o.ev.t_first = c.time;
        o.ev.strain_first = strain;
      }
      ++o.ev.cracks;
      (c.mode == CrackMode::Tensile ? o.ev.tensile : o.ev.shear)++;
      o.ev.t_last = c.time;
      o.ev.strain_last = strain;
      o.ev.position_sum += c.position;
      o.ev.energy += c.energy.total();
      o.ev.fracture_energy += ef;
      add_source(sim, o, i1);
      add_source(sim, o, i2);
      watch_near(sim, o, c.position);
    }
  } else if (!open_.empty()) {
    clusterer_->close_before(sim.time());
    find_incoming(sim, cracks);
  }
  if (open_.empty()) {
    forget_incoming(sim.particles().size());  // read again for the next event's grains
    return;
  }
  if (s_.moment_interval > 1 && steps_ % s_.moment_interval != 0) return;
  // An event is first evaluated one step after it was created: its creation step is the
  // reference. Particles joining an open event have zero force change in their joining step.
  for (auto& [root, o] : open_)
    if (o.created != steps_) evaluate(sim, o, strain);
}

void AeMonitor::finish() {
  if (clusterer_) clusterer_->close_all();
  incoming_ = {};  // the caches of open events
  grid_ = {};
}

std::vector<std::size_t> AeMonitor::crack_events() const {
  std::vector<std::size_t> out(context_.size(), static_cast<std::size_t>(-1));
  if (!clusterer_) return out;
  std::map<std::size_t, std::size_t> index;
  for (std::size_t k = 0; k < done_root_.size(); ++k) index[done_root_[k]] = k;
  for (std::size_t c = 0; c < out.size(); ++c) {
    const auto it = index.find(clusterer_->event_of(c));
    if (it != index.end()) out[c] = it->second;
  }
  return out;
}

template <class Archive>
void AeMonitor::transfer(Archive& a) {
  a.label("ae monitor");
  a.value(s_);
  a.value(duration_);
  bool has_clusterer = clusterer_.has_value();
  a.value(has_clusterer);
  if constexpr (Archive::reading) {
    clusterer_.reset();
    if (has_clusterer) configure(s_.shear_wave_speed);
  }
  if (has_clusterer) {
    if constexpr (Archive::reading)
      clusterer_->load(a);
    else
      clusterer_->save(a);
  }
  std::uint64_t n = open_.size();
  a.value(n);
  auto it = open_.begin();
  for (std::uint64_t k = 0; k < n; ++k) {
    std::uint64_t root = 0;
    if constexpr (!Archive::reading) root = (it++)->first;
    a.value(root);
    Open& o = open_[root];
    a.value(o.ev);
    a.vector(o.source);
    a.vector(o.refs);
    a.vector(o.watched);
    a.value(o.ke_baseline);
    a.value(o.created);
  }
  done_.transfer(a);
  a.vector(done_root_);
  context_.transfer(a);
  a.value(seen_);
  a.value(steps_);
}

void AeMonitor::save(ArchiveWriter& a) const {
  const_cast<AeMonitor*>(this)->transfer(a);  // the writer only reads the fields
}

void AeMonitor::load(ArchiveReader& a) {
  open_.clear();
  transfer(a);
  if (done_root_.size() != done_.size() || seen_ != context_.size())
    throw InputError(a.where(), "ae monitor", "events", "the checkpoint is corrupt");
}

}  // namespace breccia
