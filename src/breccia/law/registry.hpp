#pragma once
// The one list of laws. Adding a law is one new header and one entry here: the experiment file's
// [contact] and [bond] tables, their validation, the generated docs, the engine's law sets and the
// conformance tests (tests/test_law_conformance.cpp) all follow from the lists.
#include <string_view>

#include "breccia/core/type_list.hpp"
#include "breccia/law/brittle_beam.hpp"
#include "breccia/law/hertz_mindlin.hpp"
#include "breccia/law/linear_contact.hpp"
#include "breccia/law/parallel_bond.hpp"
#include "breccia/law/quaternion_bond.hpp"
#include "breccia/law/smooth_joint.hpp"

namespace breccia {

using ContactLaws = TypeList<LinearContact, HertzMindlin>;
using BondLaws = TypeList<ParallelBond, BrittleBeam, QuaternionBond>;
// Laws of the pairs that a joint plane cuts (physics.md §5): they replace the pair's bond and
// contact law, and the experiment's [joint] table places them.
using JointLaws = TypeList<SmoothJoint>;

// The chosen laws' parameters (the experiment's [contact] and [bond] tables).
using ContactParams = ParamsVariant<ContactLaws>;
using BondParams = ParamsVariant<BondLaws>;
using JointParams = ParamsVariant<JointLaws>;

}  // namespace breccia
