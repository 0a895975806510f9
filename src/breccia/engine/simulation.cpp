#include "breccia/engine/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/engine/neighbour_grid.hpp"

namespace breccia {

namespace {

constexpr std::uint32_t kNoHeldBond = 0xffffffffu;  // no bond of the pair awaits judging

bool has_history(const Vec3& n_old) noexcept {
  return n_old.x != 0.0 || n_old.y != 0.0 || n_old.z != 0.0;
}

// Carries contact history from an old sorted pair list to a new one (same particle indexing).
template <class State>
void merge_history(const PairList& old_pairs, const std::vector<State>& old_state,
                   const PairList& new_pairs, std::vector<State>& new_state) {
  new_state.assign(new_pairs.size(), State{});
  if (old_pairs.offsets.empty()) return;
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(new_pairs.offsets.size()) - 1;
#pragma omp parallel for schedule(static, 1024) if (n > 4096)
  for (std::ptrdiff_t si = 0; si < n; ++si) {
    const std::size_t i = static_cast<std::size_t>(si);
    std::uint32_t a = old_pairs.offsets[i];
    const std::uint32_t ae = old_pairs.offsets[i + 1];
    for (std::uint32_t b = new_pairs.offsets[i]; b < new_pairs.offsets[i + 1]; ++b) {
      while (a < ae && old_pairs.second[a] < new_pairs.second[b]) ++a;
      if (a < ae && old_pairs.second[a] == new_pairs.second[b]) new_state[b] = old_state[a];
    }
  }
}

// Adds the pairs of `bonds` (sorted) that `pairs` (sorted) lacks. Rare: a bond stretched beyond
// R1 + R2 + skin. The index of `pairs` must be rebuilt afterwards.
void add_missing_pairs(const PairList& bonds, PairList& pairs) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> missing;
  std::size_t a = 0;
  for (std::size_t k = 0; k < bonds.size(); ++k) {
    const auto key = std::pair(bonds.first[k], bonds.second[k]);
    while (a < pairs.size() && std::pair(pairs.first[a], pairs.second[a]) < key) ++a;
    if (a == pairs.size() || std::pair(pairs.first[a], pairs.second[a]) != key)
      missing.push_back(key);
  }
  if (missing.empty()) return;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> all(pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) all[k] = {pairs.first[k], pairs.second[k]};
  all.insert(all.end(), missing.begin(), missing.end());
  std::sort(all.begin(), all.end());
  pairs.first.resize(all.size());
  pairs.second.resize(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) {
    pairs.first[k] = all[k].first;
    pairs.second[k] = all[k].second;
  }
}

// For each interacting pair, the index of its bond in `set` (or kNoBond). Both lists are sorted.
template <class Law>
void map_bonds_to_pairs(BondSet<Law>& set, const PairList& pairs) {
  set.bond_of_pair.assign(pairs.size(), BondSet<Law>::kNoBond);
  std::size_t a = 0;
  for (std::size_t k = 0; k < set.size(); ++k) {
    const auto key = std::pair(set.pairs.first[k], set.pairs.second[k]);
    while (std::pair(pairs.first[a], pairs.second[a]) < key) ++a;
    set.bond_of_pair[a] = static_cast<std::uint32_t>(k);
  }
}

// Merges new elements (i < j, tag, state) into a sorted bond-layout set.
template <class Law>
void insert_sorted(
    BondSet<Law>& set,
    std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint64_t, typename Law::State>>&
        added) {
  if (added.empty()) return;
  for (std::size_t k = 0; k < set.size(); ++k)
    added.emplace_back(set.pairs.first[k], set.pairs.second[k], set.tag[k], set.state[k]);
  std::sort(added.begin(), added.end(), [](const auto& a, const auto& b) {
    return std::pair(std::get<0>(a), std::get<1>(a)) < std::pair(std::get<0>(b), std::get<1>(b));
  });
  const std::size_t n = added.size();
  set.pairs = PairList{};
  set.pairs.first.resize(n);
  set.pairs.second.resize(n);
  set.tag.resize(n);
  set.state.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    std::tie(set.pairs.first[k], set.pairs.second[k], set.tag[k], set.state[k]) = added[k];
  set.intact.assign(n, 1);
  added.clear();
}

}  // namespace

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
  if (!(cfg_.skin >= 0.0) || !std::isfinite(cfg_.skin))
    throw InputError(where, "skin", num(cfg_.skin), "must be >= 0 m (0 = automatic)");
  std::visit(
      [&]<class Law>(ContactSet<Law>& c) {
        validate_params<Law>(c.params, std::string("contact law '") + std::string(Law::name) + "'");
        validate_params<Law>(c.wall_params,
                             std::string("wall contact law '") + std::string(Law::name) + "'");
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
    std::visit([&](auto& c) { rebuild(c); }, contact_);
  }
  return walls_.size() - 1;
}

void Simulation::set_local_damping(double alpha) {
  if (!(alpha >= 0.0 && alpha < 1.0))
    throw InputError("simulation", "local_damping", num(alpha), "allowed: 0 <= value < 1");
  cfg_.local_damping = alpha;
}

