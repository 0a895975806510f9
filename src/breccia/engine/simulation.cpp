#include "breccia/engine/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/engine/pair_lists.hpp"

// Set-up, the step's sequence of stages and the queries. The stages live in their own files:
// neighbours.cpp, pair_pass.cpp, wall_pass.cpp, integrator.cpp, energy_ledger.cpp, joints.cpp,
// time_step.cpp, checkpoint.cpp.
namespace breccia {

using namespace engine_detail;

Simulation::Simulation(ParticleStore particles, EngineConfig config, ContactModel contact)
    : p_(std::move(particles)), cfg_(config), contact_(std::move(contact)) {
  const std::string where = "engine settings";
  if (!(cfg_.time_step >= 0.0) || !std::isfinite(cfg_.time_step))
    throw InputError(where, "time_step", num(cfg_.time_step), "must be >= 0 s (0 = automatic)");
  if (!(cfg_.safety_factor > 0.0 && cfg_.safety_factor <= 1.0))
    throw InputError(where, "safety_factor", num(cfg_.safety_factor), "allowed: 0 < value <= 1");
  if (!(cfg_.hertz_rayleigh_factor > 0.0 && cfg_.hertz_rayleigh_factor <= 1.0))
    throw InputError(where, "hertz_rayleigh_factor", num(cfg_.hertz_rayleigh_factor),
                     "allowed: 0 < value <= 1");
  if (!(cfg_.local_damping >= 0.0 && cfg_.local_damping < 1.0))
    throw InputError(where, "local_damping", num(cfg_.local_damping), "allowed: 0 <= value < 1");
  for (const auto& [key, value] :
       {std::pair{"bond_normal_damping_ratio", cfg_.bond_normal_damping_ratio},
        std::pair{"bond_shear_damping_ratio", cfg_.bond_shear_damping_ratio}})
    if (!(value >= 0.0 && value <= 1.0))
      throw InputError(where, key, num(value), "allowed: 0 <= value <= 1");
  set_dynamic_damping(cfg_.dynamic_damping_alpha, cfg_.dynamic_damping_radius,
                      cfg_.dynamic_damping_time);
  isa_ = cfg_.instruction_set.value_or(best_instruction_set());
  if (!instruction_set_supported(isa_))
    throw InputError(where, "instruction_set", std::string(instruction_set_name(isa_)),
                     fmt::format("this CPU (or this build) runs at most '{}'",
                                 instruction_set_name(best_instruction_set())));
  if (!(cfg_.skin >= 0.0) || !std::isfinite(cfg_.skin))
    throw InputError(where, "skin", num(cfg_.skin), "must be >= 0 m (0 = automatic)");
  std::visit(
      [&]<class Law>(ContactSet<Law>& c) {
        validate_params<Law>(c.params, std::string("contact law '") + std::string(Law::name) + "'");
        validate_params<Law>(c.wall_params,
                             std::string("wall contact law '") + std::string(Law::name) + "'");
        // make_contact_model picks the layout; one built by hand must not lose the moments.
        if (!Law::rolling && (rolling_limits(c.params).on() || rolling_limits(c.wall_params).on()))
          throw InputError(std::string("contact law '") + std::string(Law::name) + "'",
                           "rolling_friction", num(c.params.rolling_friction),
                           "rolling resistance needs the contact model of make_contact_model");
        wall_contacts_ = std::vector<WallContacts<Law>>{};
      },
      contact_);
}

std::size_t Simulation::add_wall(Wall w) {
  if (w.shape != WallShape::Plane && !(w.radius > 0.0))
    throw InputError("wall '" + w.name + "'", "radius", num(w.radius), "must be > 0 m");
  if (!(w.mass >= 0.0) || !std::isfinite(w.mass))
    throw InputError("wall '" + w.name + "'", "mass", num(w.mass),
                     "must be >= 0 kg (0: prescribed motion; > 0: a free rigid body)");
  if (w.free_body() && w.controlled)
    throw InputError("wall '" + w.name + "'", "mass", num(w.mass),
                     "a free rigid body cannot also be controlled");
  if (p_.planar() && w.shape == WallShape::Sphere &&
      (w.point.z != 0.0 || w.velocity.z != 0.0 || w.target_velocity.z != 0.0))
    throw InputError("wall '" + w.name + "'", "centre/velocity", "out of plane",
                     "in 2D a sphere wall is a circle in the x-y plane (z = 0) moving in it");
  if (p_.planar() && (w.shape == WallShape::Cylinder || w.shape == WallShape::Rod) &&
      (w.axis.x != 0.0 || w.axis.y != 0.0))
    throw InputError("wall '" + w.name + "'", "axis", "not along z",
                     "in 2D a cylinder or rod wall is a circle in the x-y plane: its axis must be "
                     "z");
  if (p_.planar() && w.shape == WallShape::Plane &&
      (w.normal.z != 0.0 || w.target_velocity.z != 0.0))
    throw InputError("wall '" + w.name + "'", "normal/velocity", "out of plane",
                     "2D walls have normals and velocities in the x-y plane");
  walls_.push_back(std::move(w));
  std::visit([&]<class Law>(std::vector<WallContacts<Law>>& v) { v.emplace_back(); },
             wall_contacts_);
  if (initialised_) {
    // Between stages (scripts): the new wall starts moving at the next step, and its contact
    // candidates are found by rebuilding the lists now (pair histories carry over).
    Wall& added = walls_.back();
    added.update_motion(time_ - 0.5 * dt_);
    added.force_prev = {};
    added.radial_force_prev = 0.0;
    added.advanced_velocity = added.velocity;
    added.advanced_radial_speed = added.radial_speed;
    rebuild();
  }
  return walls_.size() - 1;
}

// The set-up changes of packing read and change every particle (and the time step from every
// contact); a split sample holds its own part of those only.
void Simulation::refuse_on_split_sample(const char* what) const {
  if (split_)
    throw std::logic_error(std::string("Simulation::") + what +
                           ": not on a sample split over ranks (packing runs in one process)");
}

void Simulation::set_local_damping(double alpha) {
  if (!(alpha >= 0.0 && alpha < 1.0))
    throw InputError("simulation", "local_damping", num(alpha), "allowed: 0 <= value < 1");
  cfg_.local_damping = alpha;
}

template <class Law>
void Simulation::install_bonds(BondSet<Law>& set) {
  const std::size_t n = set.tag.size();
  // Sort by (first, second) for locality and the gather index; reject duplicates.
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::pair(set.pairs.first[a], set.pairs.second[a]) <
           std::pair(set.pairs.first[b], set.pairs.second[b]);
  });
  PairList sorted;
  std::vector<BondTag> tags(n);
  sorted.first.resize(n);
  sorted.second.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    sorted.first[k] = set.pairs.first[order[k]];
    sorted.second[k] = set.pairs.second[order[k]];
    tags[k] = set.tag[order[k]];
    if (k > 0 && sorted.first[k] == sorted.first[k - 1] && sorted.second[k] == sorted.second[k - 1])
      throw InputError(
          "bond list", "bond",
          std::to_string(p_.tag[sorted.first[k]]) + "-" + std::to_string(p_.tag[sorted.second[k]]),
          "each pair may be bonded once per law");
  }
  set.pairs = std::move(sorted);
  set.tag = std::move(tags);
  set.state.resize(n);
  set.intact.assign(n, 1);
  set.broken_since_compaction = 0;
  // Parameters never given through set_bond_params are the law's defaults: they are made ready
  // here too.
  prepare_params<Law>(set.params);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t i = set.pairs.first[k], j = set.pairs.second[k];
    set.state[k] = Law::install(set.params, geometry(i, j),
                                {body_orientation(i), body_orientation(j)}, cfg_.seed, set.tag[k]);
  }
}

