#include "methods.hpp"

#include <algorithm>
#include <array>
#include <cstdio>

#include "method_list.hpp"

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

// The family of a descriptor, from its kind: any other descriptor in Methods wraps a reference
// stepper (OdeintStyleStepper).
template <class M>
constexpr std::string_view family_of = "reference";
template <class Table, auto About>
constexpr std::string_view family_of<CompositionMethod<Table, About>> = "chart";
template <class Table, auto About>
constexpr std::string_view family_of<ProcessedMethod<Table, About>> = "processed";
template <class Table, auto Name, auto About>
constexpr std::string_view family_of<GeodesicMethod<Table, Name, About>> = "geodesic";
template <class Table, auto Name, auto About>
constexpr std::string_view family_of<GeodesicProcessedMethod<Table, Name, About>> = "geodesic";

template <class M>
constexpr bool processed_of = family_of<M> == "processed";
template <class Table, auto Name, auto About>
constexpr bool processed_of<GeodesicProcessedMethod<Table, Name, About>> = true;

// The geodesic methods need an embedding with curvature (make_integrator refuses them on E^n);
// the chart steppers are built for every space.
template <class... Method>
void append_entries(MethodList<Method...>, std::vector<MethodEntry>& out, std::vector<std::string_view> spaces) {
  (out.push_back(MethodEntry{Method::name, Method::order, family_of<Method>, processed_of<Method>, Method::stages,
                             Method::output_stages, spaces, Method::about}),
   ...);
}

void append_json_string(std::string& out, std::string_view text) {
  out += '"';
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(c));
      out += escaped;
    } else {
      out += c;
    }
  }
  out += '"';
}
}  // namespace

std::vector<MethodEntry> method_entries() {
  std::vector<MethodEntry> out;
  append_entries(Methods{}, out, {"sphere", "hyperbolic", "euclidean"});
  append_entries(EmbeddedMethods{}, out, {"sphere", "hyperbolic"});
  return out;
}

std::string method_list_text(bool json) {
  std::string out;
  if (!json) {
    for (const MethodEntry& m : method_entries()) (out += m.name) += '\n';
    return out;
  }
  out = "{\"methods\": [";
  bool first = true;
  for (const MethodEntry& m : method_entries()) {
    out += first ? "\n  {\"name\": " : ",\n  {\"name\": ";
    first = false;
    append_json_string(out, m.name);
    out += ", \"order\": " + std::to_string(m.order) + ", \"family\": ";
    append_json_string(out, m.family);
    out += std::string(", \"processed\": ") + (m.processed ? "true" : "false");
    out += ", \"stages\": " + std::to_string(m.stages) + ", \"output_stages\": " + std::to_string(m.output_stages);
    out += ", \"spaces\": [";
    for (std::size_t i = 0; i < m.spaces.size(); ++i) {
      if (i > 0) out += ", ";
      append_json_string(out, m.spaces[i]);
    }
    out += "], \"about\": ";
    append_json_string(out, m.about);
    out += '}';
  }
  out += "\n]}\n";
  return out;
}

std::span<const MethodInfo> method_catalogue() { return catalogue; }
std::span<const std::string_view> method_names() { return names; }
bool is_method(std::string_view name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}
bool is_embedded_method(std::string_view name) {
  return std::find(embedded_names.begin(), embedded_names.end(), name) != embedded_names.end();
}
namespace {
template <class... Method>
constexpr auto composition_names_of(MethodList<Method...>) {
  constexpr std::size_t count = ((family_of<Method> == "chart" ? 1 : 0) + ... + 0);
  std::array<std::string_view, count> out{};
  std::size_t k = 0;
  ((family_of<Method> == "chart" ? static_cast<void>(out[k++] = Method::name) : static_cast<void>(0)), ...);
  return out;
}
constexpr auto composition_names = composition_names_of(Methods{});
}  // namespace
std::span<const std::string_view> composition_method_names() { return composition_names; }
bool is_composition_method(std::string_view name) {
  return std::find(composition_names.begin(), composition_names.end(), name) != composition_names.end();
}
const MethodInfo* find_method_info(std::string_view name) {
  for (const MethodInfo& m : catalogue) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

}  // namespace sesi::program
