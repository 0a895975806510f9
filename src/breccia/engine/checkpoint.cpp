// Checkpoints of the engine: every member that carries state from one step to the next, in a
// fixed order with section labels. Restoring needs no set-up call: the neighbour lists, bond
// index maps and per-block scratch come back as they were, so the next step is the one the
// uninterrupted run would have taken.
#include <string_view>
#include <utility>

#include "breccia/core/archive.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

namespace {

void save_pairs(ArchiveWriter& a, const PairList& l) {
  a.vector(l.first);
  a.vector(l.second);
  a.vector(l.offsets);
  a.vector(l.in_offsets);
  a.vector(l.in_slot);
}

void load_pairs(ArchiveReader& a, PairList& l) {
  a.vector(l.first);
  a.vector(l.second);
  a.vector(l.offsets);
  a.vector(l.in_offsets);
  a.vector(l.in_slot);
  // Bond lists carry no gather index (empty offsets and slots).
  if (l.second.size() != l.first.size() ||
      (!l.in_slot.empty() && l.in_slot.size() != l.first.size()) ||
      l.in_offsets.size() != l.offsets.size())
    throw InputError(a.where(), "pair list", std::to_string(l.first.size()),
                     "array lengths differ: the checkpoint is corrupt");
}

// Walls hold a name (not plain data): written field by field. The size check below fails to
// compile when a field is added, as a reminder to add it here.
static_assert(sizeof(Wall) == 304, "Wall changed: update the checkpoint (engine/checkpoint.cpp)");

void save_wall(ArchiveWriter& a, const Wall& w) {
  a.string(w.name);
  a.value(w.shape);
  a.value(w.point);
  a.value(w.normal);
  a.value(w.axis);
  a.value(w.radius);
  a.value(w.target_velocity);
  a.value(w.target_radial_speed);
  a.value(w.ramp);
  a.value(w.controlled);
  a.value(w.velocity);
  a.value(w.radial_speed);
  a.value(w.force);
  a.value(w.contacts);
  a.value(w.contact_stiffness);
  a.value(w.work);
  a.value(w.radial_force);
  a.value(w.force_prev);
  a.value(w.radial_force_prev);
  a.value(w.moved);
}

void load_wall(ArchiveReader& a, Wall& w) {
  a.string(w.name);
  a.value(w.shape);
  a.value(w.point);
  a.value(w.normal);
  a.value(w.axis);
  a.value(w.radius);
  a.value(w.target_velocity);
  a.value(w.target_radial_speed);
  a.value(w.ramp);
  a.value(w.controlled);
  a.value(w.velocity);
  a.value(w.radial_speed);
  a.value(w.force);
  a.value(w.contacts);
  a.value(w.contact_stiffness);
  a.value(w.work);
  a.value(w.radial_force);
  a.value(w.force_prev);
  a.value(w.radial_force_prev);
  a.value(w.moved);
}

// The static name of a bond law (crack records point at it).
std::string_view bond_law_name(const std::string& name, const std::string& where) {
  std::string_view out;
  [&]<class... Laws>(TypeList<Laws...>) {
    ((name == Laws::name ? (out = Laws::name, 0) : 0), ...);
  }(BondLaws{});
  if (out.empty())
    throw InputError(where, "crack law", name, "not a bond law of this build of Breccia");
  return out;
}

// Emplaces alternative `index` of a variant (default-constructed).
template <class Variant, std::size_t... I>
void emplace_index(Variant& v, std::size_t index, std::index_sequence<I...>) {
  ((index == I ? (v.template emplace<I>(), 0) : 0), ...);
}

}  // namespace