void Simulation::initialise() {
  if (initialised_) return;
  if (p_.size() == 0)
    throw InputError("simulation", "particles", "0", "at least one particle is needed");
  if (p_.planar() && p_.planar_body() == PlanarBody::Disk &&
      std::visit([](const auto& c) { return c.law_name() == HertzMindlin::name; }, contact_))
    throw InputError("contact law", "law", "hertz_mindlin",
                     "Hertz contacts need 3D spheres or 2D planar spheres (docs/physics.md §3.4); "
                     "use 'linear' for 2D disks");
  auto refuse_3d = [&]<class Law>(const BondSet<Law>& set) {
    if constexpr (planar_only_law<Law>)
      if (!p_.planar() && set.size() > 0)
        throw InputError("bond law", "law", std::string(Law::name),
                         "a 2D law (disks or planar spheres): set engine.dimension = 2");
  };
  std::apply([&](const auto&... set) { (refuse_3d(set), ...); }, bonds_);
  joints_replace_bonds();
  std::apply([&](auto&... set) { (install_bonds(set), ...); }, bonds_);
  install_pending_joints();
  const std::size_t n = p_.size();
  drive_force_prev_.assign(p_.has_drives() ? 2 * n : 0, {});
  double rsum = 0.0;
  for (const PosRad& q : p_.pos_rad) rsum += q.r;
  skin_ = cfg_.skin > 0.0 ? cfg_.skin : 0.4 * rsum / static_cast<double>(n);
  rebuild();
  estimate_time_step();
  for (Wall& w : walls_) {
    w.update_motion(-0.5 * dt_);
    w.force_prev = {};
    w.radial_force_prev = 0.0;
    w.advanced_velocity = w.velocity;
    w.advanced_radial_speed = w.radial_speed;
  }
  reserve_crack_catalogue();
  initialised_ = true;
  sample_requested_ = true;  // the first step's sample is the energy baseline
}

