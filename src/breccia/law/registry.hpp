#pragma once
// The one list of laws. Adding a law is one new header and one entry here; the conformance tests
// (tests/test_law_conformance.cpp) run over every entry automatically.
#include <cstddef>

#include "breccia/law/hertz_mindlin.hpp"
#include "breccia/law/linear_contact.hpp"
#include "breccia/law/parallel_bond.hpp"

namespace breccia {

template <class... Ts>
struct TypeList {
  static constexpr std::size_t size = sizeof...(Ts);
};

using ContactLaws = TypeList<LinearContact, HertzMindlin>;
using BondLaws = TypeList<ParallelBond>;

}  // namespace breccia
