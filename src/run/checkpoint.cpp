#include "checkpoint.hpp"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <type_traits>
#include <variant>

#include <fcntl.h>
#include <unistd.h>

#include "errors.hpp"
#include "methods.hpp"
#include "signals.hpp"
#include "validate.hpp"

namespace sesi::program {

namespace {

constexpr std::string_view magic = "sesi-checkpoint";

/// FNV-1a, 64 bits (Fowler, Noll and Vo; the parameters of the IETF draft
/// draft-eastlake-fnv): catches truncation and corruption, not tampering.
std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

/// The body of a checkpoint: whitespace-separated tokens, each value after its key; doubles as
/// hex floats, strings as LENGTH:BYTES.
class Out {
 public:
  Out& key(std::string_view k) {
    if (!text_.empty()) text_ += '\n';
    text_ += k;
    return *this;
  }
  Out& num(double v) {
    char buffer[64];
    text_ += ' ';
    text_.append(buffer, std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::hex).ptr);
    return *this;
  }
  Out& integer(long long v) {
    text_ += ' ';
    text_ += std::to_string(v);
    return *this;
  }
  Out& str(std::string_view s) {
    text_ += ' ';
    text_ += std::to_string(s.size());
    text_ += ':';
    text_ += s;
    return *this;
  }
  Out& matrix(const Eigen::MatrixXd& m) {
    integer(m.rows()).integer(m.cols());
    for (Eigen::Index j = 0; j < m.cols(); ++j) {
      for (Eigen::Index i = 0; i < m.rows(); ++i) num(m(i, j));
    }
    return *this;
  }
  Out& vector(const std::vector<double>& v) {
    integer(static_cast<long long>(v.size()));
    for (const double x : v) num(x);
    return *this;
  }
  Out& vector(const Eigen::VectorXd& v) { return vector(std::vector<double>(v.data(), v.data() + v.size())); }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

/// Reads what Out wrote; any mismatch throws a Corrupt.
struct Corrupt {
  std::string what;
};
/// The state in the body is that of another version than the first line says.
struct OtherVersion {
  int written;
};

class In {
 public:
  explicit In(std::string_view text) : text_(text) {}
  void key(std::string_view k) {
    if (token() != k) throw Corrupt{"expected '" + std::string(k) + "'"};
  }
  double num() {
    const std::string_view t = token();
    double v = 0.0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v, std::chars_format::hex);
    // from_chars reads "inf" and "nan" too (an energy error may be either).
    if (ec != std::errc() || end != t.data() + t.size()) throw Corrupt{"a number is malformed"};
    return v;
  }
  long long integer(long long lo = 0, long long hi = (1LL << 62)) {
    const std::string_view t = token();
    long long v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size() || v < lo || v > hi) {
      throw Corrupt{"an integer is malformed or out of range"};
    }
    return v;
  }
  std::string str() {
    skip();
    const std::size_t colon = text_.find(':', pos_);
    if (colon == std::string_view::npos) throw Corrupt{"a string is malformed"};
    std::size_t n = 0;
    const auto [end, ec] = std::from_chars(text_.data() + pos_, text_.data() + colon, n);
    if (ec != std::errc() || end != text_.data() + colon || n > text_.size() - colon - 1) {
      throw Corrupt{"a string is malformed"};
    }
    std::string out(text_.substr(colon + 1, n));
    pos_ = colon + 1 + n;
    return out;
  }
  Eigen::MatrixXd matrix(Eigen::Index rows, Eigen::Index cols) {
    if (integer() != rows || integer() != cols) throw Corrupt{"a matrix has the wrong size"};
    Eigen::MatrixXd m(rows, cols);
    for (Eigen::Index j = 0; j < cols; ++j) {
      for (Eigen::Index i = 0; i < rows; ++i) m(i, j) = num();
    }
    return m;
  }
  std::vector<double> vector(long long max_size) {
    std::vector<double> v(static_cast<std::size_t>(integer(0, max_size)));
    for (double& x : v) x = num();
    return v;
  }
  Eigen::VectorXd eigen_vector(long long max_size) {
    const std::vector<double> v = vector(max_size);
    return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
  }
  /// Whether the next token is k; consumed if so (an optional key).
  bool optional_key(std::string_view k) {
    const std::size_t at = pos_;
    if (token() == k) return true;
    pos_ = at;
    return false;
  }
  bool at_end() {
    skip();
    return pos_ == text_.size();
  }