// Every intact bond and bonded joint can break once, and nothing else makes a crack: the
// catalogue's room for all of them (or for its resident records, when it has a file) is taken at
// once, so that it never reallocates.
void Simulation::reserve_crack_catalogue() {
  cracks_.reserve_more(intact_bonds() + bonded_joints());
}

void Simulation::step() {
  if (retired_)
    throw std::logic_error("Simulation::step: the simulation's interactions are retired");
  if (!initialised_) initialise();
  // A split sample's ghosts, and the last step's integrator partials with them, before the
  // rebuild test reads the largest displacement those partials hold.
  const bool ghosts_fresh = split_ && split_->integration_pending;
  if (ghosts_fresh) {
    refresh_ghosts(true);
    split_->integration_pending = false;
    add_integration_totals(false);
  }
  if (needs_rebuild())
    rebuild();  // on a split sample, with the ghosts' values
  else if (split_ && !ghosts_fresh)
    refresh_ghosts();
  const bool sample =
      sample_requested_ || (cfg_.energy_interval > 0 && step_ % cfg_.energy_interval == 0);
  const std::size_t cracks_before = cracks_.size();
  compute_pairs();
  compute_walls();  // on a split sample, with every rank's cracks of the step
  mark_dynamic_damping(cracks_before);
  integrate(sample);
  if (sample) {
    sample_stored_energy();
    sample_requested_ = false;
  }
  advance_walls();
  time_ += dt_;
  ++step_;
  if (split_) split_->particles_whole = false;  // the other ranks' grains moved
}

void Simulation::retire_interactions() {
  std::visit(
      [](auto& c) {
        c.pairs = {};
        c.history = {};
        c.stores = {};
        c.packed = {};
        c.kept_force = {};
      },
      contact_);
  const auto free_index = [](auto&... set) { ((set.bond_of_pair = {}), ...); };
  std::apply(free_index, bonds_);
  std::apply(free_index, joints_);
  x_at_build_ = {};
  cross_slots_ = {};
  block_dis_ = {};
  block_joint_dis_ = {};
  block_int_ = {};
  wall_block_starts_ = {};
  wall_blocks_ = {};
  block_failures_ = {};
  retired_ = true;
}

// Walls move after the grains: prescribed motion of the next half step, a free body's kick.
void Simulation::advance_walls() {
  for (Wall& w : walls_) {
    w.update_motion(time_ + 0.5 * dt_);
    // A free body's leapfrog kick: it feels minus the force it exerts on the grains.
    if (w.free_body()) {
      w.velocity += (cfg_.gravity - w.force * (1.0 / w.mass)) * dt_;
      if (p_.planar()) w.velocity.z = 0.0;
    }
    w.advance(dt_);
  }
}

