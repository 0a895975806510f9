// Checkpoints of the engine: every member that carries state from one step to the next, in a
// fixed order with section labels. One field list (Simulation::transfer) serves writing and
// reading, so the two cannot drift apart. Restoring needs no set-up call: the neighbour lists,
// bond index maps and per-block scratch come back as they were, so the next step is the one the
// uninterrupted run would have taken.
#include <stdexcept>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>

#include "breccia/core/archive.hpp"
#include "breccia/core/format.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

namespace {

template <class Archive>
void transfer_pairs(Archive& a, PairList& l) {
  a.vector(l.first);
  a.vector(l.second);
  a.vector(l.offsets);
  a.vector(l.in_offsets);
  a.vector(l.in_slot);
  // Bond lists carry no gather index (empty offsets), and no list a transposed one.
  if (l.second.size() != l.first.size() || !l.in_slot.empty() || !l.in_offsets.empty())
    throw InputError(a.where(), "pair list", std::to_string(l.first.size()),
                     "array lengths differ: the checkpoint is corrupt");
}

// The bonds (or joints) of one law: parameters, pairs, tags, states and the index into the
// neighbour pairs. Joints are never compacted, so their count of broken entries stays 0.
template <class Archive, class Law>
void transfer_set(Archive& a, BondSet<Law>& b) {
  static_assert(std::is_trivially_copyable_v<typename Law::Params> &&
                    std::is_trivially_copyable_v<typename Law::State>,
                "a law's Params and State are plain data: checkpoints copy them whole");
  a.value(b.params);
  transfer_pairs(a, b.pairs);
  a.vector(b.tag);
  a.vector(b.state);
  a.vector(b.intact);
  a.vector(b.bond_of_pair);
  std::uint64_t broken = b.broken_since_compaction;
  a.value(broken);
  b.broken_since_compaction = broken;
}

// Walls hold a name (not plain data): transferred field by field. The size check fails to
// compile when a field is added, as a reminder to add it here.
static_assert(sizeof(Wall) == 352, "Wall changed: update the checkpoint (engine/checkpoint.cpp)");

template <class Archive>
void transfer_wall(Archive& a, Wall& w) {
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
  a.value(w.mass);
  a.value(w.velocity);
  a.value(w.radial_speed);
  a.value(w.force);
  a.value(w.contacts);
  a.value(w.contact_stiffness);
  a.value(w.work);
  a.value(w.radial_force);
  a.value(w.force_prev);
  a.value(w.radial_force_prev);
  a.value(w.advanced_velocity);
  a.value(w.advanced_radial_speed);
  a.value(w.moved);
}

// The bond or joint sets of a registry, each under its law's name: the sets a checkpoint holds
// are found by name when it is read, so a build with more laws reads it (the new laws' sets stay
// empty), and adding a law changes nothing here.
template <class Archive, class... Laws>
void transfer_sets(Archive& a, std::tuple<BondSet<Laws>...>& sets) {
  std::uint64_t count = sizeof...(Laws);
  a.value(count);
  if constexpr (!Archive::reading) {
    std::apply(
        [&](auto&... set) {
          auto one = [&]<class Law>(BondSet<Law>& b) {
            std::string name(Law::name);
            a.string(name);
            transfer_set(a, b);
          };
          (one(set), ...);
        },
        sets);
  } else {
    for (std::uint64_t k = 0; k < count; ++k) {
      const std::string name = a.string();
      bool found = false;
      std::apply(
          [&](auto&... set) {
            auto one = [&]<class Law>(BondSet<Law>& b) {
              if (found || name != Law::name) return;
              found = true;
              transfer_set(a, b);
            };
            (one(set), ...);
          },
          sets);
      if (!found)
        throw InputError(a.where(), "bond law", name, "not a law of this build of Breccia");
    }
  }
}

// Emplaces alternative `index` of a variant (default-constructed).
// Field by field: the struct's padding after its last member holds whatever the memory it was
// made in held, and a checkpoint must be the same bytes wherever it is written.
template <class Archive>
void transfer_engine_config(Archive& a, EngineConfig& c) {
  a.value(c.time_step);
  a.value(c.safety_factor);
  a.value(c.hertz_rayleigh_factor);
  a.value(c.local_damping);
  a.value(c.dynamic_damping_alpha);
  a.value(c.dynamic_damping_radius);
  a.value(c.dynamic_damping_time);
  a.value(c.bond_normal_damping_ratio);
  a.value(c.bond_shear_damping_ratio);
  a.value(c.gravity);
  a.value(c.skin);
  a.value(c.seed);
  a.value(c.energy_interval);
  a.value(c.keep_pair_forces);
  static_assert(sizeof(EngineConfig) == 128, "EngineConfig changed: save its new fields above");
}

template <class Variant, std::size_t... I>
void emplace_index(Variant& v, std::size_t index, std::index_sequence<I...>) {
  ((index == I ? (v.template emplace<I>(), 0) : 0), ...);
}

}  // namespace