 private:
  void skip() {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\n')) ++pos_;
  }
  std::string_view token() {
    skip();
    const std::size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != ' ' && text_[pos_] != '\n') ++pos_;
    if (start == pos_) throw Corrupt{"it ends early"};
    return text_.substr(start, pos_ - start);
  }
  std::string_view text_;
  std::size_t pos_ = 0;
};

constexpr std::string_view space_names[] = {"sphere", "hyperbolic", "euclidean"};

void write_potential(Out& out, const PotentialSpec& spec) {
  out.key("potential").str(potential_kind(spec));
  std::visit(
      [&](const auto& s) {
        using T = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<T, ChordWellSpec>) {
          out.num(s.theta0).num(s.strength);
        } else if constexpr (std::is_same_v<T, CotangentGravitySpec>) {
          out.num(s.G).num(s.min_distance);
        } else if constexpr (std::is_same_v<T, CentralCotangentSpec>) {
          out.num(s.k).num(s.min_distance).vector(s.center);
        } else if constexpr (std::is_same_v<T, HarmonicPairSpec>) {
          out.num(s.k).num(s.d0);
        } else if constexpr (std::is_same_v<T, LennardJonesSpec>) {
          out.num(s.epsilon).num(s.sigma).num(s.cutoff).num(s.min_distance);
        } else {
          static_assert(std::is_same_v<T, FunctionExternalSpec>);
          // Code cannot be saved: scenes with a function potential (Python) take no checkpoints.
          throw std::logic_error("a scene with a function potential cannot be checkpointed");
        }
      },
      spec);
}

PotentialSpec read_potential(In& in, int ambient) {
  in.key("potential");
  const std::string kind = in.str();
  if (kind == "chord-well") {
    ChordWellSpec s{};
    s.theta0 = in.num();
    s.strength = in.num();
    return s;
  }
  if (kind == "cotangent-gravity") {
    CotangentGravitySpec s{};
    s.G = in.num();
    s.min_distance = in.num();
    return s;
  }
  if (kind == "central-cotangent") {
    CentralCotangentSpec s{};
    s.k = in.num();
    s.min_distance = in.num();
    s.center = in.eigen_vector(ambient);
    if (s.center.size() != ambient) throw Corrupt{"a center has the wrong size"};
    return s;
  }
  if (kind == "harmonic-pair") {
    HarmonicPairSpec s{};
    s.k = in.num();
    s.d0 = in.num();
    return s;
  }
  if (kind == "lennard-jones") {
    LennardJonesSpec s{};
    s.epsilon = in.num();
    s.sigma = in.num();
    s.cutoff = in.num();
    s.min_distance = in.num();
    return s;
  }
  throw Corrupt{"unknown potential kind '" + kind + "'"};
}