void Simulation::run(std::uint64_t steps) {
  // run() drives the stages before a test (packing, settling); a signal stops them at the next
  // step (a relaxed load a step: a million-grain packing's 64 steps took half a minute). The
  // test's own loop steps one at a time and checkpoints instead.
  for (std::uint64_t s = 0; s < steps; ++s) {
    throw_if_interrupted("preparing the sample");
    step();
  }
}

std::size_t Simulation::intact_bonds() const noexcept {
  std::size_t n = 0;
  std::apply([&](const auto&... set) { ((n += set.intact_count()), ...); }, bonds_);
  return n;
}

BondTag Simulation::take_bond_tag() {
  if (next_bond_tag_ > std::numeric_limits<BondTag>::max())
    throw InputError("bonds", "bond tag", std::to_string(next_bond_tag_),
                     "a run makes at most " + std::to_string(std::numeric_limits<BondTag>::max()) +
                         " bonds and joints (32-bit tags)");
  return static_cast<BondTag>(next_bond_tag_++);
}

std::size_t Simulation::intact_bond_sites() const noexcept {
  std::size_t n = 0;
  const auto one = [&]<class Law>(const BondSet<Law>& set) {
    for (std::size_t k = 0; k < set.state.size(); ++k)
      if (set.intact[k]) {
        if constexpr (requires { Law::bonded_sites(set.params, set.state[k]); })
          n += static_cast<std::size_t>(Law::bonded_sites(set.params, set.state[k]));
        else
          ++n;
      }
  };
  std::apply([&](const auto&... set) { (one(set), ...); }, bonds_);
  return n;
}

void Simulation::for_each_intact_bond(
    const std::function<void(std::uint32_t, std::uint32_t)>& f) const {
  auto one = [&](const auto& b) {
    for (std::size_t k = 0; k < b.size(); ++k)
      if (b.intact[k]) f(b.pairs.first[k], b.pairs.second[k]);
  };
  if (split()) {
    const BondSets whole = whole_bonds();
    std::apply([&](const auto&... set) { (one(set), ...); }, whole);
    return;
  }
  std::apply([&](const auto&... set) { (one(set), ...); }, bonds_);
}

std::size_t Simulation::joint_count() const noexcept {
  std::size_t n = 0;
  std::apply([&](const auto&... set) { ((n += set.size()), ...); }, joints_);
  return n;
}

std::size_t Simulation::bonded_joints() const noexcept {
  std::size_t n = 0;
  auto one = [&]<class JL>(const BondSet<JL>& s) {
    for (const auto& st : s.state) n += JL::is_bonded(st) ? 1 : 0;
  };
  std::apply([&](const auto&... set) { (one(set), ...); }, joints_);
  return n;
}

BondModuli Simulation::bond_moduli(std::string_view law) const noexcept {
  BondModuli out;
  std::apply(
      [&]<class... Laws>(const BondSet<Laws>&... set) {
        ((Laws::name == law ? (out = Laws::moduli(set.params), 0) : 0), ...);
      },
      bonds_);
  return out;
}

std::size_t Simulation::active_contacts() const noexcept {
  std::size_t n = 0;
  std::visit([&](const auto& c) { n = c.active(); }, contact_);
  return n;
}

void Simulation::scale_radii(double factor) {
  refuse_on_split_sample("scale_radii");
  if (!(factor > 0.0) || !std::isfinite(factor))
    throw InputError("radius scaling", "factor", num(factor), "must be a finite number > 0");
  if (intact_bonds() > 0)
    throw InputError("radius scaling", "bonds", std::to_string(intact_bonds()),
                     "radii can only be scaled before bonds are installed");
  double grow = 0.0;
  for (std::size_t i = 0; i < p_.size(); ++i) {
    double& r = p_.pos_rad[i].r;
    grow = std::max(grow, (factor - 1.0) * r);
    r *= factor;
    p_.mass[i] = p_.mass_of(r, p_.density[i]);
    p_.inertia[i] = p_.inertia_of(p_.mass[i], r);
  }
  radius_growth_ += std::max(grow, 0.0);
  baseline_.reset();
  sample_requested_ = true;
}

