#include "h5md_writer.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <hdf5.h>

#include "errors.hpp"
#include "output_dir.hpp"

#ifndef SESI_VERSION
#define SESI_VERSION "unknown"
#endif

namespace sesi::program {

namespace {

constexpr hid_t no_id = -1;

/// An HDF5 identifier and its close function. The destructor closes quietly; close() reports.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Handle(Handle&& other) noexcept : id_(std::exchange(other.id_, no_id)), closer_(other.closer_) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      close();
      id_ = std::exchange(other.id_, no_id);
      closer_ = other.closer_;
    }
    return *this;
  }
  ~Handle() { close(); }

  hid_t get() const { return id_; }
  /// False if HDF5 failed to close it (for a dataset: to write its cached chunks).
  bool close() {
    return id_ < 0 || closer_(std::exchange(id_, no_id)) >= 0;
  }

 private:
  hid_t id_ = no_id;
  Closer closer_ = nullptr;
};

/// The most specific message on HDF5's error stack (e.g. the system's errno text), then clears it.
std::string hdf5_message() {
  std::string innermost;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t* error, void* data) -> herr_t {
        if (n == 0 && error->desc) *static_cast<std::string*>(data) = error->desc;
        return 0;
      },
      &innermost);
  H5Eclear2(H5E_DEFAULT);
  // A failed system call reads "file write failed: time = ..., error message = 'File too large',
  // buf = ..."; keep the words and the system's text.
  const std::string marker = "error message = '";
  if (const std::size_t at = innermost.find(marker); at != std::string::npos) {
    const std::size_t from = at + marker.size(), to = innermost.find('\'', from);
    const std::size_t colon = innermost.find(':');
    if (to != std::string::npos && colon != std::string::npos && colon < at) {
      innermost = innermost.substr(0, colon) + ": " + innermost.substr(from, to - from);
    }
  }
  return innermost;
}

bool deflate_available() {
  unsigned config = 0;
  return H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0 && H5Zget_filter_info(H5Z_FILTER_DEFLATE, &config) >= 0 &&
         (config & H5Z_FILTER_CONFIG_ENCODE_ENABLED) != 0;
}

/// Chunk of a time series whose frames have shape `item` (doubles or int64): whole frames up to
/// 256 KiB, so that a small scene's chunk holds many frames and compresses well; a frame larger
/// than 1 MiB is cut along the bodies, so that no chunk outgrows HDF5's default per-dataset
/// chunk cache (1 MiB), which holds a chunk until its frames are complete.
std::vector<hsize_t> chunk_shape(const std::vector<hsize_t>& item) {
  constexpr hsize_t small = hsize_t{256} << 10, large = hsize_t{1} << 20, max_frames = 1024;
  hsize_t frame_bytes = 8;
  for (const hsize_t n : item) frame_bytes *= std::max<hsize_t>(n, 1);
  std::vector<hsize_t> chunk{1};
  for (const hsize_t n : item) chunk.push_back(std::max<hsize_t>(n, 1));
  if (frame_bytes <= small) {
    chunk[0] = std::clamp<hsize_t>(small / frame_bytes, 1, max_frames);
  } else if (frame_bytes > large) {
    const hsize_t body_bytes = frame_bytes / chunk[1];
    chunk[1] = std::clamp<hsize_t>(large / body_bytes, 1, chunk[1]);
  }
  return chunk;
}

/// A thermostatted run's observables under observables/ (the names of diagnostics.csv's columns).
constexpr const char* thermostat_names[] = {"temperature", "kinetic_temperature", "configurational_temperature",
                                            "heat", "conserved"};

/// Their values in s, in thermostat_names' order.
std::array<double, 5> thermostat_values(const Snapshot& s) {
  return {s.temperature, s.kinetic_temperature, s.configurational_temperature(), s.heat, s.conserved};
}

/// A time series under construction: its dataset and the shape of one frame.
struct Series {
  Handle dataset;
  std::vector<hsize_t> item;
  hid_t memory_type = no_id;
  std::string name;
};

}  // namespace

struct H5mdWriter::Impl {
  std::filesystem::path path;
  hsize_t bodies = 0, dim = 0, ambient = 0, frames = 0;
  bool box = false;      ///< an E^n periodic box: particles/all/image
  int sides = 0;         ///< an H^2 surface's polygon (4g): particles/all/unwrapped_position and word
  // Declared first, destroyed last: the file closes after its datasets.
  Handle file, group_properties, dataset_properties, word_type;
  Series step, time, position, chart_position, chart_momentum, energy;
  /// On a topology: the image counts (box), or the unwrapped points and words (surface).
  Series image, unwrapped, word;
  /// A thermostatted run's observables (diagnostics.csv's columns), in thermostat_names' order.
  std::vector<Series> thermostat;

