#include "scene_reader.hpp"
#include "scene_table.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>

#include <toml++/toml.h>

#include <sesi/special_functions.hpp>

#include "errors.hpp"
#include "geometry.hpp"
#include "paper_scene.hpp"
#include "scene_limits.hpp"
#include "suggest.hpp"
#include "validate.hpp"

namespace sesi::program {

namespace {

using namespace std::string_view_literals;

/// Tolerance on "x is on the space" and "v is tangent at x" (relative).
constexpr double on_space_tolerance = 1e-9;
/// Two bodies this close (relative to the space's length scale) are at the same point.
constexpr double same_point_tolerance = 1e-12;

constexpr std::array space_kinds = {"sphere"sv, "hyperbolic"sv, "euclidean"sv};
// The keys of each potential kind (docs/scene-format.md; potential_catalogue()).
constexpr std::array chord_well_keys = {"kind"sv, "theta0"sv, "strength"sv};
constexpr std::array cotangent_gravity_keys = {"kind"sv, "G"sv, "min_distance"sv};
constexpr std::array central_cotangent_keys = {"kind"sv, "k"sv, "center"sv, "min_distance"sv};
constexpr std::array harmonic_pair_keys = {"kind"sv, "k"sv, "d0"sv};
constexpr std::array lennard_jones_keys = {"kind"sv, "epsilon"sv, "sigma"sv, "cutoff"sv, "min_distance"sv};
constexpr std::array potential_kinds = {"chord-well"sv, "cotangent-gravity"sv,
                                        "central-cotangent"sv, "harmonic-pair"sv,
                                        "lennard-jones"sv};
constexpr std::array exact_solutions = {"paper"sv};

// ---- a shield against a toml++ 3.3 bug ---------------------------------------------------------
// toml++ 3.3's is_non_ascii_horizontal_whitespace() reaches __builtin_unreachable (undefined
// behaviour) for the code points U+00A1..U+0499, U+2C5E..U+3057 and U+FB26..U+FEFF (but U+3000,
// U+FEFF) wherever it tests them for whitespace: in keys, malformed values, or after a string it
// could not parse (found by fuzz/scene_fuzzer.cpp). Before parsing, every code point of those
// three ranges is replaced by one of the unused private-use code points U+F0000..U+F0BFF (beyond
// U+FEFF the test returns false at once), and the strings read from the table are mapped back,
// so valid files read exactly as before. Files that use that private-use block are refused.

constexpr char32_t shield_base = 0xF0000;
struct ShieldRange {
  char32_t first, last;
};
constexpr std::array<ShieldRange, 3> shielded_ranges = {{{0xA0, 0x499}, {0x2C5E, 0x3057}, {0xFB26, 0xFEFF}}};
constexpr char32_t shield_end = shield_base + 0xC00;

/// The code point at text[k] and its length in bytes, or length 0 for ill-formed UTF-8 (left
/// to toml++, which reports it).
std::pair<char32_t, std::size_t> decode_utf8(std::string_view text, std::size_t k) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  const unsigned char c = byte(k);
  std::size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
  if (n == 0 || k + n > text.size()) return {0, 0};
  char32_t cp = n == 1 ? c : n == 2 ? (c & 0x1F) : n == 3 ? (c & 0x0F) : (c & 0x07);
  for (std::size_t i = 1; i < n; ++i) {
    if ((byte(k + i) & 0xC0) != 0x80) return {0, 0};
    cp = (cp << 6) | (byte(k + i) & 0x3F);
  }
  return {cp, n};
}

void encode_utf8(char32_t cp, std::string& out) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

/// text with the shielded code points replaced (into out); the line and column of a code point
/// of the private-use block, if the text has one. A leading byte-order mark is kept.
std::optional<std::pair<int, int>> shield_from_toml_bug(std::string_view text, std::string& out) {
  out.clear();
  out.reserve(text.size() + text.size() / 2);
  int line = 1, column = 0;
  std::size_t k = 0;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") {
    out.append(text.substr(0, 3));
    k = 3;
  }
  while (k < text.size()) {
    const auto [cp, n] = decode_utf8(text, k);
    ++column;
    if (n == 0) {  // ill-formed: copied as is
      out += text[k++];
      continue;
    }
    if (cp == U'\n') {
      ++line;
      column = 0;
    }
    if (cp >= shield_base && cp < shield_end) return std::pair{line, column};
    char32_t mapped = cp;
    char32_t offset = 0;
    for (const ShieldRange& r : shielded_ranges) {
      if (cp >= r.first && cp <= r.last) mapped = shield_base + offset + (cp - r.first);
      offset += 0x400;
    }
    if (mapped == cp) {
      out.append(text.substr(k, n));
    } else {
      encode_utf8(mapped, out);
    }
    k += n;
  }
  return std::nullopt;
}

/// The inverse of shield_from_toml_bug on a string read from the table.
std::string unshield(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  std::size_t k = 0;
  while (k < text.size()) {
    const auto [cp, n] = decode_utf8(text, k);
    if (n == 0) {
      out += text[k++];
      continue;
    }
    if (cp >= shield_base && cp < shield_end) {
      const char32_t offset = cp - shield_base;
      encode_utf8(shielded_ranges[offset / 0x400].first + offset % 0x400, out);
    } else {
      out.append(text.substr(k, n));
    }
    k += n;
  }
  return out;
}

std::string_view type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a float";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::date: return "a date";
    case toml::node_type::time: return "a time";
    case toml::node_type::date_time: return "a date-time";
    default: return "nothing";
  }
}

/// One TOML table being read: its key path ("bodies[2]") and where it is.
class TableReader {
 public:
  TableReader(const toml::table& table, std::string path, const std::string& file)
      : table_(table), path_(std::move(path)), file_(file) {}

  const std::string& path() const { return path_; }
  Origin origin() const { return origin_of(table_.source()); }
  Origin origin_of(const toml::source_region& region) const {
    return {file_, static_cast<int>(region.begin.line), static_cast<int>(region.begin.column)};
  }
  Origin origin_of(std::string_view key) const {
    const toml::node* node = table_.get(key);
    return node ? origin_of(node->source()) : origin();
  }
  std::string key_path(std::string_view key) const {
    return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  }
  bool has(std::string_view key) const { return table_.contains(key); }
  /// The table's keys as written (unshielded).
  std::vector<std::pair<std::string, Origin>> keys() const {
    std::vector<std::pair<std::string, Origin>> out;
    for (auto&& [key, node] : table_) out.emplace_back(unshield(key.str()), origin_of(key.source()));
    return out;
  }
  const toml::node* get(std::string_view key) const { return table_.get(key); }

  /// Refuse keys not in allowed, suggesting the nearest one.
  void allow_only(std::span<const std::string_view> allowed, std::string_view what) const {
    for (auto&& [key, node] : table_) {
      if (std::find(allowed.begin(), allowed.end(), key.str()) != allowed.end()) continue;
      const std::string name = unshield(key.str());
      const std::string hint = did_you_mean(name, allowed);
      throw InputError(origin_of(key.source()), key_path(cut_input(name)),
                       "unknown key in " + std::string(what) +
                           (hint.empty() ? " (expected " + one_of(allowed) + ")" : hint));
    }
  }

  [[noreturn]] void missing(std::string_view key, std::string_view expected) const {
    throw InputError(origin(), key_path(key), "missing required key (" + std::string(expected) + ")");
  }
  [[noreturn]] void fail(std::string_view key, std::string_view message) const {
    throw InputError(origin_of(key), key_path(key), message);
  }