void Simulation::add_joint_plane(JointPlane plane) {
  const std::string where = "joint plane " + std::to_string(joint_planes_.size() + 1);
  if (initialised_)
    throw InputError(where, "plane", "", "joint planes must be added before initialise()");
  const double len = norm(plane.normal);
  if (!(len > 0.0) || !std::isfinite(len))
    throw InputError(where, "normal", "zero or not finite", "a nonzero finite vector is needed");
  plane.normal *= 1.0 / len;
  if (p_.planar() && plane.normal.z != 0.0)
    throw InputError(where, "normal", num(plane.normal.z) + " along z",
                     "a 2D joint is a line in the x-y plane: its normal has no z part");
  if (!(plane.radius > 0.0))
    throw InputError(where, "radius", num(plane.radius), "must be > 0 m (infinite: no limit)");
  if (!(plane.spacing >= 0.0) || !std::isfinite(plane.spacing))
    throw InputError(where, "spacing", num(plane.spacing),
                     "must be >= 0 m (0: one plane, else a set of parallel planes)");
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(plane.point[k]))
      throw InputError(where, "point", num(plane.point[k]), "must be finite");
  joint_planes_.push_back(plane);
}

// The first joint plane that cuts the branch of pair (i, j), or -1.
int Simulation::cutting_plane(std::uint32_t i, std::uint32_t j) const noexcept {
  for (std::size_t k = 0; k < joint_planes_.size(); ++k)
    if (joint_planes_[k].cuts(p_.pos_rad[i].x, p_.pos_rad[j].x)) return static_cast<int>(k);
  return -1;
}

// The bonds that a joint plane cuts are removed (physics.md §5, step 5): their pairs become
// joints. Bonded joints are installed with the bonds (same tags); unbonded ones come from the
// neighbour pairs at the first rebuild (assign_joints).
void Simulation::joints_replace_bonds() {
  if (joint_planes_.empty()) return;
  bool bonded = false;
  with_joint_set([&]<class JL>(BondSet<JL>& set) { bonded = JL::starts_bonded(set.params); });
  auto one = [&](auto& set) {
    std::size_t w = 0;
    for (std::size_t k = 0; k < set.tag.size(); ++k) {
      const std::uint32_t i = set.pairs.first[k], j = set.pairs.second[k];
      const int plane = cutting_plane(i, j);
      if (plane >= 0) {
        if (bonded)
          pending_joints_.push_back({i, j, static_cast<std::uint32_t>(plane), set.tag[k]});
        continue;
      }
      set.pairs.first[w] = i;
      set.pairs.second[w] = j;
      set.tag[w] = set.tag[k];
      ++w;
    }
    set.pairs.first.resize(w);
    set.pairs.second.resize(w);
    set.tag.resize(w);
  };
  std::apply([&](auto&... sets) { (one(sets), ...); }, bonds_);
}

void Simulation::install_pending_joints() {
  with_joint_set([&]<class JL>(BondSet<JL>& set) {
    std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint64_t, typename JL::State>> add;
    for (const PendingJoint& pj : pending_joints_)
      add.emplace_back(
          pj.i, pj.j, pj.tag,
          JL::install(set.params, geometry(pj.i, pj.j), joint_planes_[pj.plane].normal, true));
    insert_sorted(set, add);
  });
  pending_joints_.clear();
}

// Neighbour pairs that a joint plane cuts, not bonded, without a contact and not yet joints,
// become unbonded joints (physics.md §5, step 4: a contact created across the plane within its
// extent is a joint). Tested at every rebuild, before any such pair can touch.
template <class CL>
void Simulation::assign_joints(ContactSet<CL>& c) {
  if (joint_planes_.empty()) return;
  with_joint_set([&]<class JL>(BondSet<JL>& set) {
    map_bonds_to_pairs(set, c.pairs);
    std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint64_t, typename JL::State>> add;
    for (std::size_t k = 0; k < c.pairs.size(); ++k) {
      if (set.bond_of_pair[k] != BondSet<JL>::kNoBond || has_history(c.state[k].n_old)) continue;
      bool bonded = false;
      std::apply(
          [&](const auto&... b) { ((bonded = bonded || b.bond_of_pair[k] != b.kNoBond), ...); },
          bonds_);
      if (bonded) continue;
      const std::uint32_t i = c.pairs.first[k], j = c.pairs.second[k];
      const int plane = cutting_plane(i, j);
      if (plane < 0) continue;
      add.emplace_back(i, j, next_bond_tag_++,
                       JL::install(set.params, geometry(i, j), joint_planes_[plane].normal, false));
    }
    if (add.empty()) return;
    insert_sorted(set, add);
    map_bonds_to_pairs(set, c.pairs);
  });
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
  std::vector<std::uint64_t> tags(n);
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
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t i = set.pairs.first[k], j = set.pairs.second[k];
    set.state[k] =
        Law::install(set.params, geometry(i, j), frames<Law>(i, j), cfg_.seed, set.tag[k]);
  }
}

template <class Law>
void Simulation::compact_bonds(BondSet<Law>& set) {
  if (set.broken_since_compaction == 0) return;
  std::size_t w = 0;
  for (std::size_t k = 0; k < set.size(); ++k) {
    if (!set.intact[k]) continue;
    set.pairs.first[w] = set.pairs.first[k];
    set.pairs.second[w] = set.pairs.second[k];
    set.tag[w] = set.tag[k];
    set.state[w] = set.state[k];
    ++w;
  }
  set.pairs.first.resize(w);
  set.pairs.second.resize(w);
  set.tag.resize(w);
  set.state.resize(w);
  set.intact.assign(w, 1);
  set.broken_since_compaction = 0;
}