  [[noreturn]] void fail(const std::string& what) const {
    const std::string detail = hdf5_message();
    throw std::runtime_error("cannot write " + shown_path(path).string() + ": " + what +
                             (detail.empty() ? "" : ": " + detail));
  }
  hid_t check(hid_t id, const std::string& what) const {
    if (id < 0) fail(what);
    return id;
  }
  void check_status(herr_t status, const std::string& what) const {
    if (status < 0) fail(what);
  }

  Handle group(hid_t parent, const char* name) const {
    return {check(H5Gcreate2(parent, name, H5P_DEFAULT, group_properties.get(), H5P_DEFAULT),
                  std::string("creating group ") + name),
            H5Gclose};
  }

  void attribute(hid_t object, const char* name, hid_t file_type, hid_t memory_type, const Handle& space,
                 const void* data) const {
    const std::string what = std::string("writing attribute ") + name;
    const Handle attr(check(H5Acreate2(object, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), what),
                      H5Aclose);
    check_status(H5Awrite(attr.get(), memory_type, data), what);
  }
  Handle scalar_space() const { return {check(H5Screate(H5S_SCALAR), "creating a dataspace"), H5Sclose}; }
  Handle vector_space(hsize_t n) const {
    return {check(H5Screate_simple(1, &n, nullptr), "creating a dataspace"), H5Sclose};
  }
  void attribute_ints(hid_t object, const char* name, const std::vector<int>& values, bool scalar) const {
    attribute(object, name, H5T_STD_I32LE, H5T_NATIVE_INT, scalar ? scalar_space() : vector_space(values.size()),
              values.data());
  }
  void attribute_double(hid_t object, const char* name, double value) const {
    attribute(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, scalar_space(), &value);
  }
  /// H5MD's strings are fixed-length; one of them is scalar, several a rank-1 array.
  void attribute_strings(hid_t object, const char* name, const std::vector<std::string>& values,
                         bool scalar) const {
    std::size_t width = 1;
    for (const std::string& v : values) width = std::max(width, v.size() + 1);
    std::vector<char> buffer(width * values.size(), '\0');
    for (std::size_t k = 0; k < values.size(); ++k) std::copy(values[k].begin(), values[k].end(), &buffer[k * width]);
    const Handle type(check(H5Tcopy(H5T_C_S1), "creating a string type"), H5Tclose);
    check_status(H5Tset_size(type.get(), width), "creating a string type");
    check_status(H5Tset_strpad(type.get(), H5T_STR_NULLTERM), "creating a string type");
    attribute(object, name, type.get(), type.get(), scalar ? scalar_space() : vector_space(values.size()),
              buffer.data());
  }

  /// An empty time series, extensible along its first (frame) dimension; compressed unless its
  /// type is a variable-length one (whose heap the filters would not reach).
  Series series(hid_t group, const char* name, hid_t file_type, hid_t memory_type, std::vector<hsize_t> item,
                bool compress = true) const {
    const std::string what = std::string("creating dataset ") + name;
    std::vector<hsize_t> dims{0}, max_dims{H5S_UNLIMITED};
    dims.insert(dims.end(), item.begin(), item.end());
    max_dims.insert(max_dims.end(), item.begin(), item.end());
    const std::vector<hsize_t> chunk = chunk_shape(item);
    const int rank = static_cast<int>(dims.size());
    const Handle space(check(H5Screate_simple(rank, dims.data(), max_dims.data()), what), H5Sclose);
    const Handle properties(check(H5Pcopy(dataset_properties.get()), what), H5Pclose);
    check_status(H5Pset_chunk(properties.get(), rank, chunk.data()), what);
    // Shuffling the bytes of the doubles first lets deflate find the repeated exponents.
    if (compress && deflate_available()) {
      check_status(H5Pset_shuffle(properties.get()), what);
      check_status(H5Pset_deflate(properties.get(), 4), what);
    }
    Handle dataset(check(H5Dcreate2(group, name, file_type, space.get(), H5P_DEFAULT, properties.get(), H5P_DEFAULT),
                         what),
                   H5Dclose);
    return Series{std::move(dataset), std::move(item), memory_type, name};
  }

