#pragma once
/// @file method_list.hpp
/// The machine-readable method list (`sesi run --list-methods [--json]`, `sesi.methods()`),
/// read off the one method registry (methods.hpp: Methods and EmbeddedMethods), so that tools and
/// tests never parse --help.

#include <string>
#include <string_view>
#include <vector>

namespace sesi::program {

/// One method of `sesi run --method`, as listed.
struct MethodEntry {
  std::string_view name;
  int order;
  /// "chart" (a composition on the chart), "processed" (a processed chart method), "geodesic"
  /// (in the embedding, processed or not) or "reference" (a wrapped reference stepper).
  std::string_view family;
  bool processed;     ///< the stepped state is a kernel's variables, post-processed where read
  int stages;         ///< force evaluations per step
  int output_stages;  ///< force evaluations per state read between steps (0 but for processed)
  std::vector<std::string_view> spaces;  ///< the [space] kinds it runs on
  std::string_view about;
};

/// Every registered method, in registration order (the chart methods, then the geodesic ones).
std::vector<MethodEntry> method_entries();

/// The list as `sesi run --list-methods` prints it: one name per line, or (json) one JSON
/// object {"methods": [{"name", "order", "family", "processed", "stages", "output_stages",
/// "spaces", "about"}, ...]}.
std::string method_list_text(bool json);

}  // namespace sesi::program
