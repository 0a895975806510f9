#pragma once
// Compile-time lists of registered types (laws, lab tests) and the few operations every registry
// needs: look a type up by its `name`, visit all of them, hold the chosen one's `Params` in a
// variant and find the type back from that variant.
#include <cstddef>
#include <string_view>
#include <type_traits>
#include <variant>

namespace breccia {

template <class... Ts>
struct TypeList {
  static constexpr std::size_t size = sizeof...(Ts);
};

template <class List>
struct ParamsVariantOf;
template <class... Ts>
struct ParamsVariantOf<TypeList<Ts...>> {
  using type = std::variant<typename Ts::Params...>;
};
// One alternative per registered type: the parameters of the chosen one.
template <class List>
using ParamsVariant = typename ParamsVariantOf<List>::type;

// Calls f.template operator()<T>() for the type of `List` whose name is `name`; false if none is.
template <class List, class F>
bool with_named(std::string_view name, F&& f) {
  return [&]<class... Ts>(TypeList<Ts...>) {
    return ((Ts::name == name ? (f.template operator()<Ts>(), true) : false) || ...);
  }(List{});
}

// Calls f.template operator()<T>() for every type of `List`, in order.
template <class List, class F>
void for_each_type(F&& f) {
  [&]<class... Ts>(TypeList<Ts...>) { (f.template operator()<Ts>(), ...); }(List{});
}

template <class P, class List>
struct OwnerOfParams {
  using type = void;
};
template <class P, class T, class... Rest>
struct OwnerOfParams<P, TypeList<T, Rest...>> {
  using type = std::conditional_t<std::is_same_v<typename T::Params, P>, T,
                                  typename OwnerOfParams<P, TypeList<Rest...>>::type>;
};

// Calls f.template operator()<T>(params) for the type of `List` whose parameters `params` holds.
template <class List, class Variant, class F>
decltype(auto) visit_params(Variant&& params, F&& f) {
  return std::visit(
      [&](auto&& p) -> decltype(auto) {
        using P = std::remove_cvref_t<decltype(p)>;
        return f.template operator()<typename OwnerOfParams<P, List>::type>(p);
      },
      std::forward<Variant>(params));
}

// The name of the type whose parameters `params` holds.
template <class List, class Variant>
std::string_view name_of_params(const Variant& params) {
  return visit_params<List>(params, []<class T>(const auto&) { return T::name; });
}

}  // namespace breccia