  /// Extends s by one frame (frames + 1) and writes data there.
  void append(const Series& s, const void* data) const {
    const std::string what = "writing frame " + std::to_string(frames) + " of " + s.name;
    std::vector<hsize_t> dims{frames + 1}, start{frames}, count{1};
    dims.insert(dims.end(), s.item.begin(), s.item.end());
    start.resize(dims.size(), 0);
    count.insert(count.end(), s.item.begin(), s.item.end());
    const int rank = static_cast<int>(dims.size());
    check_status(H5Dset_extent(s.dataset.get(), dims.data()), what);
    const Handle file_space(check(H5Dget_space(s.dataset.get()), what), H5Sclose);
    check_status(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr),
                 what);
    const Handle memory_space(check(H5Screate_simple(rank, count.data(), nullptr), what), H5Sclose);
    check_status(H5Dwrite(s.dataset.get(), s.memory_type, memory_space.get(), file_space.get(), H5P_DEFAULT, data),
                 what);
  }

  void link(const char* from, const char* to) const {
    check_status(H5Lcreate_hard(file.get(), from, file.get(), to, H5P_DEFAULT, H5P_DEFAULT),
                 std::string("linking ") + to);
  }
};

H5mdWriter::H5mdWriter(const std::filesystem::path& path, const Scene& scene) : impl_(std::make_unique<Impl>()) {
  // A file whose close failed (say, the disk is full) stays in HDF5's table after being freed,
  // and HDF5 1.10's exit-time cleanup then crashes on it (HDFGroup/hdf5 pull request 2291).
  // Everything is closed here, so no cleanup at exit is needed; this works only before HDF5's
  // first use, which this is.
  H5dont_atexit();
  // Failures become exceptions with one line; HDF5 would otherwise print its error stack.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  Impl& w = *impl_;
  w.path = path;
  w.bodies = static_cast<hsize_t>(scene.body_count());
  w.dim = static_cast<hsize_t>(scene.dim());
  w.ambient = scene.space.kind == SpaceKind::euclidean ? w.dim : w.dim + 1;

  // No modification times in the objects: the same run gives the same bytes.
  const Handle file_creation(w.check(H5Pcreate(H5P_FILE_CREATE), "creating the file"), H5Pclose);
  w.check_status(H5Pset_obj_track_times(file_creation.get(), false), "creating the file");
  // SEMI: closing the file fails, rather than being deferred, if anything is still open.
  const Handle file_access(w.check(H5Pcreate(H5P_FILE_ACCESS), "creating the file"), H5Pclose);
  w.check_status(H5Pset_fclose_degree(file_access.get(), H5F_CLOSE_SEMI), "creating the file");
  w.file = Handle(w.check(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, file_creation.get(), file_access.get()),
                          "creating the file"),
                  H5Fclose);
  w.group_properties = Handle(w.check(H5Pcreate(H5P_GROUP_CREATE), "creating the file"), H5Pclose);
  w.check_status(H5Pset_obj_track_times(w.group_properties.get(), false), "creating the file");
  w.dataset_properties = Handle(w.check(H5Pcreate(H5P_DATASET_CREATE), "creating the file"), H5Pclose);
  w.check_status(H5Pset_obj_track_times(w.dataset_properties.get(), false), "creating the file");
  const hid_t root = w.file.get();

  {
    const Handle h5md = w.group(root, "h5md");
    w.attribute_ints(h5md.get(), "version", {1, 1}, false);
    const Handle author = w.group(h5md.get(), "author");
    w.attribute_strings(author.get(), "name", {"sesi"}, true);
    const Handle creator = w.group(h5md.get(), "creator");
    w.attribute_strings(creator.get(), "name", {"sesi"}, true);
    w.attribute_strings(creator.get(), "version", {SESI_VERSION}, true);
  }
  {
    // What the embedding coordinates mean: a sphere or hyperboloid of this radius, or E^n.
    const Handle parameters = w.group(root, "parameters");
    w.attribute_strings(parameters.get(), "space", {std::string(space_name(scene.space.kind))}, true);
    w.attribute_ints(parameters.get(), "dim", {scene.dim()}, true);
    if (scene.space.kind != SpaceKind::euclidean) w.attribute_double(parameters.get(), "radius", scene.space.radius);
  }
  const Handle particles = w.group(root, "particles");
  const Handle all = w.group(particles.get(), "all");
  w.box = !scene.space.box.empty();
  w.sides = scene.space.genus > 0 ? 4 * scene.space.genus : 0;
  {
    const Handle box = w.group(all.get(), "box");
    w.attribute_ints(box.get(), "dimension", {static_cast<int>(w.ambient)}, true);
    if (w.box) {
      // An orthorhombic periodic box: its edges as a fixed [D] dataset (H5MD 1.1, "Simulation box").
      w.attribute_strings(box.get(), "boundary", std::vector<std::string>(w.ambient, "periodic"), false);
      const Handle space = w.vector_space(w.ambient);
      const Handle edges(w.check(H5Dcreate2(box.get(), "edges", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT,
                                            w.dataset_properties.get(), H5P_DEFAULT),
                                 "creating dataset edges"),
                         H5Dclose);
      w.check_status(H5Dwrite(edges.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, scene.space.box.data()),
                     "writing dataset edges");
    } else {
      // H5MD requires a box; the embedding space has no boundary, so no edges either. A compact
      // hyperbolic surface is no box H5MD knows: its polygon is named by attributes of sesi's own.
      w.attribute_strings(box.get(), "boundary", std::vector<std::string>(w.ambient, "none"), false);
      if (w.sides > 0) {
        w.attribute_strings(box.get(), "sesi_topology", {"hyperbolic-surface"}, true);
        w.attribute_ints(box.get(), "genus", {scene.space.genus}, true);
        w.attribute_double(box.get(), "radius", scene.space.radius);
      }
    }
  }
  {
    const Handle position = w.group(all.get(), "position");
    w.step = w.series(position.get(), "step", H5T_STD_I64LE, H5T_NATIVE_INT64, {});
    w.step.name = "particles/all/position/step";
    w.time = w.series(position.get(), "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {});
    w.time.name = "particles/all/position/time";
    w.position = w.series(position.get(), "value", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {w.bodies, w.ambient});
    w.position.name = "particles/all/position";
  }
  // The other elements are sampled with the positions: their step and time are hard links.
  const auto element = [&](hid_t parent, const char* group, const char* full_name, std::vector<hsize_t> item,
                           hid_t file_type = H5T_IEEE_F64LE, hid_t memory_type = H5T_NATIVE_DOUBLE,
                           bool compress = true) {
    const Handle g = w.group(parent, group);
    Series s = w.series(g.get(), "value", file_type, memory_type, std::move(item), compress);
    s.name = full_name;
    w.link("/particles/all/position/step", (std::string("/") + full_name + "/step").c_str());
    w.link("/particles/all/position/time", (std::string("/") + full_name + "/time").c_str());
    return s;
  };
  w.chart_position = element(all.get(), "chart_position", "particles/all/chart_position", {w.bodies, w.dim});
  w.chart_momentum = element(all.get(), "chart_momentum", "particles/all/chart_momentum", {w.bodies, w.dim});
  if (w.box) {
    // H5MD's image element: the unwrapped position is position + edges * image.
    w.image = element(all.get(), "image", "particles/all/image", {w.bodies, w.dim}, H5T_STD_I64LE, H5T_NATIVE_INT64);
  } else if (w.sides > 0) {
    w.unwrapped = element(all.get(), "unwrapped_position", "particles/all/unwrapped_position", {w.bodies, w.ambient});
    // The words as the text of trajectory.csv's b<k>_word, variable-length strings.
    w.word_type = Handle(w.check(H5Tcopy(H5T_C_S1), "creating a string type"), H5Tclose);
    w.check_status(H5Tset_size(w.word_type.get(), H5T_VARIABLE), "creating a string type");
    w.word = element(all.get(), "word", "particles/all/word", {w.bodies}, w.word_type.get(), w.word_type.get(), false);
  }
  {
    std::vector<double> masses;
    for (const Body& b : scene.bodies) masses.push_back(b.mass);
    const Handle space = w.vector_space(w.bodies);
    const Handle mass(w.check(H5Dcreate2(all.get(), "mass", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT,
                                         w.dataset_properties.get(), H5P_DEFAULT),
                              "creating dataset mass"),
                      H5Dclose);
    w.check_status(H5Dwrite(mass.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, masses.data()),
                   "writing dataset mass");
  }
  const Handle observables = w.group(root, "observables");
  w.energy = element(observables.get(), "energy", "observables/energy", {});
  if (scene.thermostat) {
    for (const char* name : thermostat_names) {
      w.thermostat.push_back(element(observables.get(), name, (std::string("observables/") + name).c_str(), {}));
    }
  }
}