void Simulation::initialise() {
  if (initialised_) return;
  if (p_.size() == 0)
    throw InputError("simulation", "particles", "0", "at least one particle is needed");
  if (p_.planar() && p_.planar_body() == PlanarBody::Disk &&
      std::holds_alternative<ContactSet<HertzMindlin>>(contact_))
    throw InputError("contact law", "law", "hertz_mindlin",
                     "Hertz contacts need 3D spheres or 2D planar spheres (physics.md §3.4); "
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
  ext_force_.assign(n, {});
  ext_torque_.assign(n, {});
  drive_force_prev_.assign(2 * n, {});
  double rsum = 0.0;
  for (const PosRad& q : p_.pos_rad) rsum += q.r;
  skin_ = cfg_.skin > 0.0 ? cfg_.skin : 0.4 * rsum / static_cast<double>(n);
  std::visit([&](auto& c) { rebuild(c); }, contact_);
  estimate_time_step();
  for (Wall& w : walls_) {
    w.update_motion(-0.5 * dt_);
    w.force_prev = {};
    w.radial_force_prev = 0.0;
    w.advanced_velocity = w.velocity;
    w.advanced_radial_speed = w.radial_speed;
  }
  initialised_ = true;
  sample_requested_ = true;  // the first step's sample is the energy baseline
}

void Simulation::estimate_time_step() {
  const std::size_t n = p_.size();
  std::vector<double> k_tr(n, 0.0), k_rot(n, 0.0);
  // Bonds and joints (§1.5, §5): translational max(K_n, K_s); rotational max(K_b, K_t) +
  // K_s |r|^2 (a joint has no couple: its max_moment_stiffness is 0).
  auto add_set = [&]<class Law>(BondSet<Law>& s) {
    for (std::size_t k = 0; k < s.size(); ++k) {
      const auto i = s.pairs.first[k], j = s.pairs.second[k];
      const PairGeometry g = geometry(i, j);
      const auto& st = s.state[k];
      const double kt = Law::max_stiffness(st), ks = Law::shear_stiffness(st);
      const double km = Law::max_moment_stiffness(st);
      k_tr[i] += kt;
      k_tr[j] += kt;
      k_rot[i] += km + ks * norm2(g.r1);
      k_rot[j] += km + ks * norm2(g.r2);
    }
  };
  std::apply([&](auto&... sets) { (add_set(sets), ...); }, bonds_);
  std::apply([&](auto&... sets) { (add_set(sets), ...); }, joints_);
  // Contacts: every neighbour pair that touches or nearly touches (gap < 0.1 R_min) may carry a
  // contact during loading; so does a particle near a wall. Each particle also gets at least one
  // contact of its own size, so that free particles have a finite estimate.
  double dt_rayleigh = std::numeric_limits<double>::infinity();
  std::visit(
      [&]<class CL>(ContactSet<CL>& c) {
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          const auto i = c.pairs.first[k], j = c.pairs.second[k];
          const PairGeometry g = geometry(i, j);
          if (-g.delta > 0.1 * std::min(g.R1, g.R2)) continue;
          double kn = 0.0, ks = 0.0;
          CL::timestep_stiffness(c.params, g, kn, ks);
          k_tr[i] += std::max(kn, ks);
          k_tr[j] += std::max(kn, ks);
          k_rot[i] += ks * g.R1 * g.R1;
          k_rot[j] += ks * g.R2 * g.R2;
        }
        for (std::size_t i = 0; i < n; ++i) {
          const PosRad& q = p_.pos_rad[i];
          PairGeometry g = pair_geometry({}, q.r, {2.0 * q.r, 0, 0}, q.r, {}, {}, {}, {}, 1, 1,
                                         p_.planar(), p_.thickness());
          double kn = 0.0, ks = 0.0;
          CL::timestep_stiffness(c.params, g, kn, ks);
          k_tr[i] += std::max(kn, ks);
          k_rot[i] += ks * q.r * q.r;
          for (const Wall& w : walls_) {
            Vec3 nrm;
            const double gap = w.gap(q.x, q.r, nrm);
            if (gap > 0.1 * q.r) continue;
            PairGeometry gw = g;
            gw.wall = true;
            gw.R1 = w.convex_radius(p_.planar());
            gw.delta = std::max(-gap, 0.0);
            CL::timestep_stiffness(c.wall_params, gw, kn, ks);
            k_tr[i] += std::max(kn, ks);
            k_rot[i] += ks * q.r * q.r;
          }
          if constexpr (requires { CL::rayleigh_time_step(c.params, 1.0, 1.0); })
            dt_rayleigh =
                std::min(dt_rayleigh, cfg_.hertz_rayleigh_factor *
                                          CL::rayleigh_time_step(c.params, q.r, p_.density[i]));
        }
      },
      contact_);
  double crit = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    if (k_tr[i] > 0.0) crit = std::min(crit, std::sqrt(p_.mass[i] / k_tr[i]));
    if (k_rot[i] > 0.0) crit = std::min(crit, std::sqrt(p_.inertia[i] / k_rot[i]));
  }
  dt_crit_ = crit;
  const double recommended = std::min(cfg_.safety_factor * crit, dt_rayleigh);
  if (!std::isfinite(recommended) || !(recommended > 0.0))
    throw InputError("time step", "estimate", num(recommended),
                     "could not estimate a stable time step: check stiffnesses and masses");
  if (cfg_.time_step > 0.0) {
    dt_ = cfg_.time_step;
    if (dt_ > recommended)
      warnings_.push_back("time_step " + num(dt_) + " s is above the stable estimate " +
                          num(recommended) + " s (critical " + num(crit) +
                          " s times safety factor); the run may blow up");
  } else {
    dt_ = recommended;
  }
}