void Simulation::save_state(ArchiveWriter& a) const {
  // Fails to compile when a member is added: add it below (and to restore) if it carries state
  // from one step to the next, then update the size.
  static_assert(sizeof(Simulation) == 2000, "Simulation changed: update engine/checkpoint.cpp");
  a.label("simulation");
  p_.save(a);
  a.value(cfg_);

  a.label("contacts");
  a.value(static_cast<std::uint64_t>(contact_.index()));
  std::visit(
      [&]<class CL>(const ContactSet<CL>& c) {
        static_assert(std::is_trivially_copyable_v<typename CL::Params>);
        a.value(c.params);
        a.value(c.wall_params);
        save_pairs(a, c.pairs);
        a.vector(c.state);
        a.vector(c.slot);
      },
      contact_);
  std::visit(
      [&]<class CL>(const std::vector<WallContacts<CL>>& v) {
        a.value(static_cast<std::uint64_t>(v.size()));
        for (const WallContacts<CL>& w : v) {
          a.vector(w.particle);
          a.vector(w.state);
          a.vector(w.force);
          a.vector(w.torque);
          a.vector(w.normal_force);
          a.vector(w.stiffness);
        }
      },
      wall_contacts_);

  a.label("bonds");
  std::apply(
      [&](const auto&... set) {
        (
            [&](const auto& b) {
              a.value(b.params);
              save_pairs(a, b.pairs);
              a.vector(b.tag);
              a.vector(b.state);
              a.vector(b.intact);
              a.vector(b.bond_of_pair);
              a.value(static_cast<std::uint64_t>(b.broken_since_compaction));
            }(set),
            ...);
      },
      bonds_);

  a.label("walls");
  a.value(static_cast<std::uint64_t>(walls_.size()));
  for (const Wall& w : walls_) save_wall(a, w);

  a.label("clock");
  a.value(dt_);
  a.value(dt_crit_);
  a.value(time_);
  a.value(skin_);
  a.value(step_);
  a.value(rebuilds_);
  a.value(next_bond_tag_);
  a.value(initialised_);
  a.value(sample_requested_);
  a.vector(x_at_build_);
  a.vector(ext_force_);
  a.vector(ext_torque_);
  a.vector(user_force_);
  a.vector(drive_force_prev_);
  a.value(max_disp2_);
  a.value(radius_growth_);

  a.label("cracks");
  a.value(static_cast<std::uint64_t>(cracks_.size()));
  for (const CrackRecord& c : cracks_) {
    a.string(std::string(c.law));
    CrackRecord plain = c;
    plain.law = {};  // a pointer into this process: restored from the name
    a.value(plain);
  }
  a.value(static_cast<std::uint64_t>(warnings_.size()));
  for (const std::string& w : warnings_) a.string(w);

  a.label("ledger");
  a.value(ledger_);
  a.value(baseline_.has_value());
  if (baseline_) a.value(*baseline_);
  a.value(w_walls_);
  a.value(w_drive_);
  a.value(w_gravity_);
  a.value(w_external_);
  a.value(d_local_);
  a.value(d_local_boundary_);
  a.value(w_external_boundary_);
  a.value(d_pairs_);
  a.value(released_);
  a.label("end of simulation");
}