// The contact law by name, its pairs and histories, and the walls' contacts.
template <class Archive>
void Simulation::transfer_contacts(Archive& a) {
  a.label("contacts");
  // By name, like the bond sets: the registry's order does not matter.
  std::string contact_law;
  if constexpr (!Archive::reading)
    std::visit([&]<class CL>(const ContactSet<CL>&) { contact_law = contact_layout_name<CL>(); },
               contact_);
  a.string(contact_law);
  if constexpr (Archive::reading) {
    constexpr std::size_t kLaws = std::variant_size_v<ContactModel>;
    std::size_t law = kLaws, index = 0;
    for_each_type<EngineContactLaws>([&]<class CL>() {
      if (contact_layout_name<CL>() == contact_law) law = index;
      ++index;
    });
    if (law >= kLaws)
      throw InputError(a.where(), "contact law", contact_law,
                       "not a contact law of this build of Breccia");
    emplace_index(contact_, law, std::make_index_sequence<kLaws>{});
    emplace_index(wall_contacts_, law, std::make_index_sequence<kLaws>{});
  }
  std::visit(
      [&]<class CL>(ContactSet<CL>& c) {
        static_assert(std::is_trivially_copyable_v<typename CL::Params>);
        a.value(c.params);
        a.value(c.wall_params);
        transfer_pairs(a, c.pairs);
        a.vector(c.history);
        // Each block's histories as they lie: a new contact appends where the uninterrupted
        // run would have appended it.
        a.sized(c.stores, 8);
        for (auto& store : c.stores) a.vector(store);
        a.vector(c.packed);
        a.value(keep_pair_forces_);
        a.vector(c.kept_force);  // empty where the states give the forces back
      },
      contact_);
  std::visit(
      [&]<class CL>(std::vector<WallContacts<CL>>& v) {
        a.sized(v, 48);
        for (WallContacts<CL>& w : v) {
          a.vector(w.particle);
          a.vector(w.state);
          a.vector(w.force);
          a.vector(w.torque);
          a.vector(w.normal_force);
          a.vector(w.stiffness);
        }
      },
      wall_contacts_);
}

// The crack catalogue (engine/crack_catalogue.cpp) and the run's warnings.
template <class Archive>
void Simulation::transfer_cracks(Archive& a) {
  a.label("cracks");
  cracks_.transfer(a);
  a.vector(damped_less_until_);
  a.sized(warnings_, 8);
  for (std::string& w : warnings_) a.string(w);
}

template <class Archive>
void Simulation::transfer(Archive& a) {
  // Fails to compile when a member of the engine is added: add it below if it carries state from
  // one step to the next, then update the size. The law-dependent members (the contact model and
  // the bond and joint sets, whose sizes grow with the registry) are left out of the count: they
  // are saved by law, so a new law needs nothing here.
  static_assert(sizeof(Simulation) - sizeof(ContactModel) - sizeof(wall_contacts_) -
                        sizeof(BondSets) - sizeof(JointSets) ==
                    1968,
                "Simulation changed: update engine/checkpoint.cpp");
  a.label("simulation");
  if constexpr (Archive::reading)
    p_.load(a);
  else
    p_.save(a);
  transfer_engine_config(a, cfg_);

  transfer_contacts(a);

  a.label("bonds");
  transfer_sets(a, bonds_);
  transfer_sets(a, joints_);
  a.vector(joint_planes_);
  a.vector(pending_joints_);
  a.value(joint_law_);

  a.label("walls");
  a.sized(walls_, 8);
  for (Wall& w : walls_) transfer_wall(a, w);

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
  a.vector(user_force_);
  a.vector(drive_force_prev_);
  a.value(max_disp2_);
  a.value(radius_growth_);
  // The kernels' instruction set goes on with the run, so that the continuation is bitwise the
  // uninterrupted run (restore() falls back where the CPU lacks it).
  a.value(isa_);

  transfer_cracks(a);

  a.label("ledger");
  a.value(ledger_);
  bool has_baseline = baseline_.has_value();
  a.value(has_baseline);
  if (has_baseline) {
    if constexpr (Archive::reading) baseline_.emplace();
    a.value(*baseline_);
  }
  a.value(w_walls_);
  a.value(w_drive_);
  a.value(w_gravity_);
  a.value(w_external_);
  a.value(d_local_);
  a.value(d_local_boundary_);
  a.value(w_external_boundary_);
  a.value(d_pairs_);
  a.value(d_joint_slip_);
  a.value(released_);
  a.label("end of simulation");
}