bool Simulation::needs_rebuild() const noexcept {
  const double d = std::sqrt(max_disp2_);
  double wall = 0.0;
  for (const Wall& w : walls_) wall = std::max(wall, w.moved);
  return 2.0 * (d + radius_growth_) > skin_ || d + radius_growth_ + wall > skin_;
}

template <class CL>
void Simulation::rebuild(ContactSet<CL>& contacts) {
  std::apply([&](auto&... set) { (compact_bonds(set), ...); }, bonds_);
  PairList old_pairs = std::move(contacts.pairs);
  std::vector<typename CL::State> old_state = std::move(contacts.state);
  contacts.pairs = PairList{};
  build_neighbour_pairs(p_.pos_rad, skin_, p_.planar(), contacts.pairs);
  // Every intact bond must be an interacting pair even if it stretched beyond the search range.
  std::apply([&](auto&... set) { (add_missing_pairs(set.pairs, contacts.pairs), ...); }, bonds_);
  std::apply([&](auto&... set) { (add_missing_pairs(set.pairs, contacts.pairs), ...); }, joints_);
  contacts.pairs.build_index(p_.size());
  std::apply([&](auto&... set) { (map_bonds_to_pairs(set, contacts.pairs), ...); }, bonds_);
  std::apply([&](auto&... set) { (map_bonds_to_pairs(set, contacts.pairs), ...); }, joints_);
  merge_history(old_pairs, old_state, contacts.pairs, contacts.state);
  assign_joints(contacts);
  contacts.slot.assign(contacts.pairs.size(), PairSlot{});
  // Wall candidates: particles within the skin of each wall, history carried by particle index.
  auto& wall_sets = std::get<std::vector<WallContacts<CL>>>(wall_contacts_);
  for (std::size_t wi = 0; wi < walls_.size(); ++wi) {
    WallContacts<CL>& wc = wall_sets[wi];
    WallContacts<CL> fresh;
    std::size_t a = 0;
    for (std::uint32_t i = 0; i < p_.size(); ++i) {
      Vec3 nrm;
      if (walls_[wi].gap(p_.pos_rad[i].x, p_.pos_rad[i].r, nrm) >= skin_) continue;
      fresh.particle.push_back(i);
      while (a < wc.particle.size() && wc.particle[a] < i) ++a;
      fresh.state.push_back(a < wc.particle.size() && wc.particle[a] == i ? wc.state[a]
                                                                          : typename CL::State{});
    }
    fresh.force.assign(fresh.particle.size(), {});
    fresh.torque.assign(fresh.particle.size(), {});
    fresh.normal_force.assign(fresh.particle.size(), 0.0);
    fresh.stiffness.assign(fresh.particle.size(), 0.0);
    wc = std::move(fresh);
    walls_[wi].moved = 0.0;
  }
  x_at_build_.resize(p_.size());
  for (std::size_t i = 0; i < p_.size(); ++i) x_at_build_[i] = p_.pos_rad[i].x;
  max_disp2_ = 0.0;
  radius_growth_ = 0.0;
  ++rebuilds_;
}