H5mdWriter::~H5mdWriter() = default;

void H5mdWriter::write(const Snapshot& s) {
  Impl& w = *impl_;
  if (w.file.get() < 0) throw std::logic_error("H5mdWriter::write after close");
  const auto fits = [](const Eigen::MatrixXd& m, hsize_t rows, hsize_t cols) {
    return static_cast<hsize_t>(m.rows()) == rows && static_cast<hsize_t>(m.cols()) == cols;
  };
  if (!fits(s.x, w.ambient, w.bodies) || !fits(s.q, w.dim, w.bodies) || !fits(s.p, w.dim, w.bodies)) {
    throw std::logic_error("H5mdWriter::write: snapshot shape differs from the scene");
  }
  // Eigen's column-major dim x bodies is C's [bodies][dim]: the layout of one frame.
  const std::int64_t step = s.step;
  w.append(w.step, &step);
  w.append(w.time, &s.t);
  w.append(w.position, s.x.data());
  w.append(w.chart_position, s.q.data());
  w.append(w.chart_momentum, s.p.data());
  if (w.box) {
    if (!(static_cast<hsize_t>(s.image_counts.rows()) == w.dim && static_cast<hsize_t>(s.image_counts.cols()) == w.bodies)) {
      throw std::logic_error("H5mdWriter::write: a snapshot without its image counts");
    }
    w.append(w.image, s.image_counts.data());
  } else if (w.sides > 0) {
    if (!fits(s.unwrapped, w.ambient, w.bodies) || s.words.size() != w.bodies) {
      throw std::logic_error("H5mdWriter::write: a snapshot without its words");
    }
    w.append(w.unwrapped, s.unwrapped.data());
    std::vector<std::string> texts;
    std::vector<const char*> pointers;
    texts.reserve(s.words.size());
    for (const auto& word : s.words) texts.push_back(word_text(word));
    for (const std::string& text : texts) pointers.push_back(text.c_str());
    w.append(w.word, pointers.data());
  }
  w.append(w.energy, &s.energy);
  if (!w.thermostat.empty()) {
    const std::array<double, 5> values = thermostat_values(s);
    for (std::size_t k = 0; k < w.thermostat.size(); ++k) w.append(w.thermostat[k], &values[k]);
  }
  ++w.frames;
}

