#include "sweep_file.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <string_view>

#include <toml++/toml.h>

#include "errors.hpp"
#include "scene_limits.hpp"
#include "scene_reader.hpp"
#include "suggest.hpp"

namespace sesi::program {

namespace fs = std::filesystem;

std::string run_name(long index, long total) {
  std::string name = std::to_string(index);
  const std::size_t width = std::max<std::size_t>(4, std::to_string(std::max(total - 1, 0L)).size());
  if (name.size() < width) name.insert(0, width - name.size(), '0');
  return name;
}

std::vector<double> perturbation_draws(std::uint64_t seed, long copy, int count) {
  std::mt19937_64 engine(seed + static_cast<std::uint64_t>(copy));
  std::vector<double> out(static_cast<std::size_t>(count));
  for (double& u : out) {
    const double unit = static_cast<double>(engine() >> 11) * 0x1.0p-53;  // exact, in [0, 1)
    u = 2.0 * unit - 1.0;                                                  // exact, in [-1, 1)
  }
  return out;
}

namespace {

constexpr std::array<std::string_view, 3> top_keys = {"scene", "trajectory", "vary"};
constexpr std::array<std::string_view, 6> vary_keys = {"key", "values", "range", "perturb", "count", "seed"};

/// One [[vary]] table: a list of values for a key, or `count` perturbations of its value.
struct VaryTable {
  std::string key;
  std::vector<std::string> parts;  ///< key split at the dots
  Origin origin;                   ///< the table's line in the sweep file
  toml::array values;
  bool perturb = false;
  double size = 0.0;  ///< perturb: the largest change of a component
  long count = 0;
  std::uint64_t seed = 0;
  long length() const { return perturb ? count : static_cast<long>(values.size()); }
};

Origin origin_of(const fs::path& file, const toml::source_region& where) {
  return Origin{file.string(), static_cast<int>(where.begin.line), static_cast<int>(where.begin.column)};
}

std::string read_text(const fs::path& path, const Origin& origin, std::string_view key, std::string_view what) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(origin, key, std::string(what) + " " + path.string() + " is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(origin, key, "cannot open " + std::string(what) + " " + path.string());
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw InputError(origin, key, "cannot read " + std::string(what) + " " + path.string());
  return text;
}

toml::table parse_toml(const std::string& text, const std::string& path) {
  check_scene_limits(text, path);
  try {
    return toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    const auto& where = e.source().begin;
    throw InputError(Origin{path, static_cast<int>(where.line), static_cast<int>(where.column)}, "",
                     "TOML syntax error: " + std::string(e.description()));
  }
}

std::optional<long> as_index(std::string_view part) {
  long index = 0;
  const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), index);
  if (error != std::errc() || end != part.data() + part.size() || index < 0) return std::nullopt;
  return index;
}

/// The node at the path of the key's first `count` parts (all of them by default), or nullptr
/// where the last of them is missing from its table. A missing table on the way is made when
/// `create`; otherwise, and for a bad array index, InputError. Nothing is copied: a sweep's
/// variants are built in time linear in their number.
toml::node* locate(toml::table& root, const VaryTable& vary, bool create,
                   std::size_t count = std::numeric_limits<std::size_t>::max()) {
  count = std::min(count, vary.parts.size());
  toml::node* node = &root;
  if (count == 0) return node;
  std::string path;
  for (std::size_t i = 0; i < count; ++i) {
    const std::string& part = vary.parts[i];
    const bool last = i + 1 == count;
    toml::node* next = nullptr;
    if (toml::table* table = node->as_table()) {
      next = table->get(part);
      if (!next && !last) {
        if (!create) break;
        next = table->insert_or_assign(part, toml::table{}).first->second.as_table();
      }
    } else if (toml::array* array = node->as_array()) {
      const std::optional<long> index = as_index(part);
      if (!index) {
        throw InputError(vary.origin, "key", "'" + cut_input(vary.key) + "': " +
                                                 (path.empty() ? "the scene" : cut_input(path)) +
                                                 " is an array; expected an index, got '" + cut_input(part) + "'");
      }
      if (*index >= static_cast<long>(array->size())) {
        throw InputError(vary.origin, "key", "'" + cut_input(vary.key) + "': " + cut_input(path) + " has " +
                                                 std::to_string(array->size()) + " entries (0 to " +
                                                 std::to_string(static_cast<long>(array->size()) - 1) +
                                                 "), no entry " + cut_input(part));
      }
      next = array->get(static_cast<std::size_t>(*index));
    } else {
      throw InputError(vary.origin, "key",
                       "'" + cut_input(vary.key) + "': " + cut_input(path) + " is a value, not a table or array");
    }
    path += (path.empty() ? "" : ".") + part;
    if (last) return next;
    if (!next) break;
    node = next;
  }
  return nullptr;
}