void Simulation::save_state(ArchiveWriter& a) const {
  if (retired_)
    throw std::logic_error("Simulation::save_state: the simulation's interactions are retired");
  if (split_)
    throw std::logic_error(
        "Simulation::save_state: a sample split over ranks is saved by gathering it first (not yet "
        "supported)");
  const_cast<Simulation*>(this)->transfer(a);  // the writer only reads the fields
}

Simulation Simulation::restore(ArchiveReader& a) {
  Simulation s{RestoreTag{}};
  s.transfer(a);
  if (!instruction_set_supported(s.isa_)) {
    const InstructionSet saved = s.isa_;
    s.isa_ = best_instruction_set();
    s.warnings_.push_back(fmt::format(
        "the run computed in the instruction set '{}', which this CPU lacks: it goes on in '{}', "
        "so it is no longer the same to the bit as the uninterrupted run (docs/physics.md §1.7)",
        instruction_set_name(saved), instruction_set_name(s.isa_)));
  }

  // Consistency of what the hot loops index without checks.
  const std::size_t n = s.p_.size();
  const auto fail = [&](const char* what) {
    throw InputError(a.where(), what, "inconsistent", "the checkpoint is corrupt");
  };
  if (s.walls_.size() != std::visit([](const auto& v) { return v.size(); }, s.wall_contacts_))
    fail("walls");
  if (s.x_at_build_.size() != n ||
      (!s.damped_less_until_.empty() && s.damped_less_until_.size() != n) ||
      (!s.drive_force_prev_.empty() && s.drive_force_prev_.size() != 2 * n))
    fail("per-particle arrays");
  std::visit(
      [&](const auto& c) {
        if (c.history.size() != c.pairs.size() ||
            c.kept_force.size() != (s.keep_pair_forces_ ? c.pairs.size() : 0) ||
            (c.pairs.offsets.size() != n + 1 && !c.pairs.offsets.empty()) ||
            ((c.stores.size() != (n + kParticleBlock - 1) / kParticleBlock ||
              c.packed.size() != c.stores.size()) &&
             !c.pairs.offsets.empty()))
          fail("contacts");
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          if (c.pairs.first[k] >= n || c.pairs.second[k] >= n) fail("contact pairs");
          if (c.history[k] != kNoHistory &&
              c.history[k] >= c.stores[c.pairs.first[k] / kParticleBlock].size())
            fail("contact history");
        }
      },
      s.contact_);
  const std::size_t pairs = s.neighbour_pairs();
  auto check_set = [&](const auto& b) {
    // A law the checkpoint did not know has an empty set and no index yet (the next rebuild
    // makes it; the pair pass reads no index of an empty set).
    const bool unindexed = b.pairs.size() == 0 && b.bond_of_pair.empty();
    if (b.tag.size() != b.pairs.size() || b.state.size() != b.pairs.size() ||
        b.intact.size() != b.pairs.size() || (b.bond_of_pair.size() != pairs && !unindexed))
      fail("bonds");
    for (std::size_t k = 0; k < b.pairs.size(); ++k)
      if (b.pairs.first[k] >= n || b.pairs.second[k] >= n) fail("bond pairs");
    for (std::uint32_t k : b.bond_of_pair)
      if (k != b.kNoBond && k >= b.pairs.size()) fail("bond index");
  };
  std::apply([&](const auto&... set) { (check_set(set), ...); }, s.bonds_);
  std::apply([&](const auto&... set) { (check_set(set), ...); }, s.joints_);
  if (s.joint_law_ >= JointLaws::size) fail("joint law");
  // The pair pass's cross index follows from the list (not saved).
  std::visit(
      [&](auto& c) {
        if (!c.pairs.offsets.empty()) c.pairs.build_cross_index(n);
      },
      s.contact_);
  s.reserve_crack_catalogue();
  return s;
}

}  // namespace breccia