Simulation Simulation::restore(ArchiveReader& a) {
  Simulation s{RestoreTag{}};
  a.label("simulation");
  s.p_.load(a);
  a.value(s.cfg_);

  a.label("contacts");
  const auto law = a.get<std::uint64_t>();
  constexpr std::size_t kLaws = std::variant_size_v<ContactModel>;
  if (law >= kLaws)
    throw InputError(a.where(), "contact law", std::to_string(law),
                     "not a contact law of this build of Breccia");
  emplace_index(s.contact_, law, std::make_index_sequence<kLaws>{});
  emplace_index(s.wall_contacts_, law, std::make_index_sequence<kLaws>{});
  std::visit(
      [&]<class CL>(ContactSet<CL>& c) {
        a.value(c.params);
        a.value(c.wall_params);
        load_pairs(a, c.pairs);
        a.vector(c.state);
        a.vector(c.slot);
      },
      s.contact_);
  std::visit(
      [&]<class CL>(std::vector<WallContacts<CL>>& v) {
        v.resize(a.get<std::uint64_t>());
        for (WallContacts<CL>& w : v) {
          a.vector(w.particle);
          a.vector(w.state);
          a.vector(w.force);
          a.vector(w.torque);
          a.vector(w.normal_force);
          a.vector(w.stiffness);
        }
      },
      s.wall_contacts_);

  a.label("bonds");
  std::apply(
      [&](auto&... set) {
        (
            [&](auto& b) {
              a.value(b.params);
              load_pairs(a, b.pairs);
              a.vector(b.tag);
              a.vector(b.state);
              a.vector(b.intact);
              a.vector(b.bond_of_pair);
              b.broken_since_compaction = a.get<std::uint64_t>();
            }(set),
            ...);
      },
      s.bonds_);

  a.label("walls");
  s.walls_.resize(a.get<std::uint64_t>());
  for (Wall& w : s.walls_) load_wall(a, w);

  a.label("clock");
  a.value(s.dt_);
  a.value(s.dt_crit_);
  a.value(s.time_);
  a.value(s.skin_);
  a.value(s.step_);
  a.value(s.rebuilds_);
  a.value(s.next_bond_tag_);
  a.value(s.initialised_);
  a.value(s.sample_requested_);
  a.vector(s.x_at_build_);
  a.vector(s.ext_force_);
  a.vector(s.ext_torque_);
  a.vector(s.user_force_);
  a.vector(s.drive_force_prev_);
  a.value(s.max_disp2_);
  a.value(s.radius_growth_);

  a.label("cracks");
  s.cracks_.resize(a.get<std::uint64_t>());
  for (CrackRecord& c : s.cracks_) {
    const std::string name = a.string();
    a.value(c);
    c.law = bond_law_name(name, a.where());
  }
  s.warnings_.resize(a.get<std::uint64_t>());
  for (std::string& w : s.warnings_) a.string(w);

  a.label("ledger");
  a.value(s.ledger_);
  if (a.get<bool>()) s.baseline_ = a.get<EnergyLedger>();
  a.value(s.w_walls_);
  a.value(s.w_drive_);
  a.value(s.w_gravity_);
  a.value(s.w_external_);
  a.value(s.d_local_);
  a.value(s.d_local_boundary_);
  a.value(s.w_external_boundary_);
  a.value(s.d_pairs_);
  a.value(s.released_);
  a.label("end of simulation");

  // Consistency of what the hot loops index without checks.
  const std::size_t n = s.p_.size();
  const auto fail = [&](const char* what) {
    throw InputError(a.where(), what, "inconsistent", "the checkpoint is corrupt");
  };
  if (s.walls_.size() != std::visit([](const auto& v) { return v.size(); }, s.wall_contacts_))
    fail("walls");
  if (s.ext_force_.size() != n || s.ext_torque_.size() != n || s.x_at_build_.size() != n)
    fail("per-particle arrays");
  std::visit(
      [&](const auto& c) {
        if (c.state.size() != c.pairs.size() || c.slot.size() != c.pairs.size() ||
            (c.pairs.offsets.size() != n + 1 && !c.pairs.offsets.empty()))
          fail("contacts");
        for (std::size_t k = 0; k < c.pairs.size(); ++k)
          if (c.pairs.first[k] >= n || c.pairs.second[k] >= n) fail("contact pairs");
      },
      s.contact_);
  const std::size_t pairs = s.neighbour_pairs();
  std::apply(
      [&](const auto&... set) {
        (
            [&](const auto& b) {
              if (b.tag.size() != b.pairs.size() || b.state.size() != b.pairs.size() ||
                  b.intact.size() != b.pairs.size() || b.bond_of_pair.size() != pairs)
                fail("bonds");
              for (std::size_t k = 0; k < b.pairs.size(); ++k)
                if (b.pairs.first[k] >= n || b.pairs.second[k] >= n) fail("bond pairs");
              for (std::uint32_t k : b.bond_of_pair)
                if (k != b.kNoBond && k >= b.pairs.size()) fail("bond index");
            }(set),
            ...);
      },
      s.bonds_);
  return s;
}

}  // namespace breccia