/// Put value at the key's path in root (replacing the node there, or adding it to its table).
void assign(toml::table& root, const VaryTable& vary, const toml::node& value) {
  const bool present = locate(root, vary, true) != nullptr;
  // The parent, one level up (the path's tables exist now).
  toml::node* up = locate(root, vary, true, vary.parts.size() - 1);
  if (toml::table* table = up ? up->as_table() : nullptr) {
    table->insert_or_assign(vary.parts.back(), value);
    return;
  }
  if (toml::array* array = up ? up->as_array() : nullptr; array && present) {
    const auto at = array->begin() + static_cast<std::ptrdiff_t>(*as_index(vary.parts.back()));
    array->replace(at, value);
    return;
  }
  throw InputError(vary.origin, "key", "'" + cut_input(vary.key) + "': no such place in the scene");
}

bool numeric(const toml::node& node) { return node.is_floating_point() || node.is_integer(); }

double number_of(const toml::node& node) {
  if (const auto* f = node.as_floating_point()) return f->get();
  return static_cast<double>(node.as_integer()->get());
}

/// The text of a value for sweep.csv, one cell per number of an array.
void append_cells(const toml::node& node, std::vector<std::string>& cells) {
  if (const toml::array* array = node.as_array()) {
    for (const toml::node& item : *array) append_cells(item, cells);
  } else if (const auto* f = node.as_floating_point()) {
    cells.push_back(format_number(f->get()));
  } else if (const auto* i = node.as_integer()) {
    cells.push_back(std::to_string(i->get()));
  } else if (const auto* s = node.as_string()) {
    cells.push_back(s->get());
  } else if (const auto* b = node.as_boolean()) {
    cells.push_back(b->get() ? "true" : "false");
  } else {
    std::ostringstream text;
    node.visit([&](auto&& concrete) { text << concrete; });
    cells.push_back(text.str());
  }
}

/// The column names of a value: KEY for a scalar, KEY.i (and KEY.i.j) for arrays.
void append_columns(const toml::node& node, const std::string& name, std::vector<std::string>& columns) {
  if (const toml::array* array = node.as_array()) {
    for (std::size_t i = 0; i < array->size(); ++i) append_columns(*array->get(i), name + "." + std::to_string(i), columns);
  } else {
    columns.push_back(name);
  }
}

/// The space of a scene table, for keeping perturbed points on it: kind and radius, if readable.
struct SpaceOf {
  std::string kind;
  double radius = 1.0;
};

SpaceOf space_of(const toml::table& root) {
  SpaceOf space;
  if (const toml::table* table = root["space"].as_table()) {
    if (const auto* kind = (*table)["kind"].as_string()) space.kind = kind->get();
    if (const toml::node* radius = table->get("radius"); radius && numeric(*radius)) space.radius = number_of(*radius);
  }
  return space;
}

std::optional<std::vector<double>> numbers_of(const toml::node* node) {
  const toml::array* array = node ? node->as_array() : nullptr;
  if (!array) return std::nullopt;
  std::vector<double> out;
  for (const toml::node& item : *array) {
    if (!numeric(item)) return std::nullopt;
    out.push_back(number_of(item));
  }
  return out;
}

toml::array array_of(const std::vector<double>& values) {
  toml::array out;
  for (double value : values) out.push_back(value);
  return out;
}

/// The Minkowski product on H^n (time-like coordinate last) or the Euclidean one.
double product(const std::vector<double>& a, const std::vector<double>& b, bool lorentz) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += (lorentz && i + 1 == a.size() ? -1.0 : 1.0) * a[i] * b[i];
  return sum;
}

/// v made tangent at x: minus its component along x (S^n: x.x = R^2; H^n: <x,x> = -R^2).
void make_tangent(const std::vector<double>& x, std::vector<double>& v, const SpaceOf& space) {
  if (space.kind != "sphere" && space.kind != "hyperbolic") return;
  if (x.size() != v.size()) return;  // the scene reader names the mismatch
  const bool lorentz = space.kind == "hyperbolic";
  const double along = product(x, v, lorentz) / product(x, x, lorentz);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] -= along * x[i];
}

