#include "methods.hpp"

#include <algorithm>
#include <array>

namespace sesi::program {

namespace {
template <class... Method>
constexpr auto catalogue_of(MethodList<Method...>) {
  return std::array<MethodInfo, sizeof...(Method)>{MethodInfo{Method::name, Method::order, Method::about, Method::stages, Method::output_stages}...};
}
template <class... Method>
constexpr auto names_of(MethodList<Method...>) {
  return std::array<std::string_view, sizeof...(Method)>{Method::name...};
}
/// The chart methods, then the geodesic methods (EmbeddedMethods).
template <class... A, class... B>
constexpr MethodList<A..., B...> joined(MethodList<A...>, MethodList<B...>) {
  return {};
}
constexpr auto catalogue = catalogue_of(joined(Methods{}, EmbeddedMethods{}));
constexpr auto names = names_of(joined(Methods{}, EmbeddedMethods{}));
constexpr auto embedded_names = names_of(EmbeddedMethods{});
}  // namespace

std::span<const MethodInfo> method_catalogue() { return catalogue; }
std::span<const std::string_view> method_names() { return names; }
bool is_method(std::string_view name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}
bool is_embedded_method(std::string_view name) {
  return std::find(embedded_names.begin(), embedded_names.end(), name) != embedded_names.end();
}
const MethodInfo* find_method_info(std::string_view name) {
  for (const MethodInfo& m : catalogue) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

}  // namespace sesi::program