// One pass over all interacting pairs: the bond(s) of the pair, then its contact, summed into one
// slot. Each pair's geometry is computed once; bonded pairs that overlap get the contact force in
// parallel (physics.md §4.0). Breaks are collected per block and processed in pair order.
template <class CL>
void Simulation::compute_pairs(ContactSet<CL>& c) {
  const std::size_t n = c.pairs.size();
  const std::size_t nb = block_count(n);
  block_dis_.assign(nb, PairDissipation{});
  block_joint_dis_.assign(nb, PairDissipation{});
  if (block_failures_.size() < nb) block_failures_.resize(nb);
  const double dt = dt_;
  for_blocks(n, [&](std::size_t begin, std::size_t end, std::size_t blk) {
    PairDissipation dis, joint_dis;
    auto& fails = block_failures_[blk];
    fails.clear();
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t i = c.pairs.first[k], j = c.pairs.second[k];
      PairGeometry g;
      bool have_geometry = false;
      Vec3 force, couple;
      std::uint32_t law_index = 0;
      bool contact_off = false;  // an intact bond whose law excludes the contact (§4.0)
      // A bond judged on the interface totals (§4.4) waits for its pair's contact force.
      PairForce held;
      std::uint32_t held_law = kNoHeldBond, held_bond = 0;
      auto bond_part = [&]<class Law>(BondSet<Law>& set) {
        // A run uses one bond law: the others' sets are empty, and their index is not read.
        const std::uint32_t b = set.size() == 0 ? BondSet<Law>::kNoBond : set.bond_of_pair[k];
        if (b != BondSet<Law>::kNoBond && set.intact[b]) {
          if (!have_geometry) g = geometry(i, j);
          have_geometry = true;
          if constexpr (judged_on_interface<Law>) {
            held = Law::loads(set.state[b], g, dt);
            held_law = law_index;
            held_bond = b;
            ++law_index;
            return;
          }
          BondFailure f;
          const PairForce pf = Law::compute(set.params, set.state[b], g, frames<Law>(i, j), dt, f);
          if (f.broken) {
            fails.push_back({law_index, b, f});
          } else {
            force += pf.force;
            couple += pf.couple;
            contact_off = contact_off || !Law::contact_while_bonded(set.params);
          }
        }
        ++law_index;
      };
      std::apply([&](auto&... set) { (bond_part(set), ...); }, bonds_);
      // A joint replaces the pair's contact law (physics.md §5); a bonded joint that breaks goes
      // on unbonded, so its force of the step is applied.
      auto joint_part = [&]<class JL>(BondSet<JL>& set) {
        // Most samples have no joints: no load of the pair's index then.
        const std::uint32_t b = set.size() == 0 ? BondSet<JL>::kNoBond : set.bond_of_pair[k];
        if (b != BondSet<JL>::kNoBond) {
          if (!have_geometry) g = geometry(i, j);
          have_geometry = true;
          contact_off = true;
          BondFailure f;
          const PairForce pf = JL::compute(set.params, set.state[b], g, dt, joint_dis, f);
          if (f.broken) fails.push_back({law_index, b, f});
          force += pf.force;
          couple += pf.couple;
        }
        ++law_index;
      };
      std::apply([&](auto&... set) { (joint_part(set), ...); }, joints_);
      if (!have_geometry) {
        const PosRad& a = p_.pos_rad[i];
        const PosRad& b = p_.pos_rad[j];
        const double reach = a.r + b.r;
        if (norm2(b.x - a.x) < reach * reach || has_history(c.state[k].n_old)) {
          g = geometry(i, j);
          have_geometry = true;
        }
      }
      PairSlot& s = c.slot[k];
      if (!have_geometry) {
        s = PairSlot{};
        continue;
      }
      if (contact_off && has_history(c.state[k].n_old)) {
        // Bonded under load with a law that excludes the contact: its spring energy is lost
        // without work (§4.0, D_del) and the contact starts afresh when the bond breaks.
        dis.deleted += CL::stored_energy(c.params, c.state[k]);
        c.state[k] = {};
      }
      Vec3 contact_force;
      if (!contact_off && (g.delta > 0.0 || has_history(c.state[k].n_old))) {
        const PairForce pf = CL::compute(c.params, c.state[k], g, dt, dis);
        force += pf.force;
        couple += pf.couple;
        contact_force = pf.force;
      }
      if (held_law != kNoHeldBond) {
        std::uint32_t li = 0;
        auto judge = [&]<class Law>(BondSet<Law>& set) {
          if constexpr (judged_on_interface<Law>) {
            if (li == held_law) {
              BondFailure f;
              Law::judge(set.params, set.state[held_bond], g, contact_force, f);
              if (f.broken) {
                fails.push_back({held_law, held_bond, f});
              } else {
                force += held.force;
                couple += held.couple;
              }
            }
          }
          ++li;
        };
        std::apply([&](auto&... set) { (judge(set), ...); }, bonds_);
      }
      s.force = force;
      s.torque1 = cross(g.r1, -force) - couple;
      s.torque2 = cross(g.r2, force) + couple;
    }
    block_dis_[blk] = dis;
    block_joint_dis_[blk] = joint_dis;
  });
  d_pairs_ += ordered_sum(block_dis_);
  const PairDissipation joint_dis = ordered_sum(block_joint_dis_);
  d_pairs_ += joint_dis;
  d_joint_slip_ += joint_dis.slip;
  // Breaks are processed as one batch in pair order (independent of the thread count).
  for (std::size_t blk = 0; blk < nb; ++blk)
    for (const Failure& f : block_failures_[blk]) {
      std::uint32_t law_index = 0;
      std::apply(
          [&](auto&... set) {
            ((law_index++ == f.law ? process_failure(set, f.bond, f.info) : void()), ...);
          },
          bonds_);
      std::apply(
          [&](auto&... set) {
            ((law_index++ == f.law ? record_crack(set, f.bond, f.info) : void()), ...);
          },
          joints_);
    }
}

template <class Law>
void Simulation::process_failure(BondSet<Law>& set, std::uint32_t bond, const BondFailure& info) {
  set.intact[bond] = 0;
  ++set.broken_since_compaction;
  record_crack(set, bond, info);
}

template <class Law>
void Simulation::record_crack(const BondSet<Law>& set, std::uint32_t bond,
                              const BondFailure& info) {
  const std::uint32_t i = set.pairs.first[bond], j = set.pairs.second[bond];
  const PairGeometry g = geometry(i, j);
  // The record names the pair by increasing tag with the normal from the first to the second
  // (§4.0); F_n, |F_s|, M_t = M . n and |M_b| do not depend on the orientation.
  const bool swap = p_.tag[i] > p_.tag[j];
  CrackRecord r;
  r.step = step_;
  r.time = time_;
  r.law = Law::name;
  r.bond_tag = set.tag[bond];
  r.id1 = p_.tag[swap ? j : i];
  r.id2 = p_.tag[swap ? i : j];
  r.R1 = swap ? g.R2 : g.R1;
  r.R2 = swap ? g.R1 : g.R2;
  r.position = p_.pos_rad[i].x + g.r1 + g.n * info.point_shift;
  r.normal = swap ? -g.n : g.n;
  r.mode = info.mode;
  r.bond_radius = info.bond_radius;
  r.Fn = info.Fn;
  r.Fs = info.Fs;
  r.Mt = info.Mt;
  r.Mb = info.Mb;
  r.sigma = info.sigma;
  r.tau = info.tau;
  r.ratio_t = info.ratio_t;
  r.ratio_s = info.ratio_s;
  r.energy = info.energy;
  released_ += info.energy;
  cracks_.push_back(r);
}