/// Copy k of a perturbation: the key's number(s) plus size * draws; a body's embedding point x
/// is put back on the space (S^n: scaled to radius R; H^n: the time-like coordinate recomputed)
/// and its velocity v made tangent there again; a perturbed v is made tangent at x.
void perturb(toml::table& root, const VaryTable& vary, long copy) {
  toml::node* node = locate(root, vary, false);
  if (!node || !(numeric(*node) || numbers_of(node))) {
    throw InputError(vary.origin, "perturb",
                     "'" + cut_input(vary.key) + "' must be a number or an array of numbers in the scene to be perturbed" +
                         (node ? "" : " (it is not in the scene)"));
  }
  if (numeric(*node)) {
    const double value = number_of(*node) + vary.size * perturbation_draws(vary.seed, copy, 1)[0];
    assign(root, vary, toml::value<double>(value));
    return;
  }
  std::vector<double> values = *numbers_of(node);
  const std::vector<double> draws = perturbation_draws(vary.seed, copy, static_cast<int>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i) values[i] += vary.size * draws[i];

  const std::size_t n = vary.parts.size();
  const bool body_vector = n == 3 && vary.parts[0] == "bodies" && (vary.parts[2] == "x" || vary.parts[2] == "v");
  const SpaceOf space = space_of(root);
  if (body_vector && !values.empty()) {
    toml::table* body = root["bodies"][static_cast<std::size_t>(as_index(vary.parts[1]).value_or(0))].as_table();
    if (!body) {
      // not a body table: the scene reader names the problem
    } else if (vary.parts[2] == "x") {
      if (space.kind == "sphere") {
        const double scale = space.radius / std::sqrt(product(values, values, false));
        for (double& c : values) c *= scale;
      } else if (space.kind == "hyperbolic") {
        double spatial = 0.0;
        for (std::size_t i = 0; i + 1 < values.size(); ++i) spatial += values[i] * values[i];
        values.back() = std::sqrt(space.radius * space.radius + spatial);
      }
      if (std::optional<std::vector<double>> v = numbers_of(body->get("v"))) {
        make_tangent(values, *v, space);
        body->insert_or_assign("v", array_of(*v));
      }
    } else if (std::optional<std::vector<double>> x = numbers_of(body->get("x"))) {
      make_tangent(*x, values, space);
    }
  }
  assign(root, vary, array_of(values));
}

/// The cap on runs and why, for messages: "N runs in one sweep (...)".
std::string cap_reason() {
  return std::to_string(max_sweep_runs) +
         " runs in one sweep (each run is a process and a folder in runs/, and every variant is built, "
         "checked and held in memory before the first run starts); split it into several sweeps";
}

