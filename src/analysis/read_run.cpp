// Reading a run's outputs for the observables (analysis.hpp): summary.json, then trajectory.csv
// or trajectory.h5 (the layouts of src/outputs/recorder.hpp and h5md_writer.hpp).
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <sstream>
#include <string_view>

#ifdef SESI_HAVE_HDF5
#include <hdf5.h>
#endif

#include "analysis.hpp"
#include "errors.hpp"
#include "geometry.hpp"

namespace sesi::analysis {

namespace fs = std::filesystem;
using program::InputError;
using program::Origin;

namespace {

// ---- a small JSON reader for summary.json (the subset json_writer.cpp writes) ----------------

struct Json {
  enum class Kind { null, boolean, number, string, array, object } kind = Kind::null;
  bool boolean = false;
  double number = 0.0;
  std::string string;
  std::vector<Json> items;
  std::map<std::string, Json, std::less<>> members;

  const Json* find(std::string_view key) const {
    const auto it = members.find(key);
    return it == members.end() ? nullptr : &it->second;
  }
};

class JsonReader {
 public:
  explicit JsonReader(std::string_view text) : text_(text) {}
  bool parse(Json& out) {
    if (!value(out, 0)) return false;
    skip();
    return at_ == text_.size();
  }

 private:
  void skip() {
    while (at_ < text_.size() && (text_[at_] == ' ' || text_[at_] == '\n' || text_[at_] == '\r' || text_[at_] == '\t')) ++at_;
  }
  bool literal(std::string_view word) {
    if (text_.substr(at_, word.size()) != word) return false;
    at_ += word.size();
    return true;
  }
  bool string(std::string& out) {
    if (at_ >= text_.size() || text_[at_] != '"') return false;
    ++at_;
    while (at_ < text_.size() && text_[at_] != '"') {
      char c = text_[at_++];
      if (c == '\\') {
        if (at_ >= text_.size()) return false;
        c = text_[at_++];
        switch (c) {
          case 'n': c = '\n'; break;
          case 't': c = '\t'; break;
          case 'r': c = '\r'; break;
          case 'b': c = '\b'; break;
          case 'f': c = '\f'; break;
          case 'u':  // a control character or other escape: kept as '?' (names are not read)
            if (at_ + 4 > text_.size()) return false;
            at_ += 4;
            c = '?';
            break;
          default: break;  // '"', '\\', '/'
        }
      }
      out.push_back(c);
    }
    if (at_ >= text_.size()) return false;
    ++at_;
    return true;
  }
  bool value(Json& out, int depth) {
    if (depth > 64) return false;
    skip();
    if (at_ >= text_.size()) return false;
    const char c = text_[at_];
    if (c == '{') {
      out.kind = Json::Kind::object;
      ++at_;
      skip();
      if (at_ < text_.size() && text_[at_] == '}') return ++at_, true;
      while (true) {
        skip();
        std::string key;
        if (!string(key)) return false;
        skip();
        if (at_ >= text_.size() || text_[at_++] != ':') return false;
        Json item;
        if (!value(item, depth + 1)) return false;
        out.members.insert_or_assign(std::move(key), std::move(item));
        skip();
        if (at_ >= text_.size()) return false;
        if (text_[at_] == ',') { ++at_; continue; }
        if (text_[at_] == '}') return ++at_, true;
        return false;
      }
    }
    if (c == '[') {
      out.kind = Json::Kind::array;
      ++at_;
      skip();
      if (at_ < text_.size() && text_[at_] == ']') return ++at_, true;
      while (true) {
        Json item;
        if (!value(item, depth + 1)) return false;
        out.items.push_back(std::move(item));
        skip();
        if (at_ >= text_.size()) return false;
        if (text_[at_] == ',') { ++at_; continue; }
        if (text_[at_] == ']') return ++at_, true;
        return false;
      }
    }
    if (c == '"') {
      out.kind = Json::Kind::string;
      return string(out.string);
    }
    if (literal("true")) { out.kind = Json::Kind::boolean; out.boolean = true; return true; }
    if (literal("false")) { out.kind = Json::Kind::boolean; return true; }
    if (literal("null")) { out.kind = Json::Kind::null; return true; }
    out.kind = Json::Kind::number;
    const char* begin = text_.data() + at_;
    const auto [end, ec] = std::from_chars(begin, text_.data() + text_.size(), out.number);
    if (ec != std::errc()) return false;
    at_ += static_cast<std::size_t>(end - begin);
    return true;
  }