std::string body_text(const Checkpoint& c) {
  const Scene& scene = c.scene;
  const IntegratorSpec& in = scene.integrator;
  Out out;
  out.key("name").str(scene.name);
  out.key("source").str(scene.source);
  out.key("space").str(space_names[static_cast<int>(scene.space.kind)]).integer(scene.space.dim).num(scene.space.radius);
  const bool topology = c.file_version() == Checkpoint::topology_version;
  if (topology) out.key("topology").vector(scene.space.box).integer(scene.space.genus);  // version 4
  out.key("exact").integer(scene.exact == ExactSolution::paper ? 1 : 0);
  out.key("masses").integer(scene.body_count());
  for (const Body& b : scene.bodies) out.num(b.mass);
  out.key("potentials").integer(static_cast<long long>(scene.potentials.size()));
  for (const PotentialSpec& p : scene.potentials) write_potential(out, p);
  out.key("method").str(in.method);
  out.key("dt").num(*in.dt);
  out.key("t_end").num(*in.t_end);
  out.key("output_every").integer(in.output_every);
  out.key("energy_guard").integer(in.energy_guard ? 1 : 0).num(in.energy_guard.value_or(0.0));
  out.key("threads").integer(in.threads);
  out.key("check_every").integer(in.check_every);
  out.key("checkpoint_every").integer(in.checkpoint_every);
  out.key("neighbour_skin").num(in.neighbour_skin);
  out.key("trajectory_format").str(trajectory_format_name(in.trajectory_format));
  if (in.auto_choice) {  // method = "auto": what it picked, for the resumed run's summary
    const AutoChoice& a = *in.auto_choice;
    out.key("auto").num(a.tolerance).str(a.reason).integer(a.given_dt ? 1 : 0).num(a.given_dt.value_or(0.0));
    out.integer(a.given_output_every).num(a.pilot_t_end).integer(a.pilot_steps).num(a.pilot_seconds);
    out.num(a.predicted_error);
    out.integer(static_cast<long long>(a.candidates.size()));
    for (const AutoCandidate& c : a.candidates) {
      out.str(c.method).num(c.pilot_dt).num(c.pilot_error).num(c.dt).num(c.cost).integer(c.refined ? 1 : 0);
    }
  }
  if (scene.thermostat) {  // version 3
    const ThermostatSpec& t = *scene.thermostat;
    out.key("thermostat").str(t.kind).integer(static_cast<long long>(t.schedule.size()));
    for (const auto& [time, kT] : t.schedule) out.num(time).num(kT);
    out.num(t.gamma).num(t.tau).integer(t.chain).integer(static_cast<long long>(t.seed));
  }
  out.key("guard").num(c.guard_energy).num(c.guard_scale);
  out.key("step").integer(c.step);
  if (c.state.embedded) {  // version 2: a geodesic method's state
    out.key("x").matrix(c.state.x);
    out.key("v").matrix(c.state.v);
  } else {  // version 1: a chart method's
    out.key("q").matrix(c.state.q);
    out.key("p").matrix(c.state.p);
    out.key("frames").integer(static_cast<long long>(c.state.frames.size()));
    for (const Eigen::MatrixXd& f : c.state.frames) out.matrix(f);
    out.key("cluster").integer(c.state.clustered ? 1 : 0);
    if (c.state.clustered) out.matrix(c.state.cluster);
    if (scene.thermostat) out.key("thermostat_state").vector(c.state.thermostat);  // version 3 (or 4)
    if (topology) {  // version 4: the image record, exact integers
      const auto& n = c.state.image_counts;
      out.key("image_counts").integer(n.rows()).integer(n.cols());
      for (Eigen::Index j = 0; j < n.cols(); ++j) {
        for (Eigen::Index i = 0; i < n.rows(); ++i) out.integer(n(i, j));
      }
      out.key("words").integer(static_cast<long long>(c.state.words.size()));
      for (const std::vector<std::int16_t>& word : c.state.words) {
        out.integer(static_cast<long long>(word.size()));
        for (const std::int16_t letter : word) out.integer(letter);
      }
    }
  }
  out.key("outputs")
      .integer(static_cast<long long>(c.outputs.trajectory_bytes))
      .integer(static_cast<long long>(c.outputs.diagnostics_bytes))
      .integer(static_cast<long long>(c.outputs.exact_bytes))
      .integer(static_cast<long long>(c.outputs.trajectory_frames));
  const InvariantStats& s = c.recorder.stats;
  out.key("energy").integer(c.recorder.tracking ? 1 : 0).num(s.energy_initial).num(s.energy_final);
  out.num(s.max_abs_energy_error).num(s.max_rel_energy_error);
  out.key("momentum_initial").vector(s.momentum_initial);
  out.key("momentum_final").vector(s.momentum_final);
  out.key("momentum_drift").num(s.max_momentum_drift);
  out.key("max_distance").num(s.max_distance);
  out.key("exact_max").vector(c.recorder.exact_max_error);
  out.key("exact_last").vector(c.recorder.exact_last_error);
  if (scene.thermostat) {  // version 3
    out.key("thermostat_stats").integer(s.conserved_tracking ? 1 : 0).num(s.conserved_initial);
    out.num(s.conserved_final).num(s.max_abs_conserved_drift).integer(s.thermostat_rows);
    out.num(s.sum_kinetic_temperature).num(s.sum_grad_squared).num(s.sum_laplacian).num(s.heat);
  }
  out.key("end");
  std::string text = out.text();
  text += '\n';
  return text;
}