void Simulation::set_radius(std::size_t i, double radius) {
  refuse_on_split_sample("set_radius");
  if (!(radius > 0.0) || !std::isfinite(radius) || i >= p_.size())
    throw InputError("radius change", "radius", num(radius), "must be a finite number > 0");
  if (intact_bonds() > 0)
    throw InputError("radius change", "bonds", std::to_string(intact_bonds()),
                     "radii can only be changed before bonds are installed");
  double& r = p_.pos_rad[i].r;
  radius_growth_ += std::max(radius - r, 0.0);
  r = radius;
  p_.mass[i] = p_.mass_of(r, p_.density[i]);
  p_.inertia[i] = p_.inertia_of(p_.mass[i], r);
  baseline_.reset();
  sample_requested_ = true;
}

void Simulation::place_particle(std::size_t i, const Vec3& position, double radius) {
  set_radius(i, radius);
  p_.pos_rad[i].x = position;
  p_.vel[i] = {};
  p_.angvel[i] = {};
  radius_growth_ = std::max(radius_growth_, skin_);  // the lists no longer cover it: rebuild
}

void Simulation::displace_particle(std::size_t i, const Vec3& dx) {
  refuse_on_split_sample("displace_particle");
  if (i >= p_.size() || !std::isfinite(norm2(dx)))
    throw InputError("particle displacement", "displacement", num(norm(dx)),
                     "must be finite, for a particle of the sample");
  if (intact_bonds() > 0)
    throw InputError("particle displacement", "bonds", std::to_string(intact_bonds()),
                     "particles can only be displaced before bonds are installed");
  p_.pos_rad[i].x += dx;
  p_.displacement[i] += dx;
  if (!x_at_build_.empty())
    max_disp2_ = std::max(max_disp2_, norm2(p_.pos_rad[i].x - x_at_build_[i]));
  baseline_.reset();
  sample_requested_ = true;
}

PairStress Simulation::pair_stress() const {
  PairStress out;
  out.coordination.assign(p_.size(), 0);
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          const Vec3 force = pair_force(c, k);
          const std::uint32_t i = c.pairs.first[k], j = c.pairs.second[k];
          const Vec3 l = p_.pos_rad[j].x - p_.pos_rad[i].x;
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
              out.lf[static_cast<std::size_t>(3 * a + b)] += l[a] * force[b];
          const double reach = p_.pos_rad[i].r + p_.pos_rad[j].r;
          if (norm2(l) >= reach * reach) continue;
          const PairGeometry g = geometry(i, j);
          double kn = 0.0, ks = 0.0;
          CL::timestep_stiffness(c.params, g, kn, ks);
          out.radius_stiffness += kn * (g.R1 + g.R2) * g.d;
          for (int a = 0; a < 3; ++a)
            out.axial_stiffness[static_cast<std::size_t>(a)] +=
                kn * l[a] * l[a] * l[a] * l[a] / norm2(l);
          ++out.touching;
          ++out.coordination[i];
          ++out.coordination[j];
        }
      },
      contact_);
  return out;
}

Simulation::ParticleStressStream::ParticleStressStream(const Simulation& sim, std::size_t chunk)
    : sim_(sim), wall_at_(sim.walls().size(), 0), chunk_(std::max<std::size_t>(chunk, 1)) {}

