// Smooth joints (docs/physics.md §5): the planes of an experiment, the bonds they replace at
// set-up and the neighbour pairs they claim at every rebuild.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/engine/pair_lists.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

using namespace engine_detail;

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

// The bonds that a joint plane cuts are removed (docs/physics.md §5, step 5): their pairs become
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
    std::vector<std::tuple<std::uint32_t, std::uint32_t, BondTag, typename JL::State>> add;
    for (const PendingJoint& pj : pending_joints_)
      add.emplace_back(
          pj.i, pj.j, pj.tag,
          JL::install(set.params, geometry(pj.i, pj.j), joint_planes_[pj.plane].normal, true));
    insert_sorted(set, add);
  });
  pending_joints_.clear();
}

// Neighbour pairs that a joint plane cuts, not bonded, without a contact and not yet joints,
// become unbonded joints (docs/physics.md §5, step 4: a contact created across the plane within its
// extent is a joint). Tested at every rebuild, before any such pair can touch.
template <class CL>
void Simulation::assign_joints_for(ContactSet<CL>& c) {
  if (joint_planes_.empty()) return;
  with_joint_set([&]<class JL>(BondSet<JL>& set) {
    map_bonds_to_pairs(set, c.pairs);
    std::vector<std::tuple<std::uint32_t, std::uint32_t, BondTag, typename JL::State>> add;
    for (std::size_t k = 0; k < c.pairs.size(); ++k) {
      if (set.bond_at_pair(k) != BondSet<JL>::kNoBond || c.has_history(k)) continue;
      bool bonded = false;
      std::apply(
          [&](const auto&... b) { ((bonded = bonded || b.bond_at_pair(k) != b.kNoBond), ...); },
          bonds_);
      if (bonded) continue;
      const std::uint32_t i = c.pairs.first[k], j = c.pairs.second[k];
      const int plane = cutting_plane(i, j);
      if (plane < 0) continue;
      add.emplace_back(i, j, BondTag{0},
                       JL::install(set.params, geometry(i, j), joint_planes_[plane].normal, false));
    }
    // Tags in pair order, over the ranks of a split sample in rank order.
    std::size_t before = 0, total = add.size();
    if (split_) {
      const std::vector<std::string> counts = ranks::all_gather(std::to_string(add.size()));
      total = 0;
      for (std::size_t r = 0; r < counts.size(); ++r) {
        if (r == static_cast<std::size_t>(ranks::rank())) before = total;
        total += std::stoull(counts[r]);
      }
    }
    next_bond_tag_ += before;
    for (auto& element : add) std::get<2>(element) = take_bond_tag();
    next_bond_tag_ += total - before - add.size();
    if (add.empty()) return;
    insert_sorted(set, add);
    map_bonds_to_pairs(set, c.pairs);
  });
}

void Simulation::assign_joints() {
  std::visit([&](auto& contacts) { assign_joints_for(contacts); }, contact_);
}

}  // namespace breccia
