/// @file analysis.cpp
/// The observables' bindings (src/analysis, docs/observables.md): g(r), MSD, VACF and reading a
/// run, as functions of the compiled module that python/sesi/analysis.py wraps. The numbers are
/// those of `sesi analyze`: the same library.

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "analysis.hpp"
#include "errors.hpp"

namespace py = pybind11;
namespace an = sesi::analysis;

namespace {

an::SpaceSpec space_of(const std::string& kind, int dim, double radius,
                       const std::optional<std::vector<double>>& box = std::nullopt, std::optional<int> genus = std::nullopt) {
  an::SpaceSpec s;
  if (kind == "sphere") {
    s.kind = an::SpaceKind::sphere;
  } else if (kind == "hyperbolic") {
    s.kind = an::SpaceKind::hyperbolic;
  } else if (kind == "euclidean") {
    s.kind = an::SpaceKind::euclidean;
  } else {
    throw sesi::program::InputError("space: expected \"sphere\", \"hyperbolic\" or \"euclidean\", got '" +
                                    sesi::program::cut_input(kind) + "'");
  }
  if (dim < 1) throw sesi::program::InputError("dim: expected a dimension >= 1, got " + std::to_string(dim));
  if (s.kind != an::SpaceKind::euclidean && !(radius > 0.0 && std::isfinite(radius))) {
    throw sesi::program::InputError("radius: expected a finite number > 0, got " + sesi::program::format_number(radius));
  }
  s.dim = dim;
  s.radius = s.kind == an::SpaceKind::euclidean ? 1.0 : radius;
  // A topology (docs/observables.md): a periodic box on E^n, a compact surface on H^2.
  if (box) {
    if (s.kind != an::SpaceKind::euclidean || static_cast<int>(box->size()) != dim) {
      throw sesi::program::InputError("box: expected " + std::to_string(dim) + " edges, and a euclidean space");
    }
    for (const double edge : *box) {
      if (!(edge > 0.0 && std::isfinite(edge))) {
        throw sesi::program::InputError("box: expected finite edges > 0, got " + sesi::program::format_number(edge));
      }
    }
    s.box = *box;
  }
  if (genus) {
    if (s.kind != an::SpaceKind::hyperbolic || dim != 2 || *genus < 2) {
      throw sesi::program::InputError("genus: expected a whole number >= 2 on a hyperbolic space of dim 2, got " +
                                      std::to_string(*genus));
    }
    s.genus = *genus;
  }
  if (s.has_topology()) an::max_cutoff(s);  // the library accepts it (its limits: one line)
  return s;
}

int ambient_of(const an::SpaceSpec& s) { return s.kind == an::SpaceKind::euclidean ? s.dim : s.dim + 1; }

/// Frames (F, N, A) as F matrices A x N, checked against the space's ambient dimension.
std::vector<Eigen::MatrixXd> frames_of(const py::array_t<double, py::array::c_style | py::array::forcecast>& a,
                                       const an::SpaceSpec& space, const char* what) {
  if (a.ndim() != 3) throw sesi::program::InputError(std::string(what) + ": expected an array (frames, bodies, coordinates)");
  if (a.shape(2) != ambient_of(space)) {
    throw sesi::program::InputError(std::string(what) + ": " + std::to_string(a.shape(2)) +
                                    " coordinates per body, expected " + std::to_string(ambient_of(space)) +
                                    " (embedding points of the space)");
  }
  std::vector<Eigen::MatrixXd> out;
  const auto view = a.unchecked<3>();
  for (py::ssize_t f = 0; f < a.shape(0); ++f) {
    Eigen::MatrixXd x(a.shape(2), a.shape(1));
    for (py::ssize_t b = 0; b < a.shape(1); ++b) {
      for (py::ssize_t c = 0; c < a.shape(2); ++c) x(c, b) = view(f, b, c);
    }
    out.push_back(std::move(x));
  }
  return out;
}

py::array_t<double> stack(const std::vector<Eigen::MatrixXd>& frames) {
  const py::ssize_t f = static_cast<py::ssize_t>(frames.size());
  const py::ssize_t n = frames.empty() ? 0 : frames.front().cols(), a = frames.empty() ? 0 : frames.front().rows();
  py::array_t<double> out({f, n, a});
  auto view = out.mutable_unchecked<3>();
  for (py::ssize_t k = 0; k < f; ++k) {
    for (py::ssize_t b = 0; b < n; ++b) {
      for (py::ssize_t c = 0; c < a; ++c) view(k, b, c) = frames[static_cast<std::size_t>(k)](c, b);
    }
  }
  return out;
}

py::dict correlation(const an::Correlation& c) {
  py::dict d;
  d["t"] = py::array_t<double>(static_cast<py::ssize_t>(c.lag_time.size()), c.lag_time.data());
  d["value"] = py::array_t<double>(static_cast<py::ssize_t>(c.value.size()), c.value.data());
  d["samples"] = py::array_t<long>(static_cast<py::ssize_t>(c.samples.size()), c.samples.data());
  d["per_body"] = py::array_t<double>(static_cast<py::ssize_t>(c.per_body_last.size()), c.per_body_last.data());
  return d;
}

using Images = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
using Words = std::vector<std::vector<std::string>>;

an::Frames frames_from(const an::SpaceSpec& space, const std::vector<double>& t,
                       const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
                       const std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>>& v,
                       const std::optional<Images>& images = std::nullopt, const std::optional<Words>& words = std::nullopt) {
  an::Frames frames;
  frames.space = space;
  frames.x = frames_of(x, space, "x");
  if (v) frames.v = frames_of(*v, space, "v");
  frames.t = t;
  if (frames.t.size() != frames.x.size() || (v && frames.v.size() != frames.x.size())) {
    throw sesi::program::InputError("t, x and v: expected one time per frame and the same frames");
  }
  // The unwrapped positions of a quotient: image counts (frames, bodies, dim), words per frame and body.
  const auto count = static_cast<py::ssize_t>(frames.x.size()), bodies = static_cast<py::ssize_t>(frames.bodies());
  if (images) {
    if (space.box.empty()) throw sesi::program::InputError("images: image counts belong to a periodic box (box=)");
    if (images->ndim() != 3 || images->shape(0) != count || images->shape(1) != bodies || images->shape(2) != space.dim) {
      throw sesi::program::InputError("images: expected an integer array (frames, bodies, dim) matching the points");
    }
    const auto view = images->unchecked<3>();
    for (py::ssize_t f = 0; f < count; ++f) {
      an::ImageCounts n(space.dim, bodies);
      for (py::ssize_t b = 0; b < bodies; ++b) {
        for (py::ssize_t k = 0; k < space.dim; ++k) n(k, b) = view(f, b, k);
      }
      frames.images.push_back(std::move(n));
    }
  }
  if (words) {
    if (space.genus == 0) throw sesi::program::InputError("words: words belong to a compact surface (genus=)");
    if (static_cast<py::ssize_t>(words->size()) != count) {
      throw sesi::program::InputError("words: expected one list of words per frame");
    }
    for (const std::vector<std::string>& row : *words) {
      if (static_cast<py::ssize_t>(row.size()) != bodies) throw sesi::program::InputError("words: expected one word per body");
      std::vector<an::Word> parsed;
      for (const std::string& w : row) parsed.push_back(an::parse_word(w, space.genus));
      frames.words.push_back(std::move(parsed));
    }
  }
  return frames;
}

}  // namespace

