#pragma once
// The one list of lab tests. Adding a test is one new file (a type with `name`, `summary`, a
// `Params` struct with its `fields()` table, `check`, `create` and `restore`) and one entry here:
// the experiment file's [test] table, its validation, the generated docs, checkpoints and the
// registry test (tests/test_protocols.cpp) follow from the list.
#include <memory>
#include <string_view>
#include <utility>

#include "breccia/law/registry.hpp"
#include "breccia/protocol/abrasion.hpp"
#include "breccia/protocol/brazilian.hpp"
#include "breccia/protocol/cantilever.hpp"
#include "breccia/protocol/compression.hpp"
#include "breccia/protocol/direct_tension.hpp"
#include "breccia/protocol/impact.hpp"
#include "breccia/protocol/vibration.hpp"

namespace breccia {

using LabTests = TypeList<UcsTest, TriaxialTest, BiaxialTest, BrazilianTest, DirectTensionTest,
                          ImpactTest, CantileverTest, VibrationTest, AbrasionTest>;

// The chosen test's parameters (the experiment's [test] table).
using TestParams = ParamsVariant<LabTests>;

// Calls f.template operator()<Test>() for the registered test called `kind`; false if none is.
template <class F>
bool with_lab_test(std::string_view kind, F&& f) {
  return with_named<LabTests>(kind, std::forward<F>(f));
}

// Calls f.template operator()<Test>() for every registered test, in order.
template <class F>
void for_each_lab_test(F&& f) {
  for_each_type<LabTests>(std::forward<F>(f));
}

// Calls f.template operator()<Test>(params) for the test whose parameters `params` holds.
template <class F>
decltype(auto) visit_lab_test(const TestParams& params, F&& f) {
  return visit_params<LabTests>(params, std::forward<F>(f));
}

}  // namespace breccia