  /// A finite number (integers accepted).
  double number(std::string_view key, std::string_view expected) const {
    const toml::node* node = get(key);
    if (!node) missing(key, expected);
    return to_number(*node, key_path(key), expected);
  }
  double number_or(std::string_view key, double fallback, std::string_view expected) const {
    return has(key) ? number(key, expected) : fallback;
  }
  double to_number(const toml::node& node, const std::string& key, std::string_view expected) const {
    double value = 0.0;
    if (const auto* i = node.as_integer()) {
      value = static_cast<double>(i->get());
    } else if (const auto* f = node.as_floating_point()) {
      value = f->get();
    } else {
      throw InputError(origin_of(node.source()), key,
                       "expected " + std::string(expected) + ", got " + std::string(type_name(node)));
    }
    if (!std::isfinite(value)) {
      throw InputError(origin_of(node.source()), key,
                       "expected " + std::string(expected) + ", got " + format_number(value));
    }
    return value;
  }

  long integer(std::string_view key, std::string_view expected) const {
    const toml::node* node = get(key);
    if (!node) missing(key, expected);
    const auto* i = node->as_integer();
    if (!i) {
      throw InputError(origin_of(node->source()), key_path(key),
                       "expected " + std::string(expected) + ", got " + std::string(type_name(*node)));
    }
    return static_cast<long>(i->get());
  }

  std::string string(std::string_view key, std::string_view expected) const {
    const toml::node* node = get(key);
    if (!node) missing(key, expected);
    const auto* s = node->as_string();
    if (!s) {
      throw InputError(origin_of(node->source()), key_path(key),
                       "expected " + std::string(expected) + ", got " + std::string(type_name(*node)));
    }
    return unshield(s->get());
  }

  /// An array of `size` finite numbers.
  Eigen::VectorXd vector(std::string_view key, int size, std::string_view what) const {
    const toml::node* node = get(key);
    const std::string expected = "an array of " + std::to_string(size) + " numbers (" + std::string(what) + ")";
    if (!node) missing(key, expected);
    const auto* array = node->as_array();
    if (!array) {
      throw InputError(origin_of(node->source()), key_path(key),
                       "expected " + expected + ", got " + std::string(type_name(*node)));
    }
    if (static_cast<int>(array->size()) != size) {
      throw InputError(origin_of(node->source()), key_path(key),
                       "expected " + expected + ", got " + std::to_string(array->size()) +
                           (array->size() == 1 ? " number" : " numbers"));
    }
    Eigen::VectorXd out(size);
    for (int k = 0; k < size; ++k) {
      out[k] = to_number(*array->get(static_cast<std::size_t>(k)),
                         key_path(key) + "[" + std::to_string(k + 1) + "]", "a finite number");
    }
    return out;
  }

  /// A sub-table, or nullptr when absent.
  const toml::table* table(std::string_view key) const {
    const toml::node* node = get(key);
    if (!node) return nullptr;
    const auto* t = node->as_table();
    if (!t) {
      throw InputError(origin_of(node->source()), key_path(key),
                       "expected a table [" + std::string(key) + "], got " + std::string(type_name(*node)));
    }
    return t;
  }

  /// An array of tables ([[key]]), empty when absent.
  std::vector<const toml::table*> tables(std::string_view key) const {
    std::vector<const toml::table*> out;
    const toml::node* node = get(key);
    if (!node) return out;
    const auto* array = node->as_array();
    if (!array || !array->is_array_of_tables()) {
      throw InputError(origin_of(node->source()), key_path(key),
                       "expected an array of tables [[" + std::string(key) + "]], got " +
                           std::string(type_name(*node)));
    }
    for (const toml::node& element : *array) out.push_back(element.as_table());
    return out;
  }

 private:
  const toml::table& table_;
  std::string path_;
  const std::string& file_;
};

/// One body's values as given, read on demand, and where each is: a [[bodies]] table or a row of
/// a bodies file (CSV). SceneReader::read_body makes every check of a body through it, so both
/// forms are checked alike, with messages that name the table's key or the file's line.
class BodyInput {
 public:
  virtual ~BodyInput() = default;
  virtual bool has(std::string_view key) const = 0;  ///< "mass", "q", "p", "x" or "v"
  virtual double number(std::string_view key, std::string_view expected) const = 0;
  virtual Eigen::VectorXd vector(std::string_view key, int size, std::string_view what) const = 0;
  virtual Origin origin() const = 0;                    ///< where the body starts
  virtual Origin origin_of(std::string_view key) const = 0;
  virtual std::string key_path(std::string_view key) const = 0;
  [[noreturn]] virtual void missing(std::string_view key, std::string_view expected) const = 0;
  [[noreturn]] void fail(std::string_view key, std::string_view message) const {
    throw InputError(origin_of(key), key_path(key), message);
  }
};

/// A [[bodies]] table.
class TableBody final : public BodyInput {
 public:
  explicit TableBody(const TableReader& table) : table_(table) {}
  bool has(std::string_view key) const override { return table_.has(key); }
  double number(std::string_view key, std::string_view expected) const override { return table_.number(key, expected); }
  Eigen::VectorXd vector(std::string_view key, int size, std::string_view what) const override {
    return table_.vector(key, size, what);
  }
  Origin origin() const override { return table_.origin(); }
  Origin origin_of(std::string_view key) const override { return table_.origin_of(key); }
  std::string key_path(std::string_view key) const override { return table_.key_path(key); }
  [[noreturn]] void missing(std::string_view key, std::string_view expected) const override {
    table_.missing(key, expected);
  }

 private:
  const TableReader& table_;
};