/// Adds the observables' functions to the compiled module (module.cpp calls it once).
void sesi_bind_analysis(py::module_& m) {
  using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
  m.def("analysis_read",
        [](const std::string& dir, std::optional<double> from, std::optional<double> to, long every) {
          const an::RunInfo info = an::read_run_info(dir);
          an::ReadOptions o;
          if (from) o.from = *from;
          if (to) o.to = *to;
          o.every = every;
          const an::Frames f = an::read_frames(dir, info, o);
          py::dict d;
          d["space"] = std::string(sesi::program::space_name(info.space.kind));
          d["dim"] = info.space.dim;
          d["radius"] = info.space.radius;
          d["t"] = py::array_t<double>(static_cast<py::ssize_t>(f.t.size()), f.t.data());
          d["x"] = stack(f.x);
          d["v"] = f.v.empty() ? py::object(py::none()) : py::object(stack(f.v));
          d["masses"] = f.masses;
          d["box"] = info.space.box.empty() ? py::object(py::none()) : py::object(py::cast(info.space.box));
          d["genus"] = info.space.genus == 0 ? py::object(py::none()) : py::object(py::int_(info.space.genus));
          if (!f.images.empty()) {
            const py::ssize_t count = static_cast<py::ssize_t>(f.images.size()), n = f.bodies(), dim = info.space.dim;
            py::array_t<std::int64_t> images({count, n, dim});
            auto view = images.mutable_unchecked<3>();
            for (py::ssize_t k = 0; k < count; ++k) {
              for (py::ssize_t b = 0; b < n; ++b) {
                for (py::ssize_t c = 0; c < dim; ++c) view(k, b, c) = f.images[static_cast<std::size_t>(k)](c, b);
              }
            }
            d["images"] = images;
          } else {
            d["images"] = py::none();
          }
          if (!f.words.empty()) {
            py::list words;
            for (const auto& row : f.words) {
              py::list texts;
              for (const an::Word& w : row) texts.append(an::word_text(w));
              words.append(texts);
            }
            d["words"] = words;
          } else {
            d["words"] = py::none();
          }
          return d;
        },
        py::arg("dir"), py::arg("t_from"), py::arg("t_to"), py::arg("every"));
  m.def("analysis_rdf",
        [](const std::string& kind, int dim, double radius, const Array& x, std::optional<double> r_max, int bins,
           std::optional<Eigen::VectorXd> center, std::optional<double> region_radius, bool all_pairs,
           std::optional<std::vector<double>> box, std::optional<int> genus) {
          const an::SpaceSpec space = space_of(kind, dim, radius, box, genus);
          const std::vector<Eigen::MatrixXd> frames = frames_of(x, space, "points");
          if (frames.empty()) throw sesi::program::InputError("points: no frames");
          std::optional<an::Region> region;
          if (center || region_radius) {
            if (!center || !region_radius) throw sesi::program::InputError("region: expected (center, radius)");
            if (center->size() != ambient_of(space)) throw sesi::program::InputError("region: the center is not a point of the space");
            region = an::Region{*center, *region_radius};
          }
          an::Rdf rdf(space, r_max ? *r_max : an::default_rdf_max(space, frames.front()), bins);
          for (const Eigen::MatrixXd& f : frames) {
            if (all_pairs) {
              rdf.accumulate_all_pairs(f, region);
            } else {
              rdf.accumulate(f, region);
            }
          }
          const std::vector<double> e = rdf.edges(), c = rdf.centers(), g = rdf.g();
          py::dict d;
          d["edges"] = py::array_t<double>(static_cast<py::ssize_t>(e.size()), e.data());
          d["r"] = py::array_t<double>(static_cast<py::ssize_t>(c.size()), c.data());
          d["g"] = py::array_t<double>(static_cast<py::ssize_t>(g.size()), g.data());
          d["counts"] = py::array_t<std::int64_t>(static_cast<py::ssize_t>(rdf.counts().size()), rdf.counts().data());
          d["expected"] = py::array_t<double>(static_cast<py::ssize_t>(rdf.expected().size()), rdf.expected().data());
          d["frames"] = rdf.frames();
          d["centres"] = rdf.centres();
          return d;
        },
        py::arg("space"), py::arg("dim"), py::arg("radius"), py::arg("points"), py::arg("r_max"), py::arg("bins"),
        py::arg("center"), py::arg("region_radius"), py::arg("all_pairs"), py::arg("box") = py::none(),
        py::arg("genus") = py::none());
  m.def("analysis_msd",
        [](const std::string& kind, int dim, double radius, const std::vector<double>& t, const Array& x,
           long max_lag, std::optional<std::vector<double>> box, std::optional<int> genus, std::optional<Images> images,
           std::optional<Words> words) {
          return correlation(an::msd(frames_from(space_of(kind, dim, radius, box, genus), t, x, std::nullopt, images, words),
                                     max_lag));
        },
        py::arg("space"), py::arg("dim"), py::arg("radius"), py::arg("t"), py::arg("x"), py::arg("max_lag"),
        py::arg("box") = py::none(), py::arg("genus") = py::none(), py::arg("images") = py::none(),
        py::arg("words") = py::none());
  m.def("analysis_vacf",
        [](const std::string& kind, int dim, double radius, const std::vector<double>& t, const Array& x,
           const Array& v, long max_lag, std::optional<std::vector<double>> box, std::optional<int> genus,
           std::optional<Images> images, std::optional<Words> words) {
          return correlation(an::vacf(frames_from(space_of(kind, dim, radius, box, genus), t, x, v, images, words), max_lag));
        },
        py::arg("space"), py::arg("dim"), py::arg("radius"), py::arg("t"), py::arg("x"), py::arg("v"),
        py::arg("max_lag"), py::arg("box") = py::none(), py::arg("genus") = py::none(), py::arg("images") = py::none(),
        py::arg("words") = py::none());
  m.def("analysis_max_cutoff",
        [](const std::string& kind, int dim, double radius, std::optional<std::vector<double>> box,
           std::optional<int> genus) { return an::max_cutoff(space_of(kind, dim, radius, box, genus)); },
        py::arg("space"), py::arg("dim"), py::arg("radius"), py::arg("box") = py::none(), py::arg("genus") = py::none());
  m.def("analysis_msd_saturation", [](const std::string& kind, int dim, double radius) {
    return an::msd_saturation(space_of(kind, dim, radius));
  });
}