Checkpoint parse_body(std::string_view text, int version) {
  In in(text);
  Checkpoint c;
  Scene& scene = c.scene;
  in.key("name");
  scene.name = in.str();
  in.key("source");
  scene.source = in.str();
  in.key("space");
  const std::string kind = in.str();
  bool known = false;
  for (int k = 0; k < 3; ++k) {
    if (kind == space_names[k]) {
      scene.space.kind = static_cast<SpaceKind>(k);
      known = true;
    }
  }
  if (!known) throw Corrupt{"unknown space kind '" + kind + "'"};
  scene.space.dim = static_cast<int>(in.integer(1, 1 << 20));
  scene.space.radius = in.num();
  const bool topology = version == Checkpoint::topology_version;
  if (topology) {  // version 4: a box or a genus (check_scene_model judges them as a scene's)
    in.key("topology");
    scene.space.box = in.vector(1 << 20);
    scene.space.genus = static_cast<int>(in.integer(0, 1 << 20));
    if (scene.space.box.empty() == (scene.space.genus == 0)) throw Corrupt{"it has no topology, or two"};
  }
  in.key("exact");
  scene.exact = in.integer(0, 1) == 1 ? ExactSolution::paper : ExactSolution::none;
  const int dim = scene.space.dim;
  const int ambient = scene.space.kind == SpaceKind::euclidean ? dim : dim + 1;
  in.key("masses");
  const auto bodies = static_cast<int>(in.integer(1, 1 << 30));
  scene.bodies.resize(static_cast<std::size_t>(bodies));
  for (Body& b : scene.bodies) b.mass = in.num();
  in.key("potentials");
  const long long terms = in.integer(0, 1 << 20);
  for (long long k = 0; k < terms; ++k) scene.potentials.push_back(read_potential(in, ambient));
  IntegratorSpec& spec = scene.integrator;
  in.key("method");
  spec.method = in.str();
  in.key("dt");
  spec.dt = in.num();
  in.key("t_end");
  spec.t_end = in.num();
  in.key("output_every");
  spec.output_every = static_cast<long>(in.integer(1));
  in.key("energy_guard");
  const bool guarded = in.integer(0, 1) == 1;
  const double threshold = in.num();
  if (guarded) spec.energy_guard = threshold;
  in.key("threads");
  spec.threads = static_cast<int>(in.integer(0, 1 << 20));
  in.key("check_every");
  spec.check_every = static_cast<long>(in.integer(0));
  in.key("checkpoint_every");
  spec.checkpoint_every = static_cast<long>(in.integer(0));
  in.key("neighbour_skin");
  spec.neighbour_skin = in.num();
  in.key("trajectory_format");
  const std::string format = in.str();
  if (format == "csv") {
    spec.trajectory_format = TrajectoryFormat::csv;
  } else if (format == "h5md") {
    spec.trajectory_format = TrajectoryFormat::h5md;
  } else {
    throw Corrupt{"unknown trajectory format '" + format + "'"};
  }
  if (in.optional_key("auto")) {
    AutoChoice a;
    a.tolerance = in.num();
    a.reason = in.str();
    const bool given = in.integer(0, 1) == 1;
    const double given_dt = in.num();
    if (given) a.given_dt = given_dt;
    a.given_output_every = static_cast<long>(in.integer(1));
    a.pilot_t_end = in.num();
    a.pilot_steps = static_cast<long>(in.integer(0));
    a.pilot_seconds = in.num();
    a.predicted_error = in.num();
    const long long n = in.integer(0, 64);
    for (long long k = 0; k < n; ++k) {
      AutoCandidate cand;
      cand.method = in.str();
      cand.pilot_dt = in.num();
      cand.pilot_error = in.num();
      cand.dt = in.num();
      cand.cost = in.num();
      cand.refined = in.integer(0, 1) == 1;
      a.candidates.push_back(std::move(cand));
    }
    spec.tolerance = a.tolerance;
    spec.auto_choice = std::move(a);
  }
  // A thermostatted run's scene (version 3, or 4 on a topology).
  if (in.optional_key("thermostat")) {
    if (version != Checkpoint::thermostat_version && !topology) {
      throw Corrupt{"it has a thermostat, which version 3 (or 4) holds"};
    }
    ThermostatSpec t;
    t.kind = in.str();
    const long long knots = in.integer(1, 1 << 20);
    for (long long k = 0; k < knots; ++k) {
      const double time = in.num();
      t.schedule.emplace_back(time, in.num());
    }
    t.gamma = in.num();
    t.tau = in.num();
    t.chain = static_cast<int>(in.integer(1, 1 << 20));
    t.seed = static_cast<std::uint64_t>(in.integer(0, std::numeric_limits<long long>::max()));
    scene.thermostat = std::move(t);
  } else if (version == Checkpoint::thermostat_version) {
    throw Corrupt{"expected its thermostat"};
  }
  in.key("guard");
  c.guard_energy = in.num();
  c.guard_scale = in.num();
  in.key("step");
  c.step = static_cast<long>(in.integer(0));
  // The state's first key says which version wrote it (q: 1, x: 2), whatever the first line says.
  const int written = in.optional_key("q")   ? Checkpoint::chart_version
                      : in.optional_key("x") ? Checkpoint::version
                                             : 0;
  if (written == 0) throw Corrupt{"expected its state ('q' or 'x')"};
  // (Version 3's state is version 1's with the thermostat's after it; version 4's, version 1's or
  // 3's with the image record after it.)
  const bool chart = version != Checkpoint::version;
  if (written != (chart ? Checkpoint::chart_version : version)) throw OtherVersion{written};
  if (chart) {
    c.state.q = in.matrix(dim, bodies);
    in.key("p");
    c.state.p = in.matrix(dim, bodies);
    in.key("frames");
    const long long frames = in.integer(0, bodies);
    if (frames != 0 && frames != bodies) throw Corrupt{"the frames do not match the bodies"};
    for (long long k = 0; k < frames; ++k) c.state.frames.push_back(in.matrix(ambient, ambient));
    in.key("cluster");
    c.state.clustered = in.integer(0, 1) == 1;
    if (c.state.clustered) c.state.cluster = in.matrix(ambient, ambient);
    if (scene.thermostat) {
      in.key("thermostat_state");
      c.state.thermostat = in.vector(1 << 20);
    }
    if (topology) {
      in.key("image_counts");
      const bool box = !scene.space.box.empty();
      const long long rows = in.integer(0, dim), cols = in.integer(0, bodies);
      if (rows != (box ? dim : 0) || cols != (box ? bodies : 0)) throw Corrupt{"the image counts have the wrong size"};
      c.state.image_counts.resize(rows, cols);
      for (long long j = 0; j < cols; ++j) {
        for (long long i = 0; i < rows; ++i) {
          c.state.image_counts(i, j) = in.integer(std::numeric_limits<long long>::min(), std::numeric_limits<long long>::max());
        }
      }
      in.key("words");
      const long long words = in.integer(0, bodies);
      if (words != (box ? 0 : bodies)) throw Corrupt{"the words do not match the bodies"};
      // Letters are the polygon's sides 0 .. 4g - 1.
      const long long sides = 4LL * scene.space.genus;
      for (long long b = 0; b < words; ++b) {
        std::vector<std::int16_t>& word = c.state.words.emplace_back(static_cast<std::size_t>(in.integer(0, 1 << 24)));
        for (std::int16_t& letter : word) letter = static_cast<std::int16_t>(in.integer(0, sides - 1));
      }
    }
  } else {
    c.state.embedded = true;
    c.state.x = in.matrix(ambient, bodies);
    in.key("v");
    c.state.v = in.matrix(ambient, bodies);
  }
  for (Body& b : scene.bodies) {  // the initial conditions are not needed: the state is
    b.q = Eigen::VectorXd::Zero(dim);
    b.p = Eigen::VectorXd::Zero(dim);
  }
  in.key("outputs");
  c.outputs.trajectory_bytes = static_cast<std::uint64_t>(in.integer());
  c.outputs.diagnostics_bytes = static_cast<std::uint64_t>(in.integer());
  c.outputs.exact_bytes = static_cast<std::uint64_t>(in.integer());
  c.outputs.trajectory_frames = static_cast<std::uint64_t>(in.integer());
  InvariantStats& s = c.recorder.stats;
  in.key("energy");
  c.recorder.tracking = in.integer(0, 1) == 1;
  s.energy_initial = in.num();
  s.energy_final = in.num();
  s.max_abs_energy_error = in.num();
  s.max_rel_energy_error = in.num();
  const long long components = static_cast<long long>(ambient) * (ambient + 1) / 2;
  in.key("momentum_initial");
  s.momentum_initial = in.eigen_vector(components);
  in.key("momentum_final");
  s.momentum_final = in.eigen_vector(components);
  in.key("momentum_drift");
  s.max_momentum_drift = in.num();
  in.key("max_distance");
  s.max_distance = in.num();
  in.key("exact_max");
  c.recorder.exact_max_error = in.vector(bodies);
  in.key("exact_last");
  c.recorder.exact_last_error = in.vector(bodies);
  if (scene.thermostat) {
    in.key("thermostat_stats");
    s.conserved_tracking = in.integer(0, 1) == 1;
    s.conserved_initial = in.num();
    s.conserved_final = in.num();
    s.max_abs_conserved_drift = in.num();
    s.thermostat_rows = static_cast<long>(in.integer());
    s.sum_kinetic_temperature = in.num();
    s.sum_grad_squared = in.num();
    s.sum_laplacian = in.num();
    s.heat = in.num();
  }
  in.key("end");
  if (!in.at_end()) throw Corrupt{"it goes on after its end"};
  return c;
}