/// A [thermostat] table (docs/scene-format.md): kind, temperature (a number or a schedule
/// [[t0, T0], [t1, T1], ...]) and the kind's own keys, each checked where it stands.
ThermostatSpec read_thermostat(const TableReader& th) {
  ThermostatSpec spec;
  spec.line = th.origin().line;
  if (!th.has("kind")) {
    th.allow_only(all_thermostat_keys(), "[thermostat]");
    th.missing("kind", one_of(thermostat_kinds()));
  }
  spec.kind = th.string("kind", "a string");
  const auto keys = thermostat_keys(spec.kind);
  if (keys.empty()) {
    th.fail("kind", "unknown thermostat kind '" + cut_input(spec.kind) + "'" + did_you_mean(spec.kind, thermostat_kinds()) +
                        " (expected " + one_of(thermostat_kinds()) + ")");
  }
  const auto takes = [&](std::string_view key) { return std::find(keys.begin(), keys.end(), key) != keys.end(); };
  // A key of another kind (gamma with nose-hoover, seed with nose-hoover, ...): say whose it is.
  const auto all = all_thermostat_keys();
  for (const auto& [key, where] : th.keys()) {
    if (takes(key) || std::find(all.begin(), all.end(), key) == all.end()) continue;
    throw InputError(where, th.key_path(key),
                     "not a key of a " + spec.kind + " thermostat (" + key + " goes with " + kinds_taking(key) +
                         "; " + spec.kind + " takes " + one_of(keys) + ")");
  }
  th.allow_only(keys, "a " + spec.kind + " thermostat");

  const std::string expected_temperature = "a finite temperature kT" + std::string(spec.kind == "nose-hoover" ? " > 0" : " >= 0");
  const toml::node* temperature = th.get("temperature");
  if (!temperature) {
    th.missing("temperature", "kT in energy units (k_B = 1), or a schedule [[t0, T0], [t1, T1], ...]");
  }
  if (const auto* knots = temperature->as_array()) {
    // A schedule: (t, kT) knots, t strictly increasing, linear between them (ThermostatSpec).
    if (knots->empty()) {
      th.fail("temperature", "expected a schedule of one or more [t, T] pairs, got an empty array");
    }
    for (std::size_t k = 0; k < knots->size(); ++k) {
      const toml::node& item = *knots->get(k);
      const std::string key = th.key_path("temperature") + "[" + std::to_string(k + 1) + "]";
      const auto* pair = item.as_array();
      if (!pair || pair->size() != 2) {
        throw InputError(th.origin_of(item.source()), key,
                         "expected a pair [t, T] (a time and the temperature there), got " +
                             (pair ? "an array of " + std::to_string(pair->size()) : std::string(type_name(item))));
      }
      const double t = th.to_number(*pair->get(0), key + "[1]", "a finite time");
      const double kT = th.to_number(*pair->get(1), key + "[2]", expected_temperature);
      if (k > 0 && !(t > spec.schedule.back().first)) {
        throw InputError(th.origin_of(pair->get(0)->source()), key + "[1]",
                         "the schedule's times must increase strictly, got " + format_number(t) + " after " +
                             format_number(spec.schedule.back().first));
      }
      check_temperature(kT, spec.kind, th.origin_of(pair->get(1)->source()), key + "[2]");
      spec.schedule.emplace_back(t, kT);
    }
  } else {
    const double kT = th.to_number(*temperature, th.key_path("temperature"),
                                   expected_temperature + " (or a schedule [[t0, T0], [t1, T1], ...])");
    check_temperature(kT, spec.kind, th.origin_of("temperature"), th.key_path("temperature"));
    spec.schedule = {{0.0, kT}};
  }
  if (takes("gamma")) {
    spec.gamma = th.number("gamma", "a finite friction gamma > 0 (1/time)");
    check_friction(spec.gamma, th.origin_of("gamma"), th.key_path("gamma"));
  }
  if (takes("tau")) {
    spec.tau = th.number("tau", "a finite relaxation time tau > 0");
    check_relaxation_time(spec.tau, th.origin_of("tau"), th.key_path("tau"));
  }
  if (takes("chain") && th.has("chain")) {
    const long chain = th.integer("chain", "an integer from 1 to " + std::to_string(max_chain));
    check_chain(chain, th.origin_of("chain"), th.key_path("chain"));
    spec.chain = static_cast<int>(chain);
  }
  if (takes("seed") && th.has("seed")) {
    const long seed = th.integer("seed", "an integer from 0 to 2^63 - 1");
    check_seed(seed, th.origin_of("seed"), th.key_path("seed"));
    spec.seed = static_cast<std::uint64_t>(seed);
  }
  return spec;
}

// ---- bodies from a file (docs/scene-format.md, "Bodies from a file") ---------------------------

/// The comma-separated fields of a line, spaces and tabs around each trimmed (and a CR, for
/// files with CRLF line ends); views into line.
void split_fields(std::string_view line, std::vector<std::string_view>& fields) {
  const auto trim = [](std::string_view f) {
    const std::size_t first = f.find_first_not_of(" \t\r");
    if (first == std::string_view::npos) return f.substr(0, 0);
    return f.substr(first, f.find_last_not_of(" \t\r") - first + 1);
  };
  fields.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    const std::size_t length = comma == std::string_view::npos ? std::string_view::npos : comma - start;
    fields.push_back(trim(line.substr(start, length)));
    if (comma == std::string_view::npos) return;
    start = comma + 1;
  }
}

/// A bodies file's columns, from its header: the field of the mass and of each component of q,
/// p, x, v (empty when absent).
struct BodyColumns {
  int count = 0;
  int mass = -1;
  std::array<std::vector<int>, 4> fields;  ///< q, p, x, v
  std::vector<std::string> names;          ///< the header's names, by field

  static constexpr std::array<std::string_view, 4> vectors = {"q"sv, "p"sv, "x"sv, "v"sv};
  const std::vector<int>& of(std::string_view key) const {
    return fields[static_cast<std::size_t>(std::find(vectors.begin(), vectors.end(), key) - vectors.begin())];
  }
};

/// One row of a bodies file, as read_body reads a [[bodies]] table: the row's numbers (parsed
/// and checked finite), the file and line for messages, "bodies[k]" for keys.
class RowBody final : public BodyInput {
 public:
  RowBody(const BodyColumns& columns, const std::vector<double>& values, const std::string& file, int line,
          int index)
      : columns_(columns), values_(values), file_(file), line_(line), index_(index) {}
  bool has(std::string_view key) const override { return key == "mass" || !columns_.of(key).empty(); }
  double number(std::string_view, std::string_view) const override {
    return values_[static_cast<std::size_t>(columns_.mass)];  // (only the mass is a number)
  }
  Eigen::VectorXd vector(std::string_view key, int size, std::string_view) const override {
    const std::vector<int>& fields = columns_.of(key);  // (the header has all size of them)
    Eigen::VectorXd out(size);
    for (int k = 0; k < size; ++k) out[k] = values_[static_cast<std::size_t>(fields[static_cast<std::size_t>(k)])];
    return out;
  }
  Origin origin() const override { return {file_, line_}; }
  Origin origin_of(std::string_view) const override { return origin(); }
  std::string key_path(std::string_view key) const override {
    return "bodies[" + std::to_string(index_) + "]." + std::string(key);
  }
  [[noreturn]] void missing(std::string_view key, std::string_view expected) const override {
    throw InputError(origin(), key_path(key), "missing column (" + std::string(expected) + ")");
  }

 private:
  const BodyColumns& columns_;
  const std::vector<double>& values_;
  const std::string& file_;
  int line_;
  int index_;
};

/// Where each body and potential came from, for the checks that involve several of them.
/// Compact, for 10^6 bodies and more: the file once (the scene file, or the bodies file), then
/// each body's line and column (column 0 in a bodies file) and whether its position was q or x.
struct Provenance {
  std::string body_file;
  std::vector<std::pair<int, int>> body_where;
  std::vector<bool> body_chart;
  std::vector<Origin> potentials;

  void add_body(const Origin& where, bool chart) {
    body_where.emplace_back(where.line, where.column);
    body_chart.push_back(chart);
  }
  Origin body_origin(int b) const {
    const auto& [line, column] = body_where[static_cast<std::size_t>(b)];
    return {body_file, line, column};
  }
  /// "bodies[2].q" or "bodies[2].x"
  std::string body_position(int b) const {
    return "bodies[" + std::to_string(b + 1) + "]." + (body_chart[static_cast<std::size_t>(b)] ? "q" : "x");
  }
};

class SceneReader {
 public:
  SceneReader(const toml::table& root, const std::string& file) : root_(root, "", file), file_(file) {}

  Scene read() {
    static constexpr std::array keys = {"name"sv, "space"sv, "bodies"sv, "potential"sv,
                                        "integrator"sv, "thermostat"sv, "exact"sv};
    root_.allow_only(keys, "the scene");
    scene_.source = file_;
    scene_.name = read_name();
    read_space();
    read_bodies();
    read_potentials();
    read_integrator();
    read_thermostat_table();
    check_far_reach();  // (beyond it, the distances check_bodies_apart measures mean nothing)
    check_bodies_apart();
    read_exact();
    return std::move(scene_);
  }