  std::string_view text_;
  std::size_t at_ = 0;
};

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

[[noreturn]] void refuse(const fs::path& where, const std::string& what) {
  throw InputError(Origin{where.string()}, "", what);
}

int ambient_of(const SpaceSpec& space) { return space.kind == SpaceKind::euclidean ? space.dim : space.dim + 1; }

/// The frames kept: t in [from, to], every k-th of those.
std::vector<std::size_t> select(const std::vector<double>& t, const ReadOptions& o) {
  std::vector<std::size_t> keep;
  long seen = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (!(t[k] >= o.from && t[k] <= o.to)) continue;
    if (seen++ % o.every == 0) keep.push_back(k);
  }
  // A run's last row falls off the even grid when t_end is not a multiple of the rows' spacing:
  // left out, as the correlations take lags in frames.
  if (keep.size() >= 3) {
    const double step = t[keep[1]] - t[keep[0]];
    const double last = t[keep.back()] - t[keep[keep.size() - 2]];
    if (std::abs(last - step) > 1e-9 * std::max(std::abs(step), std::abs(t[keep.back()]))) keep.pop_back();
  }
  return keep;
}

void add_velocities(Frames& frames, const std::vector<Eigen::MatrixXd>& q, const std::vector<Eigen::MatrixXd>& p) {
  const program::Geometry geometry(frames.space);
  frames.v.resize(frames.x.size());
  for (std::size_t f = 0; f < frames.x.size(); ++f) {
    frames.v[f].resize(frames.x[f].rows(), frames.x[f].cols());
    for (Eigen::Index b = 0; b < frames.x[f].cols(); ++b) {
      frames.v[f].col(b) = geometry.velocity(q[f].col(b), p[f].col(b), frames.masses[static_cast<std::size_t>(b)]);
    }
  }
}

/// The columns each body adds after its x columns on a topology: the image counts n1..nn (box),
/// or the unwrapped point u1..ua and the word (surface): recorder.cpp's layout.
int topology_columns(const SpaceSpec& space) {
  if (!space.box.empty()) return space.dim;
  if (space.genus != 0) return ambient_of(space) + 1;
  return 0;
}

Frames read_csv(const fs::path& path, const RunInfo& info, const ReadOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) refuse(path, "missing or unreadable: the run's trajectory");
  const int n = info.space.dim, a = ambient_of(info.space);
  const bool box = !info.space.box.empty(), surface = info.space.genus != 0;
  const long bodies = info.bodies;
  const long per_body = 2L * n + a + topology_columns(info.space);
  const long width = 1 + bodies * per_body;
  std::string line;
  if (!std::getline(in, line)) refuse(path, "empty: no header row");
  {
    // The header of recorder.cpp: t, then per body b<b>_q<i>, b<b>_p<i>, b<b>_x<i>, and on a
    // topology b<b>_n<i> (box) or b<b>_u<i>, b<b>_word (surface).
    std::string expected = "t";
    for (long b = 1; b <= bodies; ++b) {
      const std::string body = "b" + std::to_string(b) + "_";
      for (int i = 1; i <= n; ++i) expected += "," + body + "q" + std::to_string(i);
      for (int i = 1; i <= n; ++i) expected += "," + body + "p" + std::to_string(i);
      for (int i = 1; i <= a; ++i) expected += "," + body + "x" + std::to_string(i);
      if (box) {
        for (int i = 1; i <= n; ++i) expected += "," + body + "n" + std::to_string(i);
      } else if (surface) {
        for (int i = 1; i <= a; ++i) expected += "," + body + "u" + std::to_string(i);
        expected += "," + body + "word";
      }
    }
    if (line != expected) refuse(path, "its header is not that of a sesi trajectory of the run in summary.json");
  }
  std::vector<double> t;
  std::vector<std::vector<double>> rows;
  std::vector<std::vector<Word>> words;  // per row, per body (surface)
  std::vector<double> row;
  long number = 1;
  while (std::getline(in, line)) {
    ++number;
    row.clear();
    std::vector<Word> row_words;
    const char* at = line.data();
    const char* end = line.data() + line.size();
    long cell = 0;
    while (at <= end) {
      // A surface's word cell (the last of each body's columns) is text; the others numbers.
      if (surface && cell > 0 && (cell - 1) % per_body == per_body - 1) {
        const char* comma = std::find(at, end, ',');
        try {
          row_words.push_back(parse_word(std::string_view(at, static_cast<std::size_t>(comma - at)), info.space.genus));
        } catch (const InputError& e) {
          refuse(path, "line " + std::to_string(number) + ": " + e.what());
        }
        row.push_back(0.0);
        at = comma + 1;
        ++cell;
        continue;
      }
      double v = 0.0;
      const auto [next, ec] = std::from_chars(at, end, v);
      if (ec != std::errc() || (next != end && *next != ',')) {
        refuse(path, "line " + std::to_string(number) + ": not a row of numbers");
      }
      row.push_back(v);
      at = next + 1;
      ++cell;
    }
    if (static_cast<long>(row.size()) != width) {
      refuse(path, "line " + std::to_string(number) + ": " + std::to_string(row.size()) + " values, expected " +
                       std::to_string(width));
    }
    t.push_back(row[0]);
    rows.push_back(row);
    if (surface) words.push_back(std::move(row_words));
  }
  Frames frames;
  frames.space = info.space;
  const bool velocities = options.velocities && static_cast<long>(info.masses.size()) == bodies;
  if (velocities) frames.masses = info.masses;
  std::vector<Eigen::MatrixXd> q, p;
  for (const std::size_t k : select(t, options)) {
    const std::vector<double>& r = rows[k];
    frames.t.push_back(r[0]);
    Eigen::MatrixXd x(a, bodies), qk(n, bodies), pk(n, bodies);
    ImageCounts images(box ? n : 0, box ? bodies : 0);
    for (long b = 0; b < bodies; ++b) {
      const std::size_t base = 1 + static_cast<std::size_t>(b * per_body);
      for (int i = 0; i < n; ++i) qk(i, b) = r[base + static_cast<std::size_t>(i)];
      for (int i = 0; i < n; ++i) pk(i, b) = r[base + static_cast<std::size_t>(n + i)];
      for (int i = 0; i < a; ++i) x(i, b) = r[base + static_cast<std::size_t>(2 * n + i)];
      for (int i = 0; box && i < n; ++i) {
        const double count = r[base + static_cast<std::size_t>(2 * n + a + i)];
        // Image counts are whole numbers well inside the doubles' exact integers (2^53).
        if (!(count == std::trunc(count) && std::abs(count) < 0x1p53)) {
          refuse(path, "row at t = " + program::format_number(r[0]) + ": an image count that is not a whole number");
        }
        images(i, b) = static_cast<std::int64_t>(count);
      }
    }
    frames.x.push_back(std::move(x));
    if (box) frames.images.push_back(std::move(images));
    if (surface) frames.words.push_back(std::move(words[k]));
    if (velocities) {
      q.push_back(std::move(qk));
      p.push_back(std::move(pk));
    }
  }
  if (velocities) add_velocities(frames, q, p);
  return frames;
}