template <class CL>
void Simulation::compute_walls(ContactSet<CL>& c) {
  auto& wall_sets = std::get<std::vector<WallContacts<CL>>>(wall_contacts_);
  const double dt = dt_;
  for (std::size_t wi = 0; wi < walls_.size(); ++wi) {
    Wall& w = walls_[wi];
    WallContacts<CL>& wc = wall_sets[wi];
    const std::size_t n = wc.particle.size();
    const std::size_t nb = block_count(n);
    block_dis_.assign(nb, PairDissipation{});
    for_blocks(n, [&](std::size_t begin, std::size_t end, std::size_t blk) {
      PairDissipation dis;
      for (std::size_t k = begin; k < end; ++k) {
        const std::uint32_t i = wc.particle[k];
        const PosRad& q = p_.pos_rad[i];
        Vec3 nrm;
        const double gap = w.gap(q.x, q.r, nrm);
        if (gap >= 0.0 && !has_history(wc.state[k].n_old)) {
          wc.force[k] = {};
          wc.torque[k] = {};
          wc.normal_force[k] = 0.0;
          wc.stiffness[k] = 0.0;
          continue;
        }
        PairGeometry g;
        g.n = nrm;
        g.delta = -gap;
        g.d = q.r - g.delta;
        g.r2 = nrm * -(q.r - 0.5 * g.delta);
        g.r1 = {};
        g.vc = p_.vel[i] + cross(p_.angvel[i], g.r2) - w.surface_velocity(nrm);
        g.w1 = {};
        g.w2 = p_.angvel[i];
        g.R1 = w.convex_radius(p_.planar());
        g.R2 = q.r;
        g.m2 = p_.mass[i];
        g.wall = true;
        g.planar = p_.planar();
        g.thickness = p_.thickness();
        const PairForce pf = CL::compute(c.wall_params, wc.state[k], g, dt, dis);
        wc.force[k] = pf.force;
        wc.torque[k] = cross(g.r2, pf.force) + pf.couple;
        wc.normal_force[k] = dot(pf.force, nrm);
        double kn = 0.0, ks = 0.0;
        if (g.delta > 0.0) CL::timestep_stiffness(c.wall_params, g, kn, ks);
        wc.stiffness[k] = kn;
      }
      block_dis_[blk] = dis;
    });
    d_pairs_ += ordered_sum(block_dis_);
    Vec3 total;
    double radial = 0.0, stiffness = 0.0;
    std::size_t touching = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t i = wc.particle[k];
      ext_force_[i] += wc.force[k];
      ext_torque_[i] += wc.torque[k];
      total += wc.force[k];
      radial += wc.normal_force[k];
      touching += wc.normal_force[k] != 0.0 ? 1 : 0;
      stiffness += wc.stiffness[k];
    }
    // Trapezoidal work over the wall's last displacement (matches the leapfrog kinetic energy):
    // the motion that made it, not the one a servo has set for the next step.
    const double dw = w.shape != WallShape::Cylinder
                          ? 0.5 * dot(w.force_prev + total, w.advanced_velocity) * dt
                          : 0.5 * (w.radial_force_prev + radial) * w.advanced_radial_speed * dt;
    w.work += dw;
    w_walls_ += dw;
    w.force = total;
    w.radial_force = radial;
    w.force_prev = total;
    w.radial_force_prev = radial;
    w.contacts = touching;
    w.contact_stiffness = stiffness;
  }
}

