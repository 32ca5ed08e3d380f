/// @file view.cpp
/// The viewer's bindings (docs/view.md, docs/python.md): a page of a run directory, or of a
/// Simulation's rows, written by the program's page writer (src/view/view_page.hpp), so that
/// sesi.view(dir) and `sesi view DIR` give the same bytes. python/sesi/view.py wraps them.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "analysis.hpp"
#include "errors.hpp"
#include "simulation.hpp"
#include "view_page.hpp"

namespace py = pybind11;
namespace an = sesi::analysis;
namespace vw = sesi::view;
using sesi::program::InputError;

namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Images = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
using Words = std::vector<std::vector<std::string>>;

/// "auto", "32", "64" (the command's --precision; python/sesi/view.py checks the value given).
vw::Precision precision_of(const std::string& text) {
  if (text == "auto") return vw::Precision::automatic;
  if (text == "32") return vw::Precision::f32;
  if (text == "64") return vw::Precision::f64;
  throw InputError("precision: expected \"auto\", 32 or 64, got '" + sesi::program::cut_input(text) + "'");
}

/// "S^2", "H^3", "E^2" (the page's label of the space).
std::string space_label(const sesi::program::SpaceSpec& s) {
  const char* letter = s.kind == sesi::program::SpaceKind::sphere       ? "S"
                       : s.kind == sesi::program::SpaceKind::hyperbolic ? "H"
                                                                        : "E";
  return std::string(letter) + "^" + std::to_string(s.dim);
}

/// The page and what View's repr shows. The page is written with the GIL released.
py::dict page(const vw::ViewData& data, const std::string& precision) {
  const vw::PageOptions options{precision_of(precision), false};
  std::string html;
  {
    py::gil_scoped_release release;
    html = vw::page_html(data, options);
  }
  py::dict d;
  d["html"] = py::str(html);
  d["title"] = data.title;
  d["space"] = space_label(data.space);
  d["box"] = data.space.box.empty() ? py::object(py::none()) : py::object(py::cast(data.space.box));
  d["genus"] = data.space.genus == 0 ? py::object(py::none()) : py::object(py::int_(data.space.genus));
  d["bodies"] = data.x.empty() ? 0L : static_cast<long>(data.x.front().cols());
  d["frames"] = static_cast<long>(data.x.size());
  d["complete"] = data.complete;
  d["status"] = data.status;
  return d;
}

/// Rows (F, N, A) of a Simulation.run as F matrices A x N (analysis::Frames' layout).
std::vector<Eigen::MatrixXd> frames_of(const Array& a, py::ssize_t count, py::ssize_t bodies, py::ssize_t ambient,
                                       const char* what) {
  if (a.ndim() != 3 || a.shape(0) != count || a.shape(1) != bodies || a.shape(2) != ambient) {
    throw InputError(std::string("rows: ") + what + ": expected an array (" + std::to_string(count) + ", " +
                     std::to_string(bodies) + ", " + std::to_string(ambient) +
                     ") (rows, bodies, ambient coordinates) of this simulation");
  }
  std::vector<Eigen::MatrixXd> out;
  out.reserve(static_cast<std::size_t>(count));
  const auto view = a.unchecked<3>();
  for (py::ssize_t f = 0; f < count; ++f) {
    Eigen::MatrixXd x(ambient, bodies);
    for (py::ssize_t b = 0; b < bodies; ++b) {
      for (py::ssize_t c = 0; c < ambient; ++c) x(c, b) = view(f, b, c);
    }
    out.push_back(std::move(x));
  }
  return out;
}

}  // namespace