#ifdef SESI_HAVE_HDF5
/// An HDF5 identifier closed at scope exit.
struct Id {
  hid_t id;
  herr_t (*closer)(hid_t);
  ~Id() {
    if (id >= 0) closer(id);
  }
};

/// A whole dataset of doubles and its dimensions; false when it is missing.
bool read_dataset(hid_t file, const char* name, std::vector<double>& out, std::vector<hsize_t>& dims) {
  if (H5Lexists(file, name, H5P_DEFAULT) <= 0) return false;
  const Id dataset{H5Dopen2(file, name, H5P_DEFAULT), H5Dclose};
  if (dataset.id < 0) return false;
  const Id space{H5Dget_space(dataset.id), H5Sclose};
  const int rank = space.id < 0 ? -1 : H5Sget_simple_extent_ndims(space.id);
  if (rank < 1 || rank > 3) return false;
  dims.assign(static_cast<std::size_t>(rank), 0);
  H5Sget_simple_extent_dims(space.id, dims.data(), nullptr);
  hsize_t size = 1;
  for (const hsize_t d : dims) size *= d;
  out.resize(static_cast<std::size_t>(size));
  if (size == 0) return true;
  return H5Dread(dataset.id, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) >= 0;
}

/// particles/all/image/value, [frames][bodies][dim] whole numbers; false when missing or of
/// other dimensions.
bool read_images(hid_t file, hsize_t frames, hsize_t bodies, hsize_t dim, std::vector<std::int64_t>& out) {
  const char* name = "particles/all/image/value";
  if (H5Lexists(file, "particles/all/image", H5P_DEFAULT) <= 0 || H5Lexists(file, name, H5P_DEFAULT) <= 0) return false;
  const Id dataset{H5Dopen2(file, name, H5P_DEFAULT), H5Dclose};
  if (dataset.id < 0) return false;
  const Id space{H5Dget_space(dataset.id), H5Sclose};
  if (space.id < 0 || H5Sget_simple_extent_ndims(space.id) != 3) return false;
  std::array<hsize_t, 3> dims{};
  H5Sget_simple_extent_dims(space.id, dims.data(), nullptr);
  if (dims[0] != frames || dims[1] != bodies || dims[2] != dim) return false;
  out.resize(static_cast<std::size_t>(frames * bodies * dim));
  if (out.empty()) return true;
  return H5Dread(dataset.id, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) >= 0;
}