VaryTable read_vary(const toml::table& table, const fs::path& file, std::size_t number) {
  VaryTable vary;
  vary.origin = origin_of(file, table.source());
  const std::string name = "vary[" + std::to_string(number) + "]";
  for (const auto& [key, node] : table) {
    if (std::find(vary_keys.begin(), vary_keys.end(), key.str()) == vary_keys.end()) {
      throw InputError(origin_of(file, key.source()), name + "." + cut_input(key.str()),
                       "unknown key" + did_you_mean(key.str(), vary_keys) + " (keys: " + one_of(vary_keys) + ")");
    }
  }
  const auto* key = table["key"].as_string();
  if (!key) {
    throw InputError(vary.origin, name + ".key",
                     table.contains("key") ? "expected a string (a dotted scene key, e.g. \"integrator.dt\")"
                                           : "missing required key (the scene key to vary, e.g. \"integrator.dt\")");
  }
  vary.key = key->get();
  vary.origin = origin_of(file, key->source());
  std::string_view rest = vary.key;
  while (true) {
    const std::size_t dot = rest.find('.');
    vary.parts.emplace_back(rest.substr(0, dot));
    if (vary.parts.back().empty()) {
      throw InputError(vary.origin, name + ".key",
                       "'" + cut_input(vary.key) + "' has an empty part; expected e.g. \"bodies.0.v\"");
    }
    if (dot == std::string_view::npos) break;
    rest.remove_prefix(dot + 1);
  }
  if (vary.parts.size() > 8) {
    throw InputError(vary.origin, name + ".key", "'" + cut_input(vary.key) + "' has too many parts");
  }
  const int kinds = table.contains("values") + table.contains("range") + table.contains("perturb");
  if (kinds != 1) {
    throw InputError(vary.origin, name, kinds > 1 ? "give one of values, range and perturb, not several"
                                                  : "expected values = [...], range = [START, STOP, COUNT] or "
                                                    "perturb = SIZE with count = N");
  }
  if (const toml::node* range = table.get("range")) {
    // COUNT evenly spaced numbers from START to STOP, both included: START + i (STOP - START) / (COUNT - 1).
    const toml::array* items = range->as_array();
    const auto bad = [&] {
      return InputError(origin_of(file, range->source()), name + ".range",
                        "expected [START, STOP, COUNT]: two finite numbers and an integer >= 2");
    };
    if (!items || items->size() != 3 || !numeric(*items->get(0)) || !numeric(*items->get(1)) ||
        !items->get(2)->is_integer()) {
      throw bad();
    }
    const double start = number_of(*items->get(0)), stop = number_of(*items->get(1));
    const std::int64_t count = items->get(2)->as_integer()->get();
    if (!std::isfinite(start) || !std::isfinite(stop) || count < 2) throw bad();
    if (count > max_sweep_runs) {
      throw InputError(origin_of(file, range->source()), name + ".range",
                       "COUNT = " + std::to_string(count) + " is over the cap of " + cap_reason());
    }
    for (std::int64_t i = 0; i < count; ++i) {
      vary.values.push_back(i + 1 == count ? stop : start + static_cast<double>(i) * (stop - start) / static_cast<double>(count - 1));
    }
    for (const char* other : {"count", "seed"}) {
      if (table.contains(other)) {
        throw InputError(origin_of(file, table.get(other)->source()), name + "." + other, "only with perturb");
      }
    }
    return vary;
  }
  const bool has_values = table.contains("values");
  if (has_values) {
    for (const char* other : {"count", "seed"}) {
      if (table.contains(other)) {
        throw InputError(origin_of(file, table.get(other)->source()), name + "." + other, "only with perturb");
      }
    }
    const toml::array* values = table["values"].as_array();
    if (!values || values->empty()) {
      throw InputError(origin_of(file, table.get("values")->source()), name + ".values",
                       "expected a non-empty array of values for " + cut_input(vary.key));
    }
    vary.values = *values;
    return vary;
  }
  vary.perturb = true;
  const toml::node* size = table.get("perturb");
  if (!numeric(*size) || !std::isfinite(number_of(*size)) || number_of(*size) <= 0.0) {
    throw InputError(origin_of(file, size->source()), name + ".perturb", "expected a finite number > 0");
  }
  vary.size = number_of(*size);
  const toml::node* count = table.get("count");
  if (!count) throw InputError(vary.origin, name + ".count", "missing required key (the number of perturbed copies)");
  if (!count->is_integer() || count->as_integer()->get() < 1) {
    throw InputError(origin_of(file, count->source()), name + ".count", "expected an integer >= 1");
  }
  if (count->as_integer()->get() > max_sweep_runs) {
    throw InputError(origin_of(file, count->source()), name + ".count",
                     std::to_string(count->as_integer()->get()) + " is over the cap of " + cap_reason());
  }
  vary.count = static_cast<long>(count->as_integer()->get());
  if (const toml::node* seed = table.get("seed")) {
    if (!seed->is_integer() || seed->as_integer()->get() < 0) {
      throw InputError(origin_of(file, seed->source()), name + ".seed", "expected an integer >= 0");
    }
    vary.seed = static_cast<std::uint64_t>(seed->as_integer()->get());
  }
  return vary;
}

/// The message of a scene reader's error on a variant without its "run NNNN:LINE:COL: " prefix
/// (lines of the generated text mean nothing to the user).
std::string without_origin(const std::string& message, const std::string& label) {
  if (!message.starts_with(label)) return message;
  std::size_t at = label.size();
  while (at < message.size() && (message[at] == ':' || std::isdigit(static_cast<unsigned char>(message[at])))) ++at;
  while (at < message.size() && message[at] == ' ') ++at;
  return message.substr(at);
}

}  // namespace

