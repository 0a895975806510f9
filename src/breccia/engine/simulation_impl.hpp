#pragma once
// Public template members of Simulation (included at the end of simulation.hpp).
#include <algorithm>
#include <cstdint>
#include <string>

#include "breccia/core/error.hpp"
#include "breccia/engine/neighbour_grid.hpp"

namespace breccia {

template <class Law>
std::uint64_t Simulation::add_bond(std::uint64_t tag1, std::uint64_t tag2) {
  if (initialised_)
    throw InputError("simulation", "bond", std::to_string(tag1) + "-" + std::to_string(tag2),
                     "bonds must be added before initialise()");
  if (tag1 == tag2)
    throw InputError("bond list", "bond", std::to_string(tag1) + "-" + std::to_string(tag2),
                     "a particle cannot be bonded to itself");
  auto& set = std::get<BondSet<Law>>(bonds_);
  // Pairs are oriented by particle index, like contacts, so that a bond and the contact of the
  // same pair share one geometry; crack records report the tags in increasing order.
  const auto a = static_cast<std::uint32_t>(p_.index_of(tag1, "bond list"));
  const auto b = static_cast<std::uint32_t>(p_.index_of(tag2, "bond list"));
  set.pairs.first.push_back(std::min(a, b));
  set.pairs.second.push_back(std::max(a, b));
  const BondTag tag = take_bond_tag();
  set.tag.push_back(tag);
  return tag;
}

template <class Law>
void Simulation::set_bond_params(const typename Law::Params& params) {
  const std::string where = std::string("bond law '") + std::string(Law::name) + "'";
  validate_params<Law>(params, where);
  // The combinations a law refuses in experiment files, refused here too (Params built in C++).
  if constexpr (requires { Law::check(params, where, std::int64_t{3}); })
    Law::check(params, where, p_.planar() ? 2 : 3);
  auto& set = std::get<BondSet<Law>>(bonds_);
  // A bond's section follows from its grains' radii and these parameters at every step.
  if (set.intact_count() > 0)
    throw InputError(where, "parameters", std::to_string(set.intact_count()) + " intact bonds",
                     "can only be set before bonds of the law are installed");
  set.params = params;
  prepare_params<Law>(set.params);
}

template <class Law>
void Simulation::set_joint_params(const typename Law::Params& params) {
  validate_params<Law>(params, std::string("joint law '") + std::string(Law::name) + "'");
  auto& set = std::get<BondSet<Law>>(joints_);
  set.params = params;
  prepare_params<Law>(set.params);
  std::uint32_t index = 0;
  for_each_type<JointLaws>([&]<class J>() {
    if (std::is_same_v<J, Law>) joint_law_ = index;
    ++index;
  });
}

template <class Law>
std::size_t Simulation::bond_touching_pairs(double gap_tolerance) {
  if (!(gap_tolerance >= 0.0))
    throw InputError("bonding", "gap_tolerance", std::to_string(gap_tolerance), "must be >= 0 m");
  PairList near;
  // A slightly wider search, then the exact test g <= tolerance.
  build_neighbour_pairs(p_.pos_rad, gap_tolerance * 1.0001 + 1e-300, p_.planar(), near);
  std::size_t added = 0;
  for (std::size_t k = 0; k < near.size(); ++k) {
    const PosRad& a = p_.pos_rad[near.first[k]];
    const PosRad& b = p_.pos_rad[near.second[k]];
    if (norm(b.x - a.x) - a.r - b.r <= gap_tolerance) {
      add_bond<Law>(p_.tag[near.first[k]], p_.tag[near.second[k]]);
      ++added;
    }
  }
  return added;
}

}  // namespace breccia