 private:
  std::string read_name() {
    if (!root_.has("name")) return std::filesystem::path(file_).stem().string();
    const std::string name = root_.string("name", "a string (the scene's name)");
    if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos ||
        name.find('\0') != std::string::npos) {
      root_.fail("name", "expected a non-empty name without '/' (it names the output directory), got '" +
                             cut_input(name) + "'");
    }
    return name;
  }

  void read_space() {
    const toml::table* table = root_.table("space");
    if (!table) root_.missing("space", "a table [space] with kind and dim");
    const TableReader space(*table, "space", file_);
    static constexpr std::array curved_keys = {"kind"sv, "dim"sv, "radius"sv};
    static constexpr std::array hyperbolic_keys = {"kind"sv, "dim"sv, "radius"sv, "genus"sv};
    static constexpr std::array flat_keys = {"kind"sv, "dim"sv, "box"sv};
    static constexpr std::array any_keys = {"kind"sv, "dim"sv, "radius"sv, "box"sv, "genus"sv};
    if (!space.has("kind")) {
      space.allow_only(any_keys, "[space]");
      space.missing("kind", one_of(space_kinds));
    }
    const std::string kind = space.string("kind", "a string");
    if (kind == "sphere") {
      scene_.space.kind = SpaceKind::sphere;
    } else if (kind == "hyperbolic") {
      scene_.space.kind = SpaceKind::hyperbolic;
    } else if (kind == "euclidean") {
      scene_.space.kind = SpaceKind::euclidean;
    } else {
      space.fail("kind", "unknown space kind '" + cut_input(kind) + "'" + did_you_mean(kind, space_kinds) +
                             " (expected " + one_of(space_kinds) + ")");
    }
    const bool euclidean = scene_.space.kind == SpaceKind::euclidean;
    const bool hyperbolic = scene_.space.kind == SpaceKind::hyperbolic;
    // A topology key of another space: say which space takes it (check_box, check_genus).
    if (!euclidean && space.has("box")) {
      check_box({}, scene_.space.kind, 0, space.origin_of("box"), space.key_path("box"));
    }
    if (!hyperbolic && space.has("genus")) {
      check_genus(0, scene_.space.kind, 0, space.origin_of("genus"), space.key_path("genus"));
    }
    if (euclidean) {
      space.allow_only(flat_keys, "[space] of kind euclidean");
    } else if (hyperbolic) {
      space.allow_only(hyperbolic_keys, "[space]");
    } else {
      space.allow_only(curved_keys, "[space]");
    }
    const long dim = space.integer("dim", "an integer from 1 to " + std::to_string(max_dim));
    if (dim < 1 || dim > max_dim) {
      space.fail("dim", "expected an integer from 1 to " + std::to_string(max_dim) + ", got " +
                            std::to_string(dim));
    }
    scene_.space.dim = static_cast<int>(dim);
    if (!euclidean) {
      scene_.space.radius = space.number_or("radius", 1.0, "a finite number > 0");
      check_radius(scene_.space.radius, space.origin_of("radius"), space.key_path("radius"));
    }
    if (euclidean && space.has("box")) {
      // (Sized by the reader first, so that a wrong length names the array and each bad edge its place.)
      const Eigen::VectorXd box = space.vector("box", scene_.space.dim, "the box's edges L_1..L_n, one per axis");
      scene_.space.box.assign(box.data(), box.data() + box.size());
      check_box(scene_.space.box, scene_.space.kind, scene_.space.dim, space.origin_of("box"), space.key_path("box"));
    }
    if (hyperbolic && space.has("genus")) {
      const long genus = space.integer("genus", "an integer from 2 to " +
                                                    std::to_string(sesi::HyperbolicSurface<double>::max_genus) +
                                                    " (a compact surface's genus)");
      check_genus(genus, scene_.space.kind, scene_.space.dim, space.origin_of("genus"), space.key_path("genus"));
      scene_.space.genus = static_cast<int>(genus);
    }
    geometry_.emplace(scene_.space);
  }

  void read_bodies() {
    const toml::node* node = root_.get("bodies");
    if (node && node->is_string()) {
      read_body_file(root_.string("bodies", "the path of a bodies file (CSV)"));
      return;
    }
    if (node && !(node->is_array() && node->as_array()->is_array_of_tables())) {
      root_.fail("bodies", "expected an array of tables [[bodies]] or the path of a bodies file (CSV), got " +
                               std::string(type_name(*node)));
    }
    const auto tables = root_.tables("bodies");
    if (tables.empty()) root_.missing("bodies", "at least one [[bodies]] table");
    provenance_.body_file = file_;
    for (std::size_t b = 0; b < tables.size(); ++b) {
      static constexpr std::array keys = {"mass"sv, "q"sv, "p"sv, "x"sv, "v"sv};
      const TableReader table(*tables[b], "bodies[" + std::to_string(b + 1) + "]", file_);
      table.allow_only(keys, "[[bodies]]");
      read_body(TableBody(table));
    }
  }

  /// bodies = "FILE.csv": the bodies, one a row, read line by line (docs/scene-format.md, "Bodies
  /// from a file"); the path is relative to the scene file's directory (to the current directory
  /// for a scene without a file).
  void read_body_file(const std::string& given) {
    if (given.empty()) root_.fail("bodies", "expected the path of a bodies file (CSV), got an empty string");
    const std::string file = (std::filesystem::path(file_).parent_path() / given).string();
    std::error_code ec;
    if (std::filesystem::is_directory(file, ec)) {
      root_.fail("bodies", "expected a bodies file (CSV), got the directory '" + cut_input(file) + "'");
    }
    std::ifstream in(file, std::ios::binary);
    if (!in) {
      root_.fail("bodies", "cannot read the bodies file '" + cut_input(file) + "': " + std::strerror(errno));
    }
    provenance_.body_file = file;
    std::optional<BodyColumns> columns;
    // One line at a time, in a buffer of max_body_line bytes (a device or a file without line
    // ends is refused, not read whole).
    std::vector<char> buffer(max_body_line + 1);
    std::vector<std::string_view> fields;
    std::vector<double> values;
    int number = 0;
    for (bool more = true; more;) {
      in.getline(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      const std::streamsize got = in.gcount();
      if (in.bad()) {
        throw InputError(Origin{file, number + 1}, "bodies",
                         "cannot read the bodies file: " + std::string(std::strerror(errno)));
      }
      if (in.fail() && !in.eof()) {
        throw InputError(Origin{file, number + 1}, "bodies",
                         "a line longer than " + std::to_string(max_body_line) + " bytes; at most that many are allowed");
      }
      more = !in.eof();
      if (got == 0 && !more) break;
      std::string_view line(buffer.data(), static_cast<std::size_t>(got - (more ? 1 : 0)));
      if (number == std::numeric_limits<int>::max()) {
        throw InputError(Origin{file}, "bodies", "more than 2^31 - 1 lines; at most that many are allowed");
      }
      if (++number == 1 && line.starts_with("\xEF\xBB\xBF")) line.remove_prefix(3);  // a byte-order mark
      split_fields(line, fields);
      if ((fields.size() == 1 && fields[0].empty()) || fields[0].starts_with('#')) continue;  // blank, comment
      const auto column_of = [&](std::size_t f) { return static_cast<int>(fields[f].data() - line.data()) + 1; };
      if (!columns) {
        columns = read_body_columns(fields, file, number, column_of);
        continue;
      }
      const int index = scene_.body_count() + 1;
      if (static_cast<int>(fields.size()) != columns->count) {
        throw InputError(Origin{file, number}, "bodies[" + std::to_string(index) + "]",
                         "expected " + std::to_string(columns->count) + " fields (the header's columns), got " +
                             std::to_string(fields.size()));
      }
      values.resize(fields.size());
      for (std::size_t f = 0; f < fields.size(); ++f) {
        // Exact: the nearest double to the decimal text (a %.17g or repr() value reads back as written).
        const char* end = fields[f].data() + fields[f].size();
        const auto [ptr, error] = std::from_chars(fields[f].data(), end, values[f]);
        if (error != std::errc{} || ptr != end || !std::isfinite(values[f])) {
          throw InputError(Origin{file, number, column_of(f)},
                           "bodies[" + std::to_string(index) + "]." + columns->names[f],
                           "expected a finite number, got '" + cut_input(fields[f]) + "'");
        }
      }
      read_body(RowBody(*columns, values, file, number, index));
    }
    if (!columns) {
      throw InputError(Origin{file}, "bodies",
                       "no header line (expected the column names, e.g. mass," + axis_names("x") + ")");
    }
    if (scene_.bodies.empty()) {
      throw InputError(Origin{file}, "bodies", "no rows after the header (expected at least one body)");
    }
  }

  /// "x1,x2,x3" for the space's ambient dimension (or q's dimension).
  std::string axis_names(std::string_view key) const {
    const int size = key == "q" || key == "p" ? scene_.dim() : geometry_->ambient_dim();
    std::string out;
    for (int k = 1; k <= size; ++k) out += (k > 1 ? "," : "") + std::string(key) + std::to_string(k);
    return out;
  }
  /// "q1..q3" (or "q1" in one dimension)
  std::string axis_range(std::string_view key) const {
    const int size = key == "q" || key == "p" ? scene_.dim() : geometry_->ambient_dim();
    const std::string k(key);
    return size == 1 ? k + "1" : k + "1.." + k + std::to_string(size);
  }

  /// The header of a bodies file: mass, then q1..qn (p1..pn optional) or x1..xa (v1..va
  /// optional), a the ambient dimension, in any order.
  template <class ColumnOf>
  BodyColumns read_body_columns(const std::vector<std::string_view>& fields, const std::string& file, int line,
                                const ColumnOf& column_of) const {
    const int n = scene_.dim(), a = geometry_->ambient_dim();
    BodyColumns out;
    out.count = static_cast<int>(fields.size());
    for (std::size_t k = 0; k < 4; ++k) out.fields[k].assign(static_cast<std::size_t>(k < 2 ? n : a), -1);
    std::vector<int> where;  // each name's column, for "given twice"
    for (std::size_t f = 0; f < fields.size(); ++f) {
      const std::string_view name = fields[f];
      const Origin at{file, line, column_of(f)};
      int* slot = nullptr;
      if (name == "mass") {
        slot = &out.mass;
      } else if (!name.empty()) {
        const auto v = std::find(BodyColumns::vectors.begin(), BodyColumns::vectors.end(), name.substr(0, 1));
        int axis = 0;
        const char* end = name.data() + name.size();
        if (v != BodyColumns::vectors.end() && name.size() > 1 && name[1] != '0') {
          const auto [ptr, error] = std::from_chars(name.data() + 1, end, axis);
          const std::size_t kind = static_cast<std::size_t>(v - BodyColumns::vectors.begin());
          if (error == std::errc{} && ptr == end && axis >= 1 && axis <= (kind < 2 ? n : a)) {
            slot = &out.fields[kind][static_cast<std::size_t>(axis - 1)];
          }
        }
      }
      if (!slot) {
        if (name.empty()) throw InputError(at, "", "a column without a name in the bodies file's header");
        std::vector<std::string> names = {"mass"};
        for (std::string_view key : BodyColumns::vectors) {
          const int size = key == "q" || key == "p" ? n : a;
          for (int k = 1; k <= size; ++k) names.push_back(std::string(key) + std::to_string(k));
        }
        const std::vector<std::string_view> candidates(names.begin(), names.end());
        const std::string hint = did_you_mean(name, candidates);
        throw InputError(at, cut_input(name),
                         "unknown column in the bodies file" +
                             (hint.empty() ? " (expected mass, " + axis_range("q") + ", " + axis_range("p") + ", " +
                                                 axis_range("x") + " or " + axis_range("v") + ")"
                                           : hint));
      }
      if (*slot >= 0) {
        throw InputError(at, cut_input(name),
                         "column given twice (also column " + std::to_string(where[static_cast<std::size_t>(*slot)]) +
                             " of the header)");
      }
      *slot = static_cast<int>(f);
      where.push_back(at.column);
      out.names.emplace_back(name);
    }
    const Origin header{file, line};
    if (out.mass < 0) throw InputError(header, "mass", "missing required column (the bodies' masses)");
    const auto given = [&](std::size_t k) {
      return std::count_if(out.fields[k].begin(), out.fields[k].end(), [](int f) { return f >= 0; });
    };
    const auto first = [&](std::size_t k) {  // the first column of q, p, x or v given, for messages
      const int f = *std::min_element(out.fields[k].begin(), out.fields[k].end(), [](int i, int j) {
        return (i < 0 ? INT_MAX : i) < (j < 0 ? INT_MAX : j);
      });
      return std::pair{Origin{file, line, where[static_cast<std::size_t>(f)]}, out.names[static_cast<std::size_t>(f)]};
    };
    const bool chart = given(0) > 0, embedded = given(2) > 0;
    if (chart && embedded) {
      const auto [at, name] = first(2);
      throw InputError(at, name, "give either " + axis_range("q") + " (with " + axis_range("p") + ") or " +
                                     axis_range("x") + " (with " + axis_range("v") + "), not both");
    }
    if (!chart && !embedded) {
      throw InputError(header, "q1", "missing required columns: the position, " + axis_range("q") +
                                         " (chart coordinates) or " + axis_range("x") + " (embedding point)");
    }
    if (chart && given(3) > 0) {
      const auto [at, name] = first(3);
      throw InputError(at, name, axis_range("v") + " (an embedding velocity) go with " + axis_range("x") +
                                     "; with " + axis_range("q") + " give the momenta " + axis_range("p"));
    }
    if (embedded && given(1) > 0) {
      const auto [at, name] = first(1);
      throw InputError(at, name, axis_range("p") + " (chart momenta) go with " + axis_range("q") + "; with " +
                                     axis_range("x") + " give the velocity " + axis_range("v"));
    }
    // Each vector whole or (p, v) absent.
    for (std::size_t k = 0; k < 4; ++k) {
      if (given(k) == 0) {
        out.fields[k].clear();
        continue;
      }
      const auto missing = std::find(out.fields[k].begin(), out.fields[k].end(), -1);
      if (missing != out.fields[k].end()) {
        const std::string key(BodyColumns::vectors[k]);
        throw InputError(header, key + std::to_string(missing - out.fields[k].begin() + 1),
                         "missing column (" + axis_range(key) + (k % 2 == 0 ? " are required" : ": all or none") + ")");
      }
    }
    return out;
  }

  void read_body(const BodyInput& body) {
    const Geometry& g = *geometry_;
    Body out;
    out.mass = body.number("mass", "a finite number > 0");
    check_mass(out.mass, body.origin_of("mass"), body.key_path("mass"));

    const bool chart = body.has("q"), embedded = body.has("x");
    if (chart && embedded) {
      body.fail("x", "give either q (with p) or x (with v), not both");
    }
    if (!chart && !embedded) {
      body.missing("q", "the position: q (chart coordinates) or x (embedding point)");
    }
    const int n = g.dim(), a = g.ambient_dim();
    const std::string space = space_noun();
    if (chart) {
      if (body.has("v")) body.fail("v", "v (an embedding velocity) goes with x; with q give the momenta p");
      out.q = body.vector("q", n, "chart coordinates");
      if (const auto bad = g.outside_domain(out.q)) {
        body.fail("q", "q[" + std::to_string(bad->first + 1) + "] = " + format_number(out.q[bad->first]) +
                           " is outside the chart's domain: expected " + bad->second);
      }
      out.p = body.has("p") ? body.vector("p", n, "conjugate momenta") : Eigen::VectorXd::Zero(n);
    } else {
      if (body.has("p")) body.fail("p", "p (chart momenta) goes with q; with x give the velocity v");
      const Eigen::VectorXd x = body.vector("x", a, "a point of the " + space);
      const double off = g.constraint_residual(x);
      if (off > on_space_tolerance) {
        body.fail("x", "not on the " + space + ": relative residual " + format_short(off) + " > " +
                           format_number(on_space_tolerance) + residual_hint());
      }
      if (!g.on_upper_sheet(x)) {
        body.fail("x", "not on the hyperboloid's upper sheet: the last coordinate must be > 0");
      }
      const Eigen::VectorXd v = body.has("v") ? body.vector("v", a, "a tangent vector at x")
                                              : Eigen::VectorXd::Zero(a);
      const double slant = g.tangency_residual(x, v);
      if (slant > on_space_tolerance) {
        body.fail("v", "not tangent to the " + space + " at x: relative residual " + format_short(slant) +
                           " > " + format_number(on_space_tolerance) + tangency_hint());
      }
      g.to_chart(x, v, out.mass, out.q, out.p);
    }
    if (!std::isfinite(g.kinetic_energy(out.q, out.p, out.mass))) {
      const std::string position_key = body.key_path(chart ? "q" : "x");
      // A singular point is one where the inverse metric itself is not finite (unit momenta give
      // an infinite kinetic energy); anywhere else, the momenta are too large for double.
      if (!std::isfinite(g.kinetic_energy(out.q, Eigen::VectorXd::Ones(n), 1.0))) {
        throw InputError(body.origin_of(chart ? "q" : "x"), position_key,
                         "the body sits on a singular point of the chart (a pole of the sphere or the "
                         "origin of hyperbolic space), where its kinetic energy is not finite; move it "
                         "off that point");
      }
      // p (or v) is given here: with zero momenta the kinetic energy is 0 or NaN, not inf.
      const std::string_view speed = chart ? "p" : "v";
      throw InputError(body.origin_of(speed), body.key_path(speed),
                       std::string("too large: the kinetic energy overflows (exceeds the largest double, "
                                   "1.8e308) with ") +
                           (chart ? "these momenta" : "this velocity") + " and mass " + format_number(out.mass) +
                           "; use smaller values or other units");
    }
    scene_.bodies.push_back(std::move(out));
    provenance_.add_body(body.origin(), chart);
  }

  /// "sphere", "hyperboloid", "Euclidean space" (what points lie on).
  std::string space_noun() const {
    switch (scene_.space.kind) {
      case SpaceKind::sphere: return "sphere";
      case SpaceKind::hyperbolic: return "hyperboloid";
      case SpaceKind::euclidean: break;
    }
    return "Euclidean space";
  }

  std::string residual_hint() const {
    switch (scene_.space.kind) {
      case SpaceKind::sphere: return " (|x| must equal the radius)";
      case SpaceKind::hyperbolic: return " (x_1^2 + ... + x_n^2 - x_{n+1}^2 must equal -radius^2)";
      case SpaceKind::euclidean: break;
    }
    return "";
  }
  std::string tangency_hint() const {
    return scene_.space.kind == SpaceKind::hyperbolic ? " (the Minkowski product <x, v> must be 0)"
                                                      : " (x . v must be 0)";
  }

  void read_potentials() {
    const auto tables = root_.tables("potential");
    for (std::size_t k = 0; k < tables.size(); ++k) {
      const TableReader term(*tables[k], "potential[" + std::to_string(k + 1) + "]", file_);
      scene_.potentials.push_back(read_potential(term));
      provenance_.potentials.push_back(term.origin());
      check_topology_potential(scene_.potentials.back(), scene_.space, place(term));
    }
  }

  PotentialSpec read_potential(const TableReader& term) {
    if (!term.has("kind")) {
      static constexpr std::array any_keys = {"kind"sv,    "theta0"sv,  "strength"sv, "G"sv,
                                              "k"sv,       "center"sv,  "d0"sv,       "epsilon"sv,
                                              "sigma"sv,   "cutoff"sv,  "min_distance"sv};
      term.allow_only(any_keys, "[[potential]]");
      term.missing("kind", "one of " + one_of(potential_kinds));
    }
    const std::string kind = term.string("kind", "a string");
    if (kind == "chord-well") {
      term.allow_only(chord_well_keys, "a chord-well potential");
      ChordWellSpec spec{term.number("theta0", "a finite angle in [0, pi]"),
                         term.number_or("strength", 2.0, "a finite number")};
      check_potential(spec, place(term));
      return spec;
    }
    if (kind == "cotangent-gravity") {
      term.allow_only(cotangent_gravity_keys, "a cotangent-gravity potential");
      return CotangentGravitySpec{term.number_or("G", 1.0, "a finite number"), min_distance(term)};
    }
    if (kind == "central-cotangent") {
      term.allow_only(central_cotangent_keys, "a central-cotangent potential");
      CentralCotangentSpec spec{term.number_or("k", 1.0, "a finite number"),
                                term.vector("center", geometry_->ambient_dim(), "a point of the space"),
                                min_distance(term)};
      const double off = geometry_->constraint_residual(spec.center);
      if (off > on_space_tolerance || !geometry_->on_upper_sheet(spec.center)) {
        term.fail("center", "not on the " + space_noun() + ": relative residual " + format_short(off) +
                                residual_hint());
      }
      return spec;
    }
    if (kind == "harmonic-pair") {
      term.allow_only(harmonic_pair_keys, "a harmonic-pair potential");
      HarmonicPairSpec spec{term.number_or("k", 1.0, "a finite number"),
                            term.number_or("d0", 0.0, "a finite distance >= 0")};
      check_potential(spec, place(term));
      return spec;
    }
    if (kind == "lennard-jones") {
      term.allow_only(lennard_jones_keys, "a lennard-jones potential");
      LennardJonesSpec spec{term.number_or("epsilon", 1.0, "a finite number >= 0"),
                            term.number_or("sigma", 1.0, "a finite number > 0"), 0.0, min_distance(term)};
      spec.cutoff = term.number_or("cutoff", 2.5 * spec.sigma, "a finite distance > 0");
      check_potential(spec, place(term));
      return spec;
    }
    term.fail("kind", "unknown potential kind '" + cut_input(kind) + "'" + did_you_mean(kind, potential_kinds) +
                          " (expected " + one_of(potential_kinds) + ")");
  }

  /// Where check_potential's failures point: the key in the term's table.
  static KeyPlace place(const TableReader& term) {
    return [&term](std::string_view key) { return std::pair{term.origin_of(key), term.key_path(key)}; };
  }

  /// A singular term's close-encounter floor: min_distance, or -1 for the library's default.
  static double min_distance(const TableReader& term) {
    if (!term.has("min_distance")) return -1.0;
    const double d = term.number("min_distance", "a finite distance >= 0");
    check_min_distance(d, term.origin_of("min_distance"), term.key_path("min_distance"));
    return d;
  }

  void read_integrator() {
    const toml::table* table = root_.table("integrator");
    if (!table) return;  // every setting may come from the command line
    const TableReader in(*table, "integrator", file_);
    scene_.integrator.line = in.origin().line;
    static constexpr std::array keys = {"method"sv,       "dt"sv,          "t_end"sv,
                                        "output_every"sv, "energy_guard"sv, "threads"sv,
                                        "check_every"sv,  "trajectory_format"sv, "neighbour_skin"sv,
                                        "checkpoint_every"sv, "tolerance"sv};
    in.allow_only(keys, "[integrator]");
    IntegratorSpec& spec = scene_.integrator;
    if (in.has("method")) {
      spec.method = in.string("method", "a method name or \"auto\"");
      check_method_or_auto(spec.method, in.origin_of("method"), in.key_path("method"));
      check_topology_method(scene_, in.origin_of("method"), in.key_path("method"));
      method_origin_ = in.origin_of("method");
    }
    if (in.has("tolerance")) {
      spec.tolerance = in.number("tolerance", "a max relative energy error");
      check_tolerance(*spec.tolerance, in.origin_of("tolerance"), in.key_path("tolerance"));
      if (in.has("method") && spec.method != "auto") {
        in.fail("tolerance", "only with method = \"auto\" (the method and step are then chosen to "
                             "meet it); method is \"" + spec.method + "\"");
      }
    }
    if (in.has("dt")) {
      spec.dt = in.number("dt", "a finite, non-zero step");
      check_dt(*spec.dt, in.origin_of("dt"), in.key_path("dt"));
    }
    if (in.has("t_end")) {
      spec.t_end = in.number("t_end", "a finite end time >= 0");
      check_t_end(*spec.t_end, in.origin_of("t_end"), in.key_path("t_end"));
    }
    if (in.has("output_every")) {
      spec.output_every = in.integer("output_every", "an integer >= 1");
      check_output_every(spec.output_every, in.origin_of("output_every"), in.key_path("output_every"));
    }
    if (in.has("threads")) {
      const long threads = in.integer("threads", "an integer >= 0 (0: all cores)");
      check_threads(threads, in.origin_of("threads"), in.key_path("threads"));
      spec.threads = static_cast<int>(threads);
    }
    if (in.has("check_every")) {
      spec.check_every = in.integer("check_every", "an integer >= 1");
      check_check_every(spec.check_every, in.origin_of("check_every"), in.key_path("check_every"));
    }
    if (in.has("checkpoint_every")) {
      spec.checkpoint_every = in.integer("checkpoint_every", "an integer >= 1");
      check_checkpoint_every(spec.checkpoint_every, in.origin_of("checkpoint_every"),
                             in.key_path("checkpoint_every"));
    }
    if (in.has("neighbour_skin")) {
      spec.neighbour_skin = in.number("neighbour_skin", "a number from 0 to 1");
      check_neighbour_skin(spec.neighbour_skin, in.origin_of("neighbour_skin"), in.key_path("neighbour_skin"));
    }
    if (in.has("trajectory_format")) {
      spec.trajectory_format = parse_trajectory_format(in.string("trajectory_format", "\"csv\" or \"h5md\""),
                                                       in.origin_of("trajectory_format"),
                                                       in.key_path("trajectory_format"));
    }
    if (in.has("energy_guard")) {
      // false turns the guard off; a number is the threshold on the relative energy error.
      const toml::node* node = in.get("energy_guard");
      if (const auto* flag = node->as_boolean(); flag && !flag->get()) {
        spec.energy_guard = 0.0;
      } else if (flag) {
        in.fail("energy_guard", "expected a finite threshold > 0 or false, got true (the guard is on by "
                                "default; give a threshold to change it)");
      } else {
        spec.energy_guard = in.number("energy_guard", "a finite threshold > 0 or false");
        check_energy_guard(*spec.energy_guard, in.origin_of("energy_guard"), in.key_path("energy_guard"));
      }
    }
    if (spec.dt && spec.t_end) check_step_count(*spec.t_end, *spec.dt, in.origin(), in.path());
  }

  /// [thermostat]: with it, the method is sesi2 unless the scene names one (which must then be
  /// sesi2 or auto: check_thermostat_method).
  void read_thermostat_table() {
    const toml::table* table = root_.table("thermostat");
    if (!table) return;
    scene_.thermostat = read_thermostat(TableReader(*table, "thermostat", file_));
    if (!method_origin_) {
      scene_.integrator.method = "sesi2";
      return;
    }
    check_thermostat_method(scene_, *method_origin_, "integrator.method");
  }

  /// No two bodies (or a body and a center) where a potential is singular.
  void check_bodies_apart() {
    const Geometry& g = *geometry_;
    const int count = scene_.body_count();
    const double scale = g.length_scale();
    const bool sphere = scene_.space.kind == SpaceKind::sphere;
    const double antipodal = std::numbers::pi * scene_.space.radius;
    // The embedding points once, as columns (no vector per body besides: 10^6 bodies and more).
    Eigen::MatrixXd points(g.ambient_dim(), count);
    for (int i = 0; i < count; ++i) points.col(i) = g.embed(scene_.bodies[static_cast<std::size_t>(i)].q);
    const auto x = [&points](int i) -> Eigen::VectorXd { return points.col(i); };
    for (std::size_t k = 0; k < scene_.potentials.size(); ++k) {
      const PotentialSpec& spec = scene_.potentials[k];
      const std::string term = std::string(potential_kind(spec)) + " potential (potential[" +
                               std::to_string(k + 1) + "])";
      if (const auto* center = std::get_if<CentralCotangentSpec>(&spec)) {
        for (int i = 0; i < count; ++i) {
          const double d = g.distance(x(i), center->center);
          if (d <= same_point_tolerance * scale) body_error(i, "at the center of the " + term + ", where it is singular");
          if (sphere && d >= antipodal * (1 - same_point_tolerance)) {
            body_error(i, "antipodal to the center of the " + term + ", where it is singular");
          }
          check_floor(spec, i, d, "the center", term);
        }
        continue;
      }
      const bool singular_at_contact = !std::holds_alternative<HarmonicPairSpec>(spec);
      const bool cotangent_on_sphere = std::holds_alternative<CotangentGravitySpec>(spec) && sphere;
      const auto check_pair = [&](int i, int j) {
        const double d = g.distance(x(i), x(j));
        if (singular_at_contact && d <= same_point_tolerance * scale) {
          body_error(j, "at the same point as bodies[" + std::to_string(i + 1) + "], where the " + term +
                            " is singular");
        }
        if (cotangent_on_sphere && d >= antipodal * (1 - same_point_tolerance)) {
          body_error(j, "antipodal to bodies[" + std::to_string(i + 1) + "], where the " + term + " is singular");
        }
        check_floor(spec, j, d, "bodies[" + std::to_string(i + 1) + "]", term);
        if (std::holds_alternative<ChordWellSpec>(spec)) {
          // s = chord / (sqrt(3) R) must stay below 1 (the well's square root).
          const double kappa = sphere ? 1 / (scale * scale) : scene_.space.kind == SpaceKind::hyperbolic ? -1 / (scale * scale) : 0.0;
          const double chord = 2 * sesi::special::sn(kappa, d / 2);
          const double s = chord / (std::numbers::sqrt3 * scale);
          if (!(s < 1.0)) {
            body_error(j, "too far from bodies[" + std::to_string(i + 1) + "] for the " + term +
                              ": chord " + format_number(chord) + ", expected < sqrt(3) * " +
                              (sphere || scene_.space.kind == SpaceKind::hyperbolic ? "radius" : "1"));
          }
        }
      };
      if (std::holds_alternative<ChordWellSpec>(spec)) {
        // The well bounds every pair from above: all pairs (chord-well scenes are small).
        for (int j = 1; j < count; ++j) {
          for (int i = 0; i < j; ++i) check_pair(i, j);
        }
        continue;
      }
      // Only pairs near contact (or near antipodal) can fail: find them through the neighbour
      // index, and check them in the order of the all-pairs loop (j, then i), so that the first
      // error reported is the same.
      const double floor = encounter_floor(spec, scale);
      const double near = 2 * std::max(same_point_tolerance * scale, floor) + 1e-300;
      std::vector<std::pair<int, int>> candidates;  // (j, i)
      for (const auto& [i, j] : g.close_pairs(points, near)) candidates.emplace_back(j, i);
      if (cotangent_on_sphere) {
        const double gap = 2 * std::max(antipodal * same_point_tolerance, floor) + 1e-300;
        for (const auto& [i, j] : g.close_pairs(points, gap, /*antipodal=*/true)) candidates.emplace_back(j, i);
      }
      std::sort(candidates.begin(), candidates.end());
      candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
      for (const auto& [j, i] : candidates) check_pair(i, j);
    }
  }

  /// H^n, n >= 2: bodies and force centres must lie where their coordinates resolve them
  /// (check_far_resolution, validate.hpp).
  void check_far_reach() const {
    if (scene_.space.kind != SpaceKind::hyperbolic || scene_.dim() < 2) return;
    const Geometry& g = *geometry_;
    for (int b = 0; b < scene_.body_count(); ++b) {
      check_far_resolution(g.radii_from_origin(g.embed(scene_.bodies[static_cast<std::size_t>(b)].q)), scene_.dim(),
                           provenance_.body_origin(b), provenance_.body_position(b));
    }
    for (std::size_t k = 0; k < scene_.potentials.size(); ++k) {
      if (const auto* central = std::get_if<CentralCotangentSpec>(&scene_.potentials[k])) {
        check_far_resolution(g.radii_from_origin(central->center), scene_.dim(), provenance_.potentials[k],
                             "potential[" + std::to_string(k + 1) + "].center");
      }
    }
  }

  /// A body starting below a singular term's close-encounter floor would stop the run at its
  /// first step (exit 3); it is bad input instead.
  void check_floor(const PotentialSpec& spec, int b, double d, const std::string& other,
                   const std::string& term) const {
    const double floor = encounter_floor(spec, geometry_->length_scale());
    const double gap = singular_gap(spec, scene_.space.kind, scene_.space.radius, d);
    if (floor > 0.0 && gap < floor) {
      body_error(b, "within " + format_short(gap) + " of " + other + (gap < d ? "'s antipode" : "") +
                        ", below the close-encounter floor " + format_short(floor) + " of the " + term +
                        " (min_distance; docs/stability.md)");
    }
  }

  [[noreturn]] void body_error(int b, const std::string& message) const {
    throw InputError(provenance_.body_origin(b), provenance_.body_position(b), message);
  }

  void read_exact() {
    if (!root_.has("exact")) return;
    const std::string exact = root_.string("exact", "a string");
    if (exact != "paper") {
      root_.fail("exact", "unknown exact solution '" + cut_input(exact) + "'" + did_you_mean(exact, exact_solutions) +
                              " (expected " + one_of(exact_solutions) + ")");
    }
    if (const std::string mismatch = paper_scene_mismatch(scene_); !mismatch.empty()) {
      root_.fail("exact", "the 'paper' solution is exact only for the seed's scene, but " + mismatch);
    }
    scene_.exact = ExactSolution::paper;
  }

  static constexpr int max_dim = 1000;
  /// The longest line of a bodies file: a row of dim max_dim holds at most 4 (max_dim + 1) + 1
  /// numbers, about 100 KB at 25 bytes each.
  static constexpr std::size_t max_body_line = std::size_t{1} << 20;

  TableReader root_;
  const std::string& file_;
  Scene scene_;
  std::optional<Geometry> geometry_;
  Provenance provenance_;
  std::optional<Origin> method_origin_;  ///< where [integrator] method was given
};

}  // namespace