/// particles/all/word/value, [frames][bodies] variable-length strings (the text of
/// trajectory.csv's b<k>_word): the words per frame and body.
void read_words(const fs::path& path, hid_t file, hsize_t frames, hsize_t bodies, int genus,
                std::vector<std::vector<Word>>& out) {
  const char* name = "particles/all/word/value";
  const auto missing = [&]() { refuse(path, "has no particles/all/word of the run's surface in summary.json"); };
  if (H5Lexists(file, "particles/all/word", H5P_DEFAULT) <= 0 || H5Lexists(file, name, H5P_DEFAULT) <= 0) missing();
  const Id dataset{H5Dopen2(file, name, H5P_DEFAULT), H5Dclose};
  if (dataset.id < 0) missing();
  const Id space{H5Dget_space(dataset.id), H5Sclose};
  if (space.id < 0 || H5Sget_simple_extent_ndims(space.id) != 2) missing();
  std::array<hsize_t, 2> dims{};
  H5Sget_simple_extent_dims(space.id, dims.data(), nullptr);
  if (dims[0] != frames || dims[1] != bodies) missing();
  const Id type{H5Tcopy(H5T_C_S1), H5Tclose};
  if (type.id < 0 || H5Tset_size(type.id, H5T_VARIABLE) < 0) missing();
  std::vector<char*> texts(static_cast<std::size_t>(frames * bodies), nullptr);
  if (!texts.empty() && H5Dread(dataset.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, texts.data()) < 0) missing();
  // The strings HDF5 allocated, freed however the words turn out.
  struct Reclaim {
    std::vector<char*>& texts;
    ~Reclaim() {
      for (char* text : texts) H5free_memory(text);
    }
  } reclaim{texts};
  out.assign(static_cast<std::size_t>(frames), std::vector<Word>(static_cast<std::size_t>(bodies)));
  for (std::size_t f = 0; f < out.size(); ++f) {
    for (std::size_t b = 0; b < bodies; ++b) {
      const char* text = texts[f * bodies + b];
      try {
        out[f][b] = parse_word(text ? std::string_view(text) : std::string_view(), genus);
      } catch (const InputError& e) {
        refuse(path, std::string("particles/all/word: ") + e.what());
      }
    }
  }
}