// A pair (q, p) has q < p, so the pairs of a chunk's particles as second lie before the chunk's
// own rows: one scan of those rows per chunk.
void Simulation::ParticleStressStream::read_chunk(std::size_t begin) {
  std::visit(
      [&](const auto& c) {
        const PairList& l = c.pairs;
        const std::size_t n = l.offsets.size() - 1;
        chunk_begin_ = begin;
        chunk_end_ = std::min(n, begin + chunk_);
        const std::uint32_t scanned = l.offsets[chunk_end_];
        in_offsets_.assign(chunk_end_ - chunk_begin_ + 1, 0);
        for (std::uint32_t k = 0; k < scanned; ++k)
          if (l.second[k] >= chunk_begin_ && l.second[k] < chunk_end_)
            ++in_offsets_[l.second[k] - chunk_begin_ + 1];
        for (std::size_t i = 0; i + 1 < in_offsets_.size(); ++i)
          in_offsets_[i + 1] += in_offsets_[i];
        in_slot_.resize(in_offsets_.back());
        std::vector<std::uint32_t> fill(in_offsets_.begin(), in_offsets_.end() - 1);
        for (std::uint32_t k = 0; k < scanned; ++k)
          if (l.second[k] >= chunk_begin_ && l.second[k] < chunk_end_)
            in_slot_[fill[l.second[k] - chunk_begin_]++] = k;
      },
      sim_.contact_);
}

std::array<double, 9> Simulation::ParticleStressStream::at(std::size_t p) {
  const Simulation& s = sim_;
  std::array<double, 9> t{};
  // -(x_c - x_p) (x) F^{c->p}, with x_c - x_p the lever arm r of the pair geometry.
  auto add = [&](const Vec3& arm, const Vec3& force) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) t[static_cast<std::size_t>(3 * a + b)] -= arm[a] * force[b];
  };
  auto zero = [](const Vec3& f) { return f.x == 0.0 && f.y == 0.0 && f.z == 0.0; };
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        const PairList& l = c.pairs;
        if (l.offsets.size() > p + 1) {
          // Pairs with p second (their first grain is lower: they come first in pair order),
          // then those with p first.
          if (p < chunk_begin_ || p >= chunk_end_) read_chunk(p);
          const std::size_t row = p - chunk_begin_;
          for (std::uint32_t m = in_offsets_[row]; m < in_offsets_[row + 1]; ++m) {
            const std::uint32_t k = in_slot_[m];
            const Vec3 f = s.pair_force(c, k);
            if (zero(f)) continue;
            add(s.geometry(l.first[k], static_cast<std::uint32_t>(p)).r2, f);
          }
          for (std::uint32_t k = l.offsets[p]; k < l.offsets[p + 1]; ++k) {
            const Vec3 f = s.pair_force(c, k);
            if (zero(f)) continue;
            add(s.geometry(static_cast<std::uint32_t>(p), l.second[k]).r1, -f);
          }
        }
        const auto& wall_sets = std::get<std::vector<WallContacts<CL>>>(s.wall_contacts_);
        for (std::size_t wi = 0; wi < s.walls_.size(); ++wi) {
          const WallContacts<CL>& wc = wall_sets[wi];
          std::size_t& e = wall_at_[wi];
          while (e < wc.particle.size() && wc.particle[e] < p) ++e;
          if (e == wc.particle.size() || wc.particle[e] != p || zero(wc.force[e])) continue;
          const PosRad& q = s.p_.pos_rad[p];
          Vec3 n;
          const double gap = s.walls_[wi].gap(q.x, q.r, n);
          add(n * -(q.r + 0.5 * gap), wc.force[e]);
        }
      },
      s.contact_);
  const double r = s.p_.pos_rad[p].r;
  const double volume = s.p_.planar() ? std::numbers::pi * r * r * s.p_.thickness()
                                      : 4.0 / 3.0 * std::numbers::pi * r * r * r;
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) {
      const double v = 0.5 * (t[3 * a + b] + t[3 * b + a]) / volume;
      t[3 * a + b] = t[3 * b + a] = v;
    }
  return t;
}

std::vector<std::array<double, 9>> Simulation::particle_stress() const {
  std::vector<std::array<double, 9>> out(p_.size());
  ParticleStressStream stream(*this);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = stream.at(i);
  return out;
}

std::size_t Simulation::neighbour_pairs() const noexcept {
  return std::visit([](const auto& c) { return c.pairs.size(); }, contact_);
}

std::size_t Simulation::cross_block_pairs() const noexcept {
  return std::visit([](const auto& c) { return c.pairs.cross_slots(); }, contact_);
}

}  // namespace breccia
