#pragma once
// The one list of lab tests. Adding a test is one new file (a type with `name`, `summary`, a
// `Params` struct with its `fields()` table, `check`, `create` and `restore`) and one entry here:
// the experiment file's [test] table, its validation, the generated docs, checkpoints and the
// registry test (tests/test_protocols.cpp) follow from the list.
#include <memory>
#include <string_view>
#include <type_traits>
#include <variant>

#include "breccia/law/registry.hpp"
#include "breccia/protocol/brazilian_test.hpp"
#include "breccia/protocol/compression_test.hpp"

namespace breccia {

using LabTests = TypeList<UcsTest, TriaxialTest, BiaxialTest, BrazilianTest>;

template <class List>
struct TestParamsOf;
template <class... Tests>
struct TestParamsOf<TypeList<Tests...>> {
  using type = std::variant<typename Tests::Params...>;
};
// The chosen test's parameters (the experiment's [test] table).
using TestParams = TestParamsOf<LabTests>::type;

// Calls f.template operator()<Test>() for the registered test called `kind`; false if none is.
template <class F>
bool with_lab_test(std::string_view kind, F&& f) {
  return [&]<class... Tests>(TypeList<Tests...>) {
    return ((Tests::name == kind ? (f.template operator()<Tests>(), true) : false) || ...);
  }(LabTests{});
}

// Calls f.template operator()<Test>() for every registered test, in order.
template <class F>
void for_each_lab_test(F&& f) {
  [&]<class... Tests>(TypeList<Tests...>) { (f.template operator()<Tests>(), ...); }(LabTests{});
}

template <class P, class List>
struct TestFor {
  using type = void;
};
template <class P, class T, class... Rest>
struct TestFor<P, TypeList<T, Rest...>> {
  using type = std::conditional_t<std::is_same_v<typename T::Params, P>, T,
                                  typename TestFor<P, TypeList<Rest...>>::type>;
};

// Calls f.template operator()<Test>(params) for the test whose parameters `params` holds.
template <class F>
decltype(auto) visit_lab_test(const TestParams& params, F&& f) {
  return std::visit(
      [&](const auto& p) -> decltype(auto) {
        return f.template operator()<typename TestFor<std::decay_t<decltype(p)>, LabTests>::type>(
            p);
      },
      params);
}

}  // namespace breccia