/// Write all of text to fd.
bool write_all(int fd, std::string_view text) {
  while (!text.empty()) {
    const ssize_t n = ::write(fd, text.data(), text.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    text.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

}  // namespace

void write_checkpoint(const Checkpoint& c, const std::filesystem::path& dir, const std::filesystem::path& shown_dir) {
  const std::string body = body_text(c);
  char header[128];
  std::snprintf(header, sizeof header, "%.*s %d %zu %016llx\n", static_cast<int>(magic.size()), magic.data(),
                c.file_version(), body.size(), static_cast<unsigned long long>(fnv1a(body)));
  const std::filesystem::path path = dir / checkpoint_file_name;
  const std::filesystem::path temporary = dir / (std::string(checkpoint_file_name) + ".tmp");
  // A second signal while this is written removes the unfinished file (signals.hpp).
  signals::set_unfinished_file(temporary.c_str());
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  bool ok = fd >= 0 && write_all(fd, header) && write_all(fd, body);
  // On disk before the rename, so that a crash leaves the old checkpoint or the new one whole.
  if (ok) ok = ::fsync(fd) == 0;
  int error = errno;
  if (fd >= 0 && ::close(fd) != 0 && ok) {
    ok = false;
    error = errno;
  }
  if (ok && std::rename(temporary.c_str(), path.c_str()) != 0) {
    ok = false;
    error = errno;
  }
  signals::set_unfinished_file(nullptr);
  if (!ok) {
    std::remove(temporary.c_str());
    throw std::runtime_error("cannot write the checkpoint in " + shown_dir.string() + ": " + std::strerror(error));
  }
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  const std::string name = path.string();
  const auto refuse = [&](const std::string& why) { return InputError(Origin{name}, "", why); };
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw refuse(std::filesystem::exists(path, ec) ? "not a checkpoint file" : "no checkpoint here");
  }
  std::ifstream file(path, std::ios::binary);
  std::ostringstream buffer;
  buffer << file.rdbuf();
  if (!file) throw refuse(std::string("cannot read the checkpoint: ") + std::strerror(errno));
  const std::string text = buffer.str();
  const std::size_t eol = text.find('\n');
  const std::string_view head(text.data(), eol == std::string::npos ? std::min<std::size_t>(text.size(), 80) : eol);
  if (head.substr(0, magic.size() + 1) != std::string(magic) + " ") {
    throw refuse("not a sesi checkpoint (it does not start with 'sesi-checkpoint')");
  }
  int version = 0;
  std::size_t length = 0;
  unsigned long long sum = 0;
  char tail = 0;
  const std::string head_string(head);
  if (std::sscanf(head_string.c_str() + magic.size(), " %d %zu %16llx%c", &version, &length, &sum, &tail) != 3 ||
      eol == std::string::npos) {
    throw refuse("the checkpoint's first line is malformed");
  }
  if (version != Checkpoint::chart_version && version != Checkpoint::version &&
      version != Checkpoint::thermostat_version && version != Checkpoint::topology_version) {
    throw refuse("checkpoint format version " + std::to_string(version) + "; this sesi reads versions " +
                 std::to_string(Checkpoint::chart_version) + ", " + std::to_string(Checkpoint::version) + ", " +
                 std::to_string(Checkpoint::thermostat_version) + " and " +
                 std::to_string(Checkpoint::topology_version));
  }
  const std::string_view body = std::string_view(text).substr(eol + 1);
  if (body.size() != length) {
    throw refuse("the checkpoint is truncated or extended (" + std::to_string(body.size()) + " bytes after its " +
                 "first line, expected " + std::to_string(length) + ")");
  }
  if (fnv1a(body) != sum) throw refuse("the checkpoint is corrupted (checksum mismatch)");
  const std::string reads = "; this sesi reads format version " + std::to_string(Checkpoint::chart_version) +
                            " (a chart method's q and p) and " + std::to_string(Checkpoint::version) +
                            " (a geodesic method's x and v), version " +
                            std::to_string(Checkpoint::thermostat_version) + " for a thermostatted run and " +
                            std::to_string(Checkpoint::topology_version) + " for a run on a box or surface";
  Checkpoint c;
  try {
    c = parse_body(body, version);
  } catch (const Corrupt& e) {
    throw refuse("the checkpoint is inconsistent with its format version " + std::to_string(version) + ": " +
                 e.what + reads);
  } catch (const OtherVersion& e) {
    throw refuse("the checkpoint was written by format version " + std::to_string(e.written) +
                 ", but its first line says version " + std::to_string(version) + reads);
  }
  // A scene model that no scene file held: the rules of the scene reader, so that an edited
  // checkpoint (a negative mass with its checksum recomputed) is refused like a scene file.
  check_scene_model(c.scene, Origin{name});
  // A chart method steps q and p, a geodesic method x and v: the one cannot go on from the
  // other's state (an unknown method is check_method's to report).
  const std::string& method = c.scene.integrator.method;
  if (is_method(method) && is_embedded_method(method) != c.state.embedded) {
    throw refuse(c.state.embedded
                     ? "the checkpoint holds a geodesic method's state (x, v), but its method '" + method +
                           "' is a chart method, which steps q and p"
                     : "the checkpoint holds a chart method's state (q, p), but its method '" + method +
                           "' is a geodesic method, which steps x and v");
  }
  return c;
}

}  // namespace sesi::program