/// Adds the viewer's functions to the compiled module (module.cpp calls it once).
void sesi_bind_view(py::module_& m) {
  m.def("view_run",
        [](const std::string& dir, std::optional<double> from, std::optional<double> to, long every, long max_frames,
           const std::string& precision) {
          vw::ReadViewOptions o;
          if (from) o.from = *from;
          if (to) o.to = *to;
          o.every = every;
          o.max_frames = max_frames;
          precision_of(precision);  // a bad value is refused before the run is read
          vw::ViewData data;
          {
            py::gil_scoped_release release;
            data = vw::read_view_data(dir, o);
          }
          return page(data, precision);
        },
        py::arg("dir"), py::arg("t_from"), py::arg("t_to"), py::arg("every"), py::arg("max_frames"),
        py::arg("precision"));

  // A Simulation's rows (Simulation.run's dict, or its state as one row): the frames as the run
  // directory's would be (speeds from v and the masses, jumps from the image counts or words),
  // the relative energy error against the first row and the kinetic temperature.
  m.def("view_rows",
        [](const sesi::python::Simulation& sim, const std::vector<double>& t, const Array& x, const Array& v,
           const std::vector<double>& energy, std::optional<Images> images, std::optional<Words> words,
           const std::string& title, long max_frames, const std::string& precision, const std::string& status) {
          const sesi::program::Scene& scene = sim.scene();
          const sesi::program::SpaceSpec& space = scene.space;
          const auto count = static_cast<py::ssize_t>(t.size());
          const py::ssize_t bodies = sim.bodies(), dim = space.dim;
          const py::ssize_t ambient = space.kind == sesi::program::SpaceKind::euclidean ? dim : dim + 1;
          if (count == 0) throw InputError("rows: no rows (t is empty)");
          if (static_cast<py::ssize_t>(energy.size()) != count) {
            throw InputError("rows: energy: expected one value per row (" + std::to_string(count) + ")");
          }
          precision_of(precision);
          an::Frames frames;
          frames.space = space;
          frames.t = t;
          frames.x = frames_of(x, count, bodies, ambient, "x");
          frames.v = frames_of(v, count, bodies, ambient, "v");
          const Eigen::VectorXd masses = sim.masses();
          frames.masses.assign(masses.data(), masses.data() + masses.size());
          if (!space.box.empty()) {
            if (!images) throw InputError("rows: image_counts: missing (a box simulation's rows carry them)");
            if (images->ndim() != 3 || images->shape(0) != count || images->shape(1) != bodies ||
                images->shape(2) != dim) {
              throw InputError("rows: image_counts: expected an integer array (rows, bodies, dim) of this simulation");
            }
            const auto view = images->unchecked<3>();
            for (py::ssize_t f = 0; f < count; ++f) {
              an::ImageCounts n(dim, bodies);
              for (py::ssize_t b = 0; b < bodies; ++b) {
                for (py::ssize_t k = 0; k < dim; ++k) n(k, b) = view(f, b, k);
              }
              frames.images.push_back(std::move(n));
            }
          }
          if (space.genus != 0) {
            if (!words) throw InputError("rows: words: missing (a surface simulation's rows carry them)");
            if (static_cast<py::ssize_t>(words->size()) != count) {
              throw InputError("rows: words: expected one list of words per row");
            }
            for (const std::vector<std::string>& row : *words) {
              if (static_cast<py::ssize_t>(row.size()) != bodies) throw InputError("rows: words: expected one word per body");
              std::vector<an::Word> parsed;
              parsed.reserve(row.size());
              for (const std::string& w : row) parsed.push_back(an::parse_word(w, space.genus));
              frames.words.push_back(std::move(parsed));
            }
          }

          vw::ViewData data = vw::from_frames(frames, title, max_frames);
          data.trajectory = "";
          data.complete = status.empty();
          data.status = status;
          // The display radius: half the smallest Lennard-Jones sigma (as a run directory's page).
          double sigma = std::numeric_limits<double>::infinity();
          for (const sesi::program::PotentialSpec& p : scene.potentials) {
            if (const auto* lj = std::get_if<sesi::program::LennardJonesSpec>(&p)) sigma = std::min(sigma, lj->sigma);
          }
          data.body_radius = std::isfinite(sigma) ? sigma / 2 : 0.0;

          // Diagnostics over every row (not only the frames kept), as a run directory's: the energy
          // error relative to the first row's energy (absolute when that is 0), and the kinetic
          // temperature (vw::kinetic_temperature); at most vw::max_series_points each.
          std::vector<double> error(energy.size());
          const double e0 = energy.front();
          for (std::size_t k = 0; k < energy.size(); ++k) {
            error[k] = e0 != 0.0 ? (energy[k] - e0) / std::abs(e0) : energy[k] - e0;
          }
          data.diagnostics.clear();
          data.diagnostics.push_back(vw::thin_series({e0 != 0.0 ? "relative energy error" : "energy error", t, error}));
          data.diagnostics.push_back(vw::thin_series(vw::kinetic_temperature(frames)));
          return page(data, precision);
        },
        py::arg("sim"), py::arg("t"), py::arg("x"), py::arg("v"), py::arg("energy"), py::arg("image_counts"),
        py::arg("words"), py::arg("title"), py::arg("max_frames"), py::arg("precision"), py::arg("status"));
}