std::span<const PotentialInfo> potential_catalogue() {
  // The defaults and energies as docs/scene-format.md states them.
  static const std::array<PotentialInfo, 5> catalogue = {{
      {"chord-well", chord_well_keys, "theta0 (required, in [0, pi]), strength = 2",
       "strength * sum over pairs i<j of the seed's well of the chord"},
      {"cotangent-gravity", cotangent_gravity_keys, "G = 1, min_distance = R eps^(1/3)",
       "-G sum_(i<j) m_i m_j ctn(d_ij)"},
      {"central-cotangent", central_cotangent_keys,
       "k = 1, center (required, an embedding point), min_distance = R eps^(1/3)",
       "-k sum_i m_i ctn(d(x_i, center))"},
      {"harmonic-pair", harmonic_pair_keys, "k = 1, d0 = 0", "sum_(i<j) k/2 (d_ij - d0)^2"},
      {"lennard-jones", lennard_jones_keys,
       "epsilon = 1, sigma = 1, cutoff = 2.5 sigma, min_distance = sigma eps^(1/3)",
       "sum_(i<j) 4 epsilon ((sigma/d)^12 - (sigma/d)^6), shifted to 0 at the cutoff"},
  }};
  return catalogue;
}

Scene read_scene_table(const toml::table& root, const std::string& source) {
  return SceneReader(root, source).read();
}