void H5mdWriter::replay(const std::filesystem::path& from, unsigned long long frames) {
  const Impl& w = *impl_;
  const auto refuse = [&](const std::string& what) {
    H5Eclear2(H5E_DEFAULT);
    return InputError(Origin{from.string()}, "", what + ", but the checkpoint goes on from it");
  };
  const Handle file(H5Fopen(from.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (file.get() < 0) throw refuse("cannot be read as HDF5");
  // One dataset, all its frames up to `frames`, as a flat vector of item-sized frames.
  const auto read = [&](const char* name, hid_t memory_type, hsize_t item, auto* out) {
    const Handle dataset(H5Dopen2(file.get(), name, H5P_DEFAULT), H5Dclose);
    if (dataset.get() < 0) throw refuse(std::string("has no dataset ") + name);
    const Handle space(H5Dget_space(dataset.get()), H5Sclose);
    hsize_t dims[3] = {0, 0, 0};
    const int rank = space.get() < 0 ? -1 : H5Sget_simple_extent_dims(space.get(), dims, nullptr);
    hsize_t size = 1;
    for (int k = 1; k < rank; ++k) size *= dims[k];
    if (rank < 1 || rank > 3 || dims[0] < frames || size != item) {
      throw refuse(std::string("has fewer frames or another shape in ") + name);
    }
    out->resize(static_cast<std::size_t>(frames * item));
    if (frames == 0) return;
    hsize_t start[3] = {0, 0, 0}, count[3] = {frames, dims[1], dims[2]};
    if (H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0) {
      throw refuse(std::string("cannot select the frames of ") + name);
    }
    const Handle memory(H5Screate_simple(rank, count, nullptr), H5Sclose);
    if (H5Dread(dataset.get(), memory_type, memory.get(), space.get(), H5P_DEFAULT, out->data()) < 0) {
      throw refuse(std::string("cannot read ") + name);
    }
  };
  std::vector<std::int64_t> step;
  std::vector<double> time, x, q, p, energy;
  read("particles/all/position/step", H5T_NATIVE_INT64, 1, &step);
  read("particles/all/position/time", H5T_NATIVE_DOUBLE, 1, &time);
  read("particles/all/position/value", H5T_NATIVE_DOUBLE, w.bodies * w.ambient, &x);
  read("particles/all/chart_position/value", H5T_NATIVE_DOUBLE, w.bodies * w.dim, &q);
  read("particles/all/chart_momentum/value", H5T_NATIVE_DOUBLE, w.bodies * w.dim, &p);
  read("observables/energy/value", H5T_NATIVE_DOUBLE, 1, &energy);
  std::vector<std::int64_t> image;
  std::vector<double> unwrapped;
  std::vector<std::vector<std::int16_t>> words;
  if (w.box) read("particles/all/image/value", H5T_NATIVE_INT64, w.bodies * w.dim, &image);
  if (w.sides > 0) {
    read("particles/all/unwrapped_position/value", H5T_NATIVE_DOUBLE, w.bodies * w.ambient, &unwrapped);
    std::vector<char*> texts;
    // The strings HDF5 allocates in H5Dread, freed however the reading and the words turn out.
    struct Reclaim {
      std::vector<char*>& texts;
      ~Reclaim() {
        for (char*& text : texts) {
          H5free_memory(text);
          text = nullptr;
        }
      }
    } reclaim{texts};
    read("particles/all/word/value", w.word_type.get(), w.bodies, &texts);
    words.reserve(texts.size());
    for (const char* text : texts) {
      auto word = parse_word_text(text ? std::string_view(text) : std::string_view(), w.sides);
      if (!word) throw refuse("has a word that is not one in particles/all/word");
      words.push_back(std::move(*word));
    }
  }
  std::vector<std::vector<double>> thermostat(w.thermostat.size());
  for (std::size_t k = 0; k < w.thermostat.size(); ++k) {
    read((std::string("observables/") + thermostat_names[k] + "/value").c_str(), H5T_NATIVE_DOUBLE, 1, &thermostat[k]);
  }
  const auto rows = static_cast<Eigen::Index>(w.bodies);
  Snapshot s;
  for (unsigned long long f = 0; f < frames; ++f) {
    s.step = static_cast<long>(step[f]);
    s.t = time[f];
    s.x = Eigen::Map<const Eigen::MatrixXd>(&x[f * w.bodies * w.ambient], static_cast<Eigen::Index>(w.ambient), rows);
    s.q = Eigen::Map<const Eigen::MatrixXd>(&q[f * w.bodies * w.dim], static_cast<Eigen::Index>(w.dim), rows);
    s.p = Eigen::Map<const Eigen::MatrixXd>(&p[f * w.bodies * w.dim], static_cast<Eigen::Index>(w.dim), rows);
    s.energy = energy[f];
    if (w.box) {
      s.image_counts = Eigen::Map<const Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic>>(
          &image[f * w.bodies * w.dim], static_cast<Eigen::Index>(w.dim), rows);
    } else if (w.sides > 0) {
      s.unwrapped =
          Eigen::Map<const Eigen::MatrixXd>(&unwrapped[f * w.bodies * w.ambient], static_cast<Eigen::Index>(w.ambient), rows);
      s.words.assign(words.begin() + static_cast<std::ptrdiff_t>(f * w.bodies),
                     words.begin() + static_cast<std::ptrdiff_t>((f + 1) * w.bodies));
    }
    if (!thermostat.empty()) {
      // The configurational temperature was written as the ratio of the sums: {T, 1}.
      s.thermostat = true;
      s.temperature = thermostat[0][f];
      s.kinetic_temperature = thermostat[1][f];
      s.configurational = {thermostat[2][f], 1.0};
      s.heat = thermostat[3][f];
      s.conserved = thermostat[4][f];
    }
    write(s);
  }
}

void H5mdWriter::close() {
  Impl& w = *impl_;
  if (w.file.get() < 0) return;
  bool ok = true;
  for (Series& s : w.thermostat) ok = s.dataset.close() && ok;
  for (Series* s : {&w.energy, &w.word, &w.unwrapped, &w.image, &w.chart_momentum, &w.chart_position, &w.position,
                    &w.time, &w.step}) {
    ok = s->dataset.close() && ok;
  }
  ok = w.word_type.close() && ok;
  ok = w.dataset_properties.close() && ok;
  ok = w.group_properties.close() && ok;
  ok = ok && H5Fflush(w.file.get(), H5F_SCOPE_LOCAL) >= 0;
  ok = w.file.close() && ok;
  if (!ok) w.fail("closing the file");
}

}  // namespace sesi::program