Frames read_h5md(const fs::path& path, const RunInfo& info, const ReadOptions& options) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // failures become one line, not HDF5's stack
  const Id file{H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  if (file.id < 0) refuse(path, "missing or not an HDF5 file: the run's trajectory");
  const int n = info.space.dim, a = ambient_of(info.space);
  const auto bodies = static_cast<hsize_t>(info.bodies);
  std::vector<double> t, x, q, p, mass;
  std::vector<hsize_t> dt, dx, dq, dp, dm;
  if (!read_dataset(file.id, "particles/all/position/time", t, dt) ||
      !read_dataset(file.id, "particles/all/position/value", x, dx) || dx.size() != 3 || dx[0] != dt[0] ||
      dx[1] != bodies || dx[2] != static_cast<hsize_t>(a)) {
    refuse(path, "has no particles/all/position of the run in summary.json");
  }
  Frames frames;
  frames.space = info.space;
  std::vector<double> masses = info.masses;
  if (masses.empty() && read_dataset(file.id, "particles/all/mass", mass, dm) && dm.size() == 1 && dm[0] == bodies) {
    masses = mass;
  }
  bool velocities = options.velocities && masses.size() == bodies;
  if (velocities) {
    velocities = read_dataset(file.id, "particles/all/chart_position/value", q, dq) &&
                 read_dataset(file.id, "particles/all/chart_momentum/value", p, dp) && dq.size() == 3 &&
                 dp.size() == 3 && dq[0] == dt[0] && dp[0] == dt[0] && dq[1] == bodies && dp[1] == bodies &&
                 dq[2] == static_cast<hsize_t>(n) && dp[2] == static_cast<hsize_t>(n);
  }
  if (velocities) frames.masses = masses;
  // On a topology: the image counts (particles/all/image) or the words (particles/all/word).
  std::vector<std::int64_t> image;
  std::vector<std::vector<Word>> words;
  if (!info.space.box.empty() && !read_images(file.id, dt[0], bodies, static_cast<hsize_t>(n), image)) {
    refuse(path, "has no particles/all/image of the run's periodic box in summary.json");
  }
  if (info.space.genus != 0) read_words(path, file.id, dt[0], bodies, info.space.genus, words);
  std::vector<Eigen::MatrixXd> qs, ps;
  const auto cols = static_cast<Eigen::Index>(bodies);
  for (const std::size_t k : select(t, options)) {
    frames.t.push_back(t[k]);
    if (!image.empty()) {
      frames.images.emplace_back(Eigen::Map<const ImageCounts>(&image[k * bodies * static_cast<hsize_t>(n)], n, cols));
    }
    if (!words.empty()) frames.words.push_back(words[k]);
    // H5MD's [frame][body][coordinate] is Eigen's column-major coordinate x body.
    frames.x.emplace_back(Eigen::Map<const Eigen::MatrixXd>(&x[k * bodies * a], a, cols));
    if (velocities) {
      qs.emplace_back(Eigen::Map<const Eigen::MatrixXd>(&q[k * bodies * n], n, cols));
      ps.emplace_back(Eigen::Map<const Eigen::MatrixXd>(&p[k * bodies * n], n, cols));
    }
  }
  if (velocities) add_velocities(frames, qs, ps);
  return frames;
}
#endif

}  // namespace