template <class CL>
void Simulation::integrate(ContactSet<CL>& c, bool sample) {
  const std::size_t n = p_.size();
  const std::size_t nb = block_count(n);
  block_int_.assign(nb, IntegrateBlock{});
  const bool has_user_force = !user_force_.empty();
  const double dt = dt_;
  const double alpha = cfg_.local_damping;
  const Vec3 gravity = cfg_.gravity;
  const bool planar = p_.planar();
  for_blocks(n, [&](std::size_t begin, std::size_t end, std::size_t blk) {
    IntegrateBlock acc;
    for (std::size_t i = begin; i < end; ++i) {
      Vec3 f = ext_force_[i], t = ext_torque_[i];
      ext_force_[i] = {};
      ext_torque_[i] = {};
      gather_pairs(c.pairs, c.slot, i, f, t);
      Vec3 f_user;
      if (has_user_force) {
        f_user = user_force_[i];
        user_force_[i] = {};
        f += f_user;
      }
      p_.force[i] = f;
      p_.torque[i] = t;
      const double m = p_.mass[i], inertia = p_.inertia[i];
      f += gravity * m;
      if (planar) {
        f.z = 0.0;
        t.x = 0.0;
        t.y = 0.0;
      }
      const Vec3 v_old = p_.vel[i], w_old = p_.angvel[i];
      Vec3 v_new, w_new;
      if (p_.motion[i] == Motion::Free) {
        if (alpha > 0.0) {
          // Cundall local damping, sign tested with the predicted full-step velocity (§2.1).
          const Vec3 vp = v_old + f * (0.5 * dt / m);
          const Vec3 wp = w_old + t * (0.5 * dt / inertia);
          Vec3 fd, td;
          for (int k = 0; k < 3; ++k) {
            fd[k] = -alpha * std::abs(f[k]) * ((vp[k] > 0.0) - (vp[k] < 0.0));
            td[k] = -alpha * std::abs(t[k]) * ((wp[k] > 0.0) - (wp[k] < 0.0));
          }
          f += fd;
          t += td;
          v_new = v_old + f * (dt / m);
          w_new = w_old + t * (dt / inertia);
          // The loss is booked as minus the work of the damping force with the same trapezoidal
          // rule as every other term, (1/2) F_d . (v^{n-1/2} + v^{n+1/2}) dt, so the ledger
          // closes; it equals physics.md's alpha dt sum |F||v~| to O(dt). The half that pairs
          // with v^{n+1/2} belongs to the next interval and is removed from a sample.
          acc.local_damping -= 0.5 * (dot(fd, v_old + v_new) + dot(td, w_old + w_new)) * dt;
          if (sample) acc.damping_boundary -= 0.5 * (dot(fd, v_new) + dot(td, w_new)) * dt;
        } else {
          v_new = v_old + f * (dt / m);
          w_new = w_old + t * (dt / inertia);
        }
        acc.gravity += m * dot(gravity, v_old) * dt;
      } else {
        // Fixed or driven: the driver supplies whatever force keeps the prescribed motion; its
        // work is booked with the trapezoidal rule like the walls'.
        const bool fixed = p_.motion[i] == Motion::Fixed;
        v_new = fixed ? Vec3{} : p_.drive_vel[i];
        w_new = fixed ? Vec3{} : p_.drive_angvel[i];
        if (planar) {
          v_new.z = 0.0;
          w_new.x = 0.0;
          w_new.y = 0.0;
        }
        const Vec3 fd = (v_new - v_old) * (m / dt) - f;
        const Vec3 td = (w_new - w_old) * (inertia / dt) - t;
        Vec3& fd_prev = drive_force_prev_[2 * i];
        Vec3& td_prev = drive_force_prev_[2 * i + 1];
        acc.drive += 0.5 * (dot(fd_prev + fd, v_old) + dot(td_prev + td, w_old)) * dt;
        acc.gravity += m * dot(gravity, v_old) * dt;
        fd_prev = fd;
        td_prev = td;
      }
      if (has_user_force) {
        acc.external += 0.5 * dot(f_user, v_old + v_new) * dt;
        if (sample) acc.external_boundary += 0.5 * dot(f_user, v_new) * dt;
      }
      p_.vel[i] = v_new;
      p_.angvel[i] = w_new;
      const Vec3 dx = v_new * dt;
      p_.pos_rad[i].x += dx;
      p_.displacement[i] += dx;
      if (planar)
        p_.angle[i] += w_new.z * dt;
      else
        p_.orientation[i] = integrate_orientation(p_.orientation[i], w_new, dt);
      acc.max_disp2 = std::max(acc.max_disp2, norm2(p_.pos_rad[i].x - x_at_build_[i]));
      if (sample) {
        // Kinetic energy at t_n as leapfrog conserves it: (1/2) m v^{n-1/2} . v^{n+1/2}. With the
        // trapezoidal work rule the balance of §2.4 then closes exactly for linear springs (it
        // differs from (1/2) m v^2 by O(dt^2)).
        acc.ke_t += 0.5 * m * dot(v_old, v_new);
        acc.ke_r += 0.5 * inertia * dot(w_old, w_new);
      }
    }
    block_int_[blk] = acc;
  });
  IntegrateBlock total;
  for (const IntegrateBlock& s : block_int_) {
    total.local_damping += s.local_damping;
    total.gravity += s.gravity;
    total.drive += s.drive;
    total.external += s.external;
    total.damping_boundary += s.damping_boundary;
    total.external_boundary += s.external_boundary;
    total.ke_t += s.ke_t;
    total.ke_r += s.ke_r;
    total.max_disp2 = std::max(total.max_disp2, s.max_disp2);
  }
  d_local_ += total.local_damping;
  w_gravity_ += total.gravity;
  w_drive_ += total.drive;
  w_external_ += total.external;
  max_disp2_ = std::max(max_disp2_, total.max_disp2);
  if (sample) {
    ledger_.kinetic_translational = total.ke_t;
    ledger_.kinetic_rotational = total.ke_r;
    d_local_boundary_ = total.damping_boundary;
    w_external_boundary_ = total.external_boundary;
  }
}