ThermostatSpec read_thermostat_table(const toml::table& table, const std::string& source) {
  return read_thermostat(TableReader(table, "thermostat", source));
}

Scene read_scene_text(std::string_view text, const std::string& path) {
  // Size, key parts and nesting first: toml++ recurses once per level (scene_limits.hpp).
  check_scene_limits(text, path);
  std::string shielded;
  if (const auto where = shield_from_toml_bug(text, shielded)) {
    throw InputError(Origin{path, where->first, where->second}, "",
                     "private-use characters U+F0000 to U+F0BFF are not allowed in a scene file");
  }
  toml::table root;
  try {
    root = toml::parse(shielded, path);
  } catch (const toml::parse_error& e) {
    const auto& where = e.source().begin;
    throw InputError(Origin{path, static_cast<int>(where.line), static_cast<int>(where.column)}, "",
                     "TOML syntax error: " + cut_quoted(unshield(e.description())));
  }
  return SceneReader(root, path).read();
}

Scene read_scene_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(Origin{path}, "", "expected a scene file, got a directory");
  }
  const auto too_large = [&] {
    return InputError(Origin{path}, "",
                      "the scene file has more than " + std::to_string(max_scene_bytes) +
                          " bytes (1 GiB); at most that many are allowed");
  };
  std::uintmax_t size = 0;  // known for a regular file, 0 otherwise
  if (std::filesystem::is_regular_file(path, ec)) {
    size = std::filesystem::file_size(path, ec);
    if (ec) size = 0;
  }
  if (size > max_scene_bytes) throw too_large();
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw InputError(Origin{path}, "", std::string("cannot read the scene file: ") + std::strerror(errno));
  }
  // Read at most one byte past the limit, so that a device or a pipe without end is refused too.
  std::string text;
  text.reserve(static_cast<std::size_t>(size));
  std::array<char, 1 << 16> chunk{};
  while (in.read(chunk.data(), chunk.size()) || in.gcount() > 0) {
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
    if (text.size() > max_scene_bytes) throw too_large();
  }
  return read_scene_text(text, path);
}

}  // namespace sesi::program