RunInfo read_run_info(const fs::path& dir, bool allow_incomplete) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) refuse(dir, "not a directory (expected a sesi run's output directory)");
  const fs::path path = dir / "summary.json";
  if (!fs::exists(path, ec)) {
    refuse(dir, "has no summary.json: not a finished sesi run (a run still going writes its outputs elsewhere "
                "until it ends)");
  }
  Json json;
  if (!JsonReader(read_text(path)).parse(json) || json.kind != Json::Kind::object) {
    refuse(path, "not a sesi summary (cannot be read as JSON)");
  }
  const Json* complete = json.find("complete");
  if (!complete || complete->kind != Json::Kind::boolean) refuse(path, "not a sesi summary (no \"complete\")");
  if (!complete->boolean && !allow_incomplete) {
    const Json* reason = json.find("stop_reason");
    refuse(dir, "holds an unfinished run (" + (reason ? reason->string : std::string("incomplete")) +
                    "): finish it with sesi resume, or analyse a complete run");
  }
  RunInfo info;
  info.complete = complete->boolean;
  if (!info.complete) {
    // What stopped it: the stop reason, and the failure's message when there is one.
    const Json* reason = json.find("stop_reason");
    info.status = reason && reason->kind == Json::Kind::string ? reason->string : std::string("incomplete");
    const Json* failure = json.find("failure");
    const Json* message = failure ? failure->find("message") : nullptr;
    // The failure's message usually begins with the reason already ("energy error exceeded: |E - E0| ...").
    if (message && message->kind == Json::Kind::string && !message->string.empty()) {
      info.status = message->string.starts_with(info.status) ? message->string : info.status + ": " + message->string;
    }
  }
  if (const Json* source = json.find("source"); source && source->kind == Json::Kind::string) info.source = source->string;
  if (const Json* potentials = json.find("potentials"); potentials && potentials->kind == Json::Kind::array) {
    for (const Json& p : potentials->items) {
      if (p.kind == Json::Kind::string) info.potentials.push_back(p.string);
    }
  }
  const Json* space = json.find("space");
  const Json* kind = space ? space->find("kind") : nullptr;
  const Json* dim = space ? space->find("dim") : nullptr;
  if (!kind || !dim || dim->kind != Json::Kind::number) refuse(path, "not a sesi summary (no space)");
  if (kind->string == "sphere") {
    info.space.kind = SpaceKind::sphere;
  } else if (kind->string == "hyperbolic") {
    info.space.kind = SpaceKind::hyperbolic;
  } else if (kind->string == "euclidean") {
    info.space.kind = SpaceKind::euclidean;
  } else {
    refuse(path, "space.kind '" + program::cut_input(kind->string) + "' is not one sesi writes");
  }
  info.space.dim = static_cast<int>(dim->number);
  if (info.space.dim < 1 || info.space.dim != dim->number) refuse(path, "space.dim is not a dimension");
  if (info.space.kind != SpaceKind::euclidean) {
    const Json* radius = space->find("radius");
    if (!radius || radius->kind != Json::Kind::number || !(radius->number > 0.0)) refuse(path, "space.radius missing");
    info.space.radius = radius->number;
  }
  // The topology (summary.cpp): "box": [L1, ..., Ln] on E^n, "genus": g on H^2.
  if (const Json* box = space->find("box"); box && box->kind != Json::Kind::null) {
    if (box->kind != Json::Kind::array || info.space.kind != SpaceKind::euclidean ||
        static_cast<int>(box->items.size()) != info.space.dim) {
      refuse(path, "space.box is not a box of this space's dimension");
    }
    for (const Json& edge : box->items) {
      if (edge.kind != Json::Kind::number || !(edge.number > 0.0 && std::isfinite(edge.number))) {
        refuse(path, "space.box has an edge that is not a finite number > 0");
      }
      info.space.box.push_back(edge.number);
    }
  }
  if (const Json* genus = space->find("genus"); genus && genus->kind != Json::Kind::null) {
    if (genus->kind != Json::Kind::number || genus->number != std::trunc(genus->number) || genus->number < 2 ||
        genus->number > 1000 || info.space.kind != SpaceKind::hyperbolic || info.space.dim != 2) {
      refuse(path, "space.genus is not the genus of a surface on H^2");
    }
    info.space.genus = static_cast<int>(genus->number);
  }
  if (info.space.has_topology()) {
    try {
      max_cutoff(info.space);  // the library accepts the box or genus
    } catch (const InputError& e) {
      refuse(path, e.what());
    }
  }
  const Json* bodies = json.find("bodies");
  if (!bodies || bodies->kind != Json::Kind::number || bodies->number < 1) refuse(path, "no body count");
  info.bodies = static_cast<long>(bodies->number);
  const Json* trajectory = json.find("trajectory");
  info.trajectory = trajectory ? trajectory->string : "trajectory.csv";
  if (info.trajectory != "trajectory.csv" && info.trajectory != "trajectory.h5") {
    refuse(path, "trajectory '" + program::cut_input(info.trajectory) + "' is not one sesi writes");
  }
  if (const Json* masses = json.find("masses"); masses && masses->kind == Json::Kind::array) {
    for (const Json& m : masses->items) info.masses.push_back(m.number);
    if (static_cast<long>(info.masses.size()) != info.bodies) info.masses.clear();
  }
  return info;
}

Frames read_frames(const fs::path& dir, const RunInfo& info, const ReadOptions& options) {
  if (options.every < 1) throw InputError(Origin{}, "--every", "expected a whole number >= 1, got " + std::to_string(options.every));
  if (!(options.from <= options.to)) {
    throw InputError(Origin{}, "--from", "the first time read is after the last (--to)");
  }
  Frames frames;
  if (info.trajectory == "trajectory.h5") {
#ifdef SESI_HAVE_HDF5
    frames = read_h5md(dir / info.trajectory, info, options);
#else
    refuse(dir / info.trajectory, "an H5MD trajectory, and this sesi is built without HDF5");
#endif
  } else {
    frames = read_csv(dir / info.trajectory, info, options);
  }
  if (frames.x.empty()) {
    const bool window = options.from != -std::numeric_limits<double>::infinity() ||
                        options.to != std::numeric_limits<double>::infinity();
    if (!window) refuse(dir / info.trajectory, "holds no frame (the run wrote none)");
    throw InputError(Origin{}, "--from", "no frame of " + (dir / info.trajectory).string() + " lies in the times asked for");
  }
  return frames;
}

}  // namespace sesi::analysis