template <class CL>
void Simulation::sample_stored_energy(ContactSet<CL>& c) {
  BondEnergy bond;
  std::apply(
      [&](auto&... sets) {
        auto one = [&]<class Law>(BondSet<Law>& s) {
          std::vector<BondEnergy> part(block_count(s.size()));
          for_blocks(s.size(), [&](std::size_t b, std::size_t e, std::size_t blk) {
            BondEnergy acc;
            for (std::size_t k = b; k < e; ++k)
              if (s.intact[k]) acc += Law::energy(s.state[k]);
            part[blk] = acc;
          });
          bond += ordered_sum(part);
        };
        (one(sets), ...);
      },
      bonds_);
  std::vector<double> part(block_count(c.pairs.size()));
  for_blocks(c.pairs.size(), [&](std::size_t b, std::size_t e, std::size_t blk) {
    double acc = 0.0;
    for (std::size_t k = b; k < e; ++k) acc += CL::stored_energy(c.params, c.state[k]);
    part[blk] = acc;
  });
  double contact = ordered_sum(part);
  for (const auto& wc : std::get<std::vector<WallContacts<CL>>>(wall_contacts_))
    for (const auto& st : wc.state) contact += CL::stored_energy(c.wall_params, st);
  // Joints: a bonded joint's springs are bond energy by component, an unbonded joint's are
  // contact energy (it replaces a contact).
  std::apply(
      [&](auto&... sets) {
        auto one = [&]<class JL>(BondSet<JL>& s) {
          for (std::size_t k = 0; k < s.size(); ++k) {
            const BondEnergy e = JL::energy(s.state[k]);
            if (JL::is_bonded(s.state[k]))
              bond += e;
            else
              contact += e.total();
          }
        };
        (one(sets), ...);
      },
      joints_);

  EnergyLedger& L = ledger_;
  L.step = step_;
  L.time = time_;
  L.bond = bond;
  L.contact = contact;
  L.boundary_work = w_walls_ + w_drive_;
  L.body_force_work = w_gravity_;
  L.external_work = w_external_ - w_external_boundary_;
  L.joint_dilation = d_pairs_.dilation;
  L.friction = d_pairs_.slip;
  L.joint_slip = d_joint_slip_;
  L.local_damping = d_local_ - d_local_boundary_;
  L.viscous_damping = d_pairs_.viscous;
  L.deleted = d_pairs_.deleted;
  L.released = released_;
  L.broken_bonds = cracks_.size();
  if (!baseline_) baseline_ = L;
  const EnergyLedger& B = *baseline_;
  const double work = L.work_in() - B.work_in();
  const double d_stored = L.stored() - B.stored();
  const double d_dissipated = L.dissipated() - B.dissipated();
  L.residual = work - d_stored - d_dissipated;
  const double scale = std::max({std::abs(work), std::abs(d_stored), std::abs(d_dissipated),
                                 std::numeric_limits<double>::min()});
  L.residual_relative = L.residual / scale;
}

template <class CL>
void Simulation::step_impl(ContactSet<CL>& contacts) {
  if (needs_rebuild()) rebuild(contacts);
  const bool sample =
      sample_requested_ || (cfg_.energy_interval > 0 && step_ % cfg_.energy_interval == 0);
  compute_pairs(contacts);
  compute_walls(contacts);
  integrate(contacts, sample);
  if (sample) {
    sample_stored_energy(contacts);
    sample_requested_ = false;
  }
  for (Wall& w : walls_) {
    w.update_motion(time_ + 0.5 * dt_);
    // A free body's leapfrog kick: it feels minus the force it exerts on the grains.
    if (w.free_body()) {
      w.velocity += (cfg_.gravity - w.force * (1.0 / w.mass)) * dt_;
      if (p_.planar()) w.velocity.z = 0.0;
    }
    w.advance(dt_);
  }
  time_ += dt_;
  ++step_;
}

void Simulation::step() {
  if (!initialised_) initialise();
  std::visit([&](auto& c) { step_impl(c); }, contact_);
}

void Simulation::run(std::uint64_t steps) {
  // run() drives the stages before a test (packing, settling); a signal stops them between
  // steps. The test's own loop steps one at a time and checkpoints instead.
  for (std::uint64_t s = 0; s < steps; ++s) {
    if (s % 64 == 0) throw_if_interrupted("preparing the sample");
    step();
  }
}

std::size_t Simulation::intact_bonds() const noexcept {
  std::size_t n = 0;
  std::apply([&](const auto&... set) { ((n += set.intact_count()), ...); }, bonds_);
  return n;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> Simulation::intact_bond_pairs() const {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  auto one = [&](const auto& b) {
    for (std::size_t k = 0; k < b.size(); ++k)
      if (b.intact[k]) out.emplace_back(b.pairs.first[k], b.pairs.second[k]);
  };
  std::apply([&](const auto&... set) { (one(set), ...); }, bonds_);
  return out;
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
  std::visit(
      [&](const auto& c) {
        for (const auto& s : c.state) n += has_history(s.n_old) ? 1 : 0;
      },
      contact_);
  return n;
}

void Simulation::scale_radii(double factor) {
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

void Simulation::refresh_time_step() {
  if (intact_bonds() > 0)
    throw InputError("time step", "bonds", std::to_string(intact_bonds()),
                     "the time step is only re-estimated before bonds are installed");
  if (!initialised_) return;
  estimate_time_step();
  baseline_.reset();
  sample_requested_ = true;
}

PairStress Simulation::pair_stress() const {
  PairStress out;
  out.coordination.assign(p_.size(), 0);
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          const PairSlot& s = c.slot[k];
          const std::uint32_t i = c.pairs.first[k], j = c.pairs.second[k];
          const Vec3 l = p_.pos_rad[j].x - p_.pos_rad[i].x;
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
              out.lf[static_cast<std::size_t>(3 * a + b)] += l[a] * s.force[b];
          const double reach = p_.pos_rad[i].r + p_.pos_rad[j].r;
          if (norm2(l) >= reach * reach) continue;
          const PairGeometry g = geometry(i, j);
          double kn = 0.0, ks = 0.0;
          CL::timestep_stiffness(c.params, g, kn, ks);
          out.radius_stiffness += kn * (g.R1 + g.R2) * g.d;
          ++out.touching;
          ++out.coordination[i];
          ++out.coordination[j];
        }
      },
      contact_);
  return out;
}

std::size_t Simulation::neighbour_pairs() const noexcept {
  return std::visit([](const auto& c) { return c.pairs.size(); }, contact_);
}

}  // namespace breccia