Sweep read_sweep_file(const fs::path& path) {
  Sweep sweep;
  sweep.file = path;
  const std::string file = path.string();
  const toml::table root = parse_toml(read_text(path, Origin{}, "SWEEP", "sweep file"), file);
  for (const auto& [key, node] : root) {
    if (std::find(top_keys.begin(), top_keys.end(), key.str()) == top_keys.end()) {
      throw InputError(origin_of(path, key.source()), cut_input(key.str()),
                       "unknown key" + did_you_mean(key.str(), top_keys) + " (keys: " + one_of(top_keys) + ")");
    }
  }
  const auto* scene = root["scene"].as_string();
  if (!scene) {
    throw InputError(Origin{file}, "scene",
                     root.contains("scene") ? "expected a string, the base scene's path (relative to the sweep file)"
                                            : "missing required key (the base scene's path, relative to the sweep file)");
  }
  const Origin scene_origin = origin_of(path, scene->source());
  sweep.scene_path = path.parent_path() / scene->get();
  if (const toml::node* trajectory = root.get("trajectory")) {
    if (!trajectory->is_boolean()) {
      throw InputError(origin_of(path, trajectory->source()), "trajectory", "expected true or false");
    }
    sweep.trajectory = trajectory->as_boolean()->get();
  }
  const toml::array* tables = root["vary"].as_array();
  if (!tables || tables->empty() || !tables->is_array_of_tables()) {
    throw InputError(Origin{file}, "vary", "expected one or more [[vary]] tables");
  }
  std::vector<VaryTable> varies;
  long total = 1;
  for (std::size_t i = 0; i < tables->size(); ++i) {
    varies.push_back(read_vary(*tables->get(i)->as_table(), path, i));
    for (std::size_t j = 0; j + 1 < varies.size(); ++j) {
      if (varies[j].key == varies.back().key) {
        throw InputError(varies.back().origin, "key", "'" + cut_input(varies.back().key) + "' is varied twice");
      }
    }
    const long length = varies.back().length();
    if (total > max_sweep_runs / length) {
      throw InputError(varies.back().origin, "vary",
                       "the [[vary]] tables make " + (i == 0 ? std::to_string(length) + " runs"
                                                             : std::to_string(total) + " x " + std::to_string(length) +
                                                                   " runs so far") +
                           ", over the cap of " + cap_reason());
    }
    total *= length;
  }

  const std::string scene_text = read_text(sweep.scene_path, scene_origin, "scene", "scene file");
  toml::table base = parse_toml(scene_text, sweep.scene_path.string());
  // A bodies file (bodies = "FILE.csv") is relative to the base scene's directory, but each run's
  // scene is read from its own directory: the runs name the file by its absolute path.
  if (auto* bodies = base.get_as<std::string>("bodies"); bodies && fs::path(bodies->get()).is_relative()) {
    *bodies = fs::absolute(sweep.scene_path.parent_path() / bodies->get()).lexically_normal().string();
  }

  // Build every variant: the first [[vary]] varies slowest.
  sweep.variants.reserve(static_cast<std::size_t>(total));
  std::vector<long> choice(varies.size(), 0);
  for (long index = 0; index < total; ++index) {
    long rest = index;
    for (std::size_t v = varies.size(); v-- > 0;) {
      choice[v] = rest % varies[v].length();
      rest /= varies[v].length();
    }
    toml::table table = base;
    for (std::size_t v = 0; v < varies.size(); ++v) {
      if (!varies[v].perturb) assign(table, varies[v], *varies[v].values.get(static_cast<std::size_t>(choice[v])));
    }
    for (std::size_t v = 0; v < varies.size(); ++v) {
      if (varies[v].perturb) perturb(table, varies[v], choice[v]);
    }
    Variant variant;
    variant.index = index;
    std::vector<std::string> columns;
    for (const VaryTable& vary : varies) {
      const toml::node* value = locate(table, vary, false);
      append_cells(*value, variant.values);
      append_columns(*value, vary.key, columns);
    }
    if (index == 0) {
      sweep.columns = columns;
    } else if (columns != sweep.columns) {
      throw InputError(varies.front().origin, "values",
                       "every value of a key must have the same shape (run " + std::to_string(index) +
                           " has columns that run 0 does not)");
    }
    std::ostringstream text;
    const std::string label = run_name(index, total);
    // File names only: the text must not depend on where the sweep is started from (a rerun
    // compares it with the run's scene.toml).
    text << "# sesi sweep " << path.filename().string() << ", run " << label << "; base scene "
         << sweep.scene_path.filename().string() << "\n"
         << toml::toml_formatter(table) << "\n";
    variant.scene_text = text.str();
    try {
      (void)read_scene_text(variant.scene_text, "run " + label);
    } catch (const InputError& e) {
      std::string values;
      for (std::size_t c = 0; c < columns.size(); ++c) {
        values += (c ? ", " : "") + cut_input(columns[c] + " = " + variant.values[c]);
      }
      throw InputError(varies.size() == 1 ? varies.front().origin : Origin{file}, "",
                       "run " + label + " (" + values + ") is not a valid scene: " +
                           without_origin(e.what(), "run " + label));
    }
    variant.sets_threads = table["integrator"]["threads"].node() != nullptr;
    sweep.variants.push_back(std::move(variant));
  }
  return sweep;
}

}  // namespace sesi::program
