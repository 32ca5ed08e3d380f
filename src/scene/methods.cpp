#include "methods.hpp"

#include <algorithm>
#include <array>

namespace sesi::program {

namespace {
template <class... Method>
constexpr auto catalogue_of(MethodList<Method...>) {
  return std::array<MethodInfo, sizeof...(Method)>{MethodInfo{Method::name, Method::order, Method::about, Method::stages}...};
}
template <class... Method>
constexpr auto names_of(MethodList<Method...>) {
  return std::array<std::string_view, sizeof...(Method)>{Method::name...};
}
constexpr auto catalogue = catalogue_of(Methods{});
constexpr auto names = names_of(Methods{});
}  // namespace

std::span<const MethodInfo> method_catalogue() { return catalogue; }
std::span<const std::string_view> method_names() { return names; }
bool is_method(std::string_view name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}
const MethodInfo* find_method_info(std::string_view name) {
  for (const MethodInfo& m : catalogue) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

}  // namespace sesi::program
