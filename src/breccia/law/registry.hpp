#pragma once
// The one list of laws. Adding a law is one new header and one entry here: the experiment file's
// [contact] and [bond] tables, their validation, the generated docs, the engine's law sets and the
// conformance tests (tests/test_law_conformance.cpp) all follow from the lists.
#include <concepts>
#include <string>
#include <string_view>

#include "breccia/core/type_list.hpp"
#include "breccia/law/brittle_beam.hpp"
#include "breccia/law/flat_joint.hpp"
#include "breccia/law/hertz_mindlin.hpp"
#include "breccia/law/linear_contact.hpp"
#include "breccia/law/parallel_bond.hpp"
#include "breccia/law/quaternion_bond.hpp"
#include "breccia/law/ricebal_bond.hpp"
#include "breccia/law/smooth_joint.hpp"

namespace breccia {

using ContactLaws = TypeList<LinearContact, HertzMindlin>;
// The contact laws as the engine holds them: each in its two state layouts, without and with the
// rolling and twisting moments (law/rolling_resistance.hpp; make_contact_model picks one).
template <class List>
struct WithRollingLayouts;
template <class... Laws>
struct WithRollingLayouts<TypeList<Laws...>> {
  using type = TypeList<typename Laws::template with_rolling<false>...,
                        typename Laws::template with_rolling<true>...>;
};
using EngineContactLaws = WithRollingLayouts<ContactLaws>::type;
// The name a contact state layout is saved under in a checkpoint.
template <class CL>
std::string contact_layout_name() {
  return std::string(CL::name) + (CL::rolling ? "+rolling" : "");
}
using BondLaws = TypeList<ParallelBond, BrittleBeam, QuaternionBond, RicebalBond, FlatJoint>;
// Laws of the pairs that a joint plane cuts (docs/physics.md §5): they replace the pair's bond and
// contact law, and the experiment's [joint] table places them.
using JointLaws = TypeList<SmoothJoint>;

// A bond law whose failure envelope reads the interface totals, bond plus contact (docs/physics.md
// §4.4), splits its step into loads() and judge(); the engine judges it once the pair's contact
// force of the step is known.
template <class Law>
constexpr bool judged_on_interface = requires(typename Law::State& s, const PairGeometry& g) {
  Law::loads(s, g, 0.0);
};
// A bond law whose kernel books losses (the flat joint's sliding elements) takes the pair's
// PairDissipation after the step's interval.
template <class Law>
constexpr bool law_dissipates = requires(const typename Law::Params& p, typename Law::State& s,
                                         const PairGeometry& g, const BodyFrames& fr,
                                         PairDissipation& d, BondFailure& f) {
  Law::compute(p, s, g, fr, 0.0, d, f);
};
// A bond law whose elements break one at a time, each a crack, while the bond stays in place
// until it is released (BondOutcome; the flat joint).
template <class Law>
constexpr bool law_breaks_by_element = requires {
  Law::breaks_by_element;
};
// A law defined for disks and planar spheres only (2D).
template <class Law>
consteval bool is_planar_only() {
  if constexpr (requires { Law::planar_only; })
    return Law::planar_only;
  else
    return false;
}
template <class Law>
constexpr bool planar_only_law = is_planar_only<Law>();
// Whether a law reads the pair's motion (PairGeometry::vc, w1, w2, m1, m2). A law that reads only
// the shape and the orientations says `needs_motion = false`, and the pair pass then skips
// loading the velocities of its pairs; without the declaration a law gets the motion.
template <class Law>
consteval bool reads_motion() {
  if constexpr (requires { Law::needs_motion; })
    return Law::needs_motion;
  else
    return true;
}
template <class Law>
constexpr bool law_needs_motion = reads_motion<Law>();
// Whether a contact law with these parameters reads the pair's motion: a law that declares
// `needs_motion_with(params)` may spare the pair pass the velocities for some parameters (a
// frictionless contact without dashpots); without the declaration a contact reads it.
template <class CL>
bool contact_needs_motion(const typename CL::Params& p) noexcept {
  if constexpr (requires { CL::needs_motion_with(p); })
    return CL::needs_motion_with(p);
  else
    return true;
}

// A law whose state holds the pair's force of its last step: state_force(state) gives back, to
// the bit, the force on the pair's second grain that compute() returned (the same expression on
// the same numbers), whenever state_holds_force(params) is true (a contact without dashpots, whose
// damping force no state keeps). The engine then keeps no array of pair forces for the observers
// (Simulation::pair_force).
template <class Law>
constexpr bool has_state_force = requires(const typename Law::Params& p,
                                          const typename Law::State& s) {
  { Law::state_force(s) } -> std::same_as<Vec3>;
  { Law::state_holds_force(p) } -> std::same_as<bool>;
};

// The chosen laws' parameters (the experiment's [contact] and [bond] tables).
using ContactParams = ParamsVariant<ContactLaws>;
using BondParams = ParamsVariant<BondLaws>;
using JointParams = ParamsVariant<JointLaws>;

}  // namespace breccia
