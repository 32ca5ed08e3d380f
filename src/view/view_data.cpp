// A run directory's data for the viewer (view_page.hpp, read_view_data): the space and frames
// through the observables' reader (src/analysis), the diagnostics from diagnostics.csv and the
// bodies' display size from the scene's Lennard-Jones sigma.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <string_view>

#include <toml++/toml.h>

#include "errors.hpp"
#include "view_page.hpp"

namespace sesi::view {

namespace fs = std::filesystem;
using program::InputError;
using program::Origin;

namespace {

/// diagnostics.csv's columns by name (recorder.cpp: t, energy, energy_error, ..., and a
/// thermostatted run's temperature, kinetic_temperature, ...); empty when missing or unreadable:
/// the page then plots nothing, the frames are what it is for.
std::vector<std::pair<std::string, std::vector<double>>> read_diagnostics(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!in || !std::getline(in, line)) return {};
  std::vector<std::pair<std::string, std::vector<double>>> columns;
  for (std::size_t at = 0; at <= line.size();) {
    const std::size_t comma = std::min(line.find(',', at), line.size());
    columns.push_back({line.substr(at, comma - at), {}});
    at = comma + 1;
  }
  while (std::getline(in, line)) {
    const char* at = line.data();
    const char* end = line.data() + line.size();
    for (std::size_t c = 0; c < columns.size(); ++c) {
      double v = 0.0;
      const auto [next, ec] = std::from_chars(at, end, v);
      if (ec != std::errc() || (next != end && *next != ',') || (next == end && c + 1 < columns.size())) return {};
      columns[c].second.push_back(v);
      at = next + 1;
    }
  }
  return columns;
}

const std::vector<double>* column(const std::vector<std::pair<std::string, std::vector<double>>>& columns,
                                  std::string_view name) {
  for (const auto& [n, values] : columns) {
    if (n == name) return &values;
  }
  return nullptr;
}

/// Half the smallest Lennard-Jones sigma of the run's scene file (summary.json's "source"), when
/// it is still there and is the run's (same space and body count); 0 otherwise.
double lj_body_radius(const analysis::RunInfo& info) {
  if (std::find(info.potentials.begin(), info.potentials.end(), "lennard-jones") == info.potentials.end()) return 0.0;
  std::error_code ec;
  if (info.source.empty() || !fs::is_regular_file(info.source, ec)) return 0.0;
  try {
    const toml::table scene = toml::parse_file(info.source);
    const toml::array* bodies = scene["bodies"].as_array();
    if (!bodies || static_cast<long>(bodies->size()) != info.bodies) return 0.0;
    if (scene["space"]["dim"].value_or(0L) != info.space.dim) return 0.0;
    double sigma = 0.0;
    if (const toml::array* potentials = scene["potential"].as_array()) {
      for (const toml::node& p : *potentials) {
        const toml::table* table = p.as_table();
        if (!table || (*table)["kind"].value_or(std::string_view{}) != "lennard-jones") continue;
        const double s = (*table)["sigma"].value_or(0.0);
        if (s > 0.0 && std::isfinite(s) && (sigma == 0.0 || s < sigma)) sigma = s;
      }
    }
    return sigma / 2.0;
  } catch (const std::exception&) {
    return 0.0;  // a scene file changed or gone since the run: no size in the space's units
  }
}

}  // namespace

ViewData read_view_data(const fs::path& dir, const ReadViewOptions& options) {
  if (options.max_frames < 1) {
    throw InputError(Origin{}, "--max-frames", "expected a whole number >= 1, got " + std::to_string(options.max_frames));
  }
  const analysis::RunInfo info = analysis::read_run_info(dir, true);
  analysis::ReadOptions read;
  read.from = options.from;
  read.to = options.to;
  read.every = options.every;
  const analysis::Frames frames = analysis::read_frames(dir, info, read);

  fs::path name = dir;
  if (name.filename().empty()) name = name.parent_path();
  name = fs::absolute(name).lexically_normal();
  if (name.filename().empty()) name = name.parent_path();
  ViewData data = from_frames(frames, name.filename().string(), options.max_frames);
  data.complete = info.complete;
  data.status = info.status;
  data.trajectory = info.trajectory;
  data.body_radius = lj_body_radius(info);

  // The diagnostics over the frames' times.
  const double t0 = frames.t.front(), t1 = frames.t.back();
  const auto within = [&](double t) { return t >= std::min(t0, t1) && t <= std::max(t0, t1); };
  const auto columns = read_diagnostics(dir / "diagnostics.csv");
  const std::vector<double>* t = column(columns, "t");
  if (t && !t->empty()) {
    const std::vector<double>* energy = column(columns, "energy");
    const std::vector<double>* error = column(columns, "energy_error");
    if (error) {
      // energy_error is E - E(t0) (recorder.cpp); relative to |E(t0)| where that is not 0.
      const double e0 = energy ? std::abs(energy->front()) : 0.0;
      Series s{e0 > 0.0 ? "relative energy error" : "energy error", {}, {}};
      for (std::size_t k = 0; k < t->size(); ++k) {
        if (!within((*t)[k])) continue;
        s.t.push_back((*t)[k]);
        s.y.push_back(e0 > 0.0 ? (*error)[k] / e0 : (*error)[k]);
      }
      if (!s.t.empty()) data.diagnostics.push_back(thin_series(std::move(s)));
    }
  }
  const std::vector<double>* kinetic = t ? column(columns, "kinetic_temperature") : nullptr;
  if (kinetic) {
    Series s{"kinetic temperature", {}, {}};
    for (std::size_t k = 0; k < t->size(); ++k) {
      if (!within((*t)[k])) continue;
      s.t.push_back((*t)[k]);
      s.y.push_back((*kinetic)[k]);
    }
    if (!s.t.empty()) data.diagnostics.push_back(thin_series(std::move(s)));
  } else if (Series s = kinetic_temperature(frames); !s.t.empty()) {
    data.diagnostics.push_back(thin_series(std::move(s)));  // from the frames read (NVE runs)
  }
  return data;
}

}  // namespace sesi::view
