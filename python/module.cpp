/// @file module.cpp
/// The compiled module `sesi._sesi` (pybind11): the scene document from Python values into
/// TOML nodes, the Simulation core, the catalogues, and InputError. The public API is the
/// Python layer's (sesi/__init__.py, docs/python.md).

#include <cstdint>
#include <limits>
#include <string>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <sesi/scenes/paper.hpp>

#include "errors.hpp"
#include "paper_scene.hpp"
#include "methods.hpp"
#include "method_list.hpp"
#include "scene_reader.hpp"
#include "scene_table.hpp"
#include "validate.hpp"
#include "simulation.hpp"

namespace py = pybind11;
using sesi::python::Simulation;

namespace {

/// A Python value as a TOML value, handed to put (by its concrete type): dict -> table,
/// list/tuple/NumPy array -> array, bool, int, float, str; anything else is an InputError naming
/// its key path.
toml::table to_table(py::handle dict, const std::string& path);
toml::array to_array(py::handle sequence, const std::string& path);

template <class Put>
void convert(py::handle value, const std::string& path, Put&& put) {
  if (py::isinstance<py::bool_>(value)) return put(value.cast<bool>());
  if (py::isinstance<py::int_>(value)) {
    std::int64_t n = 0;
    try {
      n = value.cast<std::int64_t>();
    } catch (const py::cast_error&) {
      throw sesi::program::InputError(path + ": an integer out of the 64-bit range");
    }
    return put(n);
  }
  if (py::isinstance<py::float_>(value)) return put(value.cast<double>());
  if (py::isinstance<py::str>(value)) return put(value.cast<std::string>());
  if (py::isinstance<py::dict>(value)) return put(to_table(value, path));
  if (py::isinstance<py::array>(value)) {
    const auto a = py::reinterpret_borrow<py::array>(value);
    return convert(a.ndim() == 0 ? a.attr("item")() : a.attr("tolist")(), path, put);
  }
  // NumPy scalars and other numbers: as an integer or a float.
  const auto object = py::reinterpret_borrow<py::object>(value);
  if (py::hasattr(value, "__index__")) return convert(py::int_(object), path, put);
  if (py::hasattr(value, "__float__") && !py::isinstance<py::sequence>(value)) {
    return convert(py::float_(object), path, put);
  }
  if (py::isinstance<py::sequence>(value)) return put(to_array(value, path));
  throw sesi::program::InputError(path + ": " + py::str(py::type::of(value).attr("__name__")).cast<std::string>() +
                                  " is not a scene value (a number, string, bool, list, array or dict)");
}

toml::array to_array(py::handle sequence, const std::string& path) {
  toml::array array;
  std::size_t k = 0;
  for (py::handle item : sequence) {
    convert(item, path + "[" + std::to_string(++k) + "]", [&](auto&& v) { array.push_back(std::move(v)); });
  }
  return array;
}

toml::table to_table(py::handle dict, const std::string& path) {
  toml::table table;
  for (auto [key, value] : py::reinterpret_borrow<py::dict>(dict)) {
    if (!py::isinstance<py::str>(key)) {
      throw sesi::program::InputError((path.empty() ? std::string("the scene") : path) + ": key " +
                                      py::repr(key).cast<std::string>() + " is not a string");
    }
    const std::string name = key.cast<std::string>();
    if (value.is_none()) continue;  // None: the key's default
    convert(value, path.empty() ? name : path + "." + name,
            [&](auto&& v) { table.insert(name, std::move(v)); });
  }
  return table;
}

/// An array with one row per output row (and bodies x coordinates after it).
py::array_t<double> stack(const std::vector<Eigen::MatrixXd>& rows, Eigen::Index bodies, Eigen::Index cols) {
  py::array_t<double> out({static_cast<py::ssize_t>(rows.size()), static_cast<py::ssize_t>(bodies),
                           static_cast<py::ssize_t>(cols)});
  auto view = out.mutable_unchecked<3>();
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (Eigen::Index b = 0; b < bodies; ++b) {
      for (Eigen::Index c = 0; c < cols; ++c) view(static_cast<py::ssize_t>(r), b, c) = rows[r](b, c);
    }
  }
  return out;
}

/// A [thermostat] table read by the scene reader (the program's checks and messages).
sesi::program::ThermostatSpec thermostat_of(py::handle dict, const std::string& source) {
  if (!py::isinstance<py::dict>(dict)) {
    throw sesi::program::InputError("thermostat: expected a sesi.Thermostat, a dict of the [thermostat] keys or None");
  }
  return sesi::program::read_thermostat_table(to_table(dict, "thermostat"), source);
}

/// A ThermostatSpec as the dict of its [thermostat] keys (temperature a number when constant).
py::dict thermostat_dict(const sesi::program::ThermostatSpec& th) {
  py::dict d;
  d["kind"] = th.kind;
  if (th.schedule.size() == 1 && th.schedule.front().first == 0.0) {
    d["temperature"] = th.schedule.front().second;
  } else {
    py::list knots;
    for (const auto& [t, kT] : th.schedule) knots.append(py::make_tuple(t, kT));
    d["temperature"] = knots;
  }
  for (std::string_view key : sesi::program::thermostat_keys(th.kind)) {
    if (key == "gamma") d["gamma"] = th.gamma;
    if (key == "tau") d["tau"] = th.tau;
    if (key == "chain") d["chain"] = th.chain;
    if (key == "seed") d["seed"] = th.seed;
  }
  return d;
}

}  // namespace

void sesi_bind_analysis(py::module_& m);  // analysis.cpp: g(r), MSD, VACF (sesi.analysis)
void sesi_bind_view(py::module_& m);      // view.cpp: the viewer page (sesi.view, Simulation.view)

PYBIND11_MODULE(_sesi, m) {
  m.doc() = "sesi's compiled core; use the package `sesi` (docs/python.md).";
  sesi_bind_analysis(m);
  sesi_bind_view(m);

  static py::exception<sesi::program::InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const sesi::program::InputError& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    } catch (const sesi::program::InvariantFailure& e) {
      PyErr_SetString(PyExc_RuntimeError, (std::string("a library invariant failed: ") + e.what()).c_str());
    }
  });

  // The same list as `sesi run --list-methods --json` (src/scene/method_list.hpp).
  m.def("methods", [] {
    py::list out;
    for (const auto& info : sesi::program::method_entries()) {
      py::dict d;
      d["name"] = std::string(info.name);
      d["order"] = info.order;
      d["family"] = std::string(info.family);
      d["processed"] = info.processed;
      d["stages"] = info.stages;
      d["output_stages"] = info.output_stages;
      py::list spaces;
      for (auto space : info.spaces) spaces.append(std::string(space));
      d["spaces"] = spaces;
      d["about"] = std::string(info.about);
      out.append(d);
    }
    return out;
  });
  m.def("potentials", [] {
    py::list out;
    for (const auto& info : sesi::program::potential_catalogue()) {
      py::dict d;
      d["kind"] = std::string(info.kind);
      py::list keys;
      for (auto key : info.keys) {
        if (key != "kind") keys.append(std::string(key));
      }
      d["keys"] = keys;
      d["defaults"] = std::string(info.defaults);
      d["energy"] = std::string(info.energy);
      out.append(d);
    }
    return out;
  });

  m.def("paper_exact", [](const std::vector<double>& times) {
    // The seed scene's exact solution (include/sesi/scenes/paper.hpp), in long double.
    const sesi::scenes::paper::Exact exact;
    py::array_t<double> out({static_cast<py::ssize_t>(times.size()), py::ssize_t{3}, py::ssize_t{3}});
    auto view = out.mutable_unchecked<3>();
    for (std::size_t k = 0; k < times.size(); ++k) {
      for (int b = 0; b < 3; ++b) {
        const auto x = exact.position(b, static_cast<long double>(times[k]));
        for (int c = 0; c < 3; ++c) view(static_cast<py::ssize_t>(k), b, c) = static_cast<double>(x(c));
      }
    }
    return out;
  });

  // A [thermostat] dict checked as a scene file's table, back with its defaults (sesi.Thermostat).
  m.def("thermostat_keys", [](py::dict d, const std::string& source) { return thermostat_dict(thermostat_of(d, source)); });
  m.def("thermostat_kinds", [] {
    py::list out;
    for (std::string_view kind : sesi::program::thermostat_kinds()) {
      py::list keys;
      for (std::string_view key : sesi::program::thermostat_keys(kind)) {
        if (key != "kind") keys.append(std::string(key));
      }
      out.append(py::make_tuple(std::string(kind), keys));
    }
    return out;
  });

  py::class_<sesi::python::Report>(m, "Report")
      .def_readonly("complete", &sesi::python::Report::complete)
      .def_readonly("reason", &sesi::python::Report::reason)
      .def_readonly("detail", &sesi::python::Report::detail)
      .def_readonly("failed_step", &sesi::python::Report::failed_step)
      .def_readonly("failed_t", &sesi::python::Report::failed_t)
      .def_readonly("failed_body", &sesi::python::Report::failed_body)
      .def_readonly("interrupted", &sesi::python::Report::interrupted);

  py::class_<Simulation>(m, "Core")
      .def(py::init([](py::dict doc, const std::string& source, py::list functions) {
             std::vector<std::shared_ptr<const sesi::program::FunctionExternalSpec::Functions>> fs;
             for (py::handle pair : functions) {
               const auto t = py::reinterpret_borrow<py::tuple>(pair);
               fs.push_back(std::make_shared<sesi::python::PythonFunctions>(t[0].cast<py::function>(),
                                                                            t[1].cast<py::function>()));
             }
             const toml::table table = to_table(doc, "");
             return std::make_unique<Simulation>(table, source, std::move(fs));
           }),
           py::arg("doc"), py::arg("source"), py::arg("functions"))
      .def_static("from_file", [](const std::string& path) {
        return std::make_unique<Simulation>(sesi::program::read_scene_file(path));
      })
      .def_static("paper", [] { return std::make_unique<Simulation>(sesi::program::paper_scene()); })
      .def_property_readonly("t", &Simulation::t)
      .def_property_readonly("step", &Simulation::step)
      .def_property_readonly("bodies", &Simulation::bodies)
      .def_property_readonly("dim", [](const Simulation& s) { return s.scene().dim(); })
      .def_property_readonly("space", [](const Simulation& s) { return std::string(sesi::program::space_name(s.scene().space.kind)); })
      .def_property_readonly("radius", [](const Simulation& s) { return s.scene().space.radius; })
      // A topology (docs/scene-format.md, [space]): the box's edges, the surface's genus, else None.
      .def_property_readonly("box", [](const Simulation& s) -> py::object {
        if (s.scene().space.box.empty()) return py::none();
        return py::cast(s.scene().space.box);
      })
      .def_property_readonly("genus", [](const Simulation& s) -> py::object {
        if (s.scene().space.genus == 0) return py::none();
        return py::int_(s.scene().space.genus);
      })
      .def_property_readonly("max_cutoff", [](const Simulation& s) -> py::object {
        if (!s.scene().space.has_topology()) return py::none();
        return py::float_(sesi::program::max_cutoff(s.scene().space));
      })
      .def_property_readonly("image_counts", [](const Simulation& s) -> py::object {
        if (s.scene().space.box.empty()) return py::none();
        return py::cast(s.image_counts());
      })
      .def_property_readonly("words", [](const Simulation& s) -> py::object {
        if (s.scene().space.genus == 0) return py::none();
        return py::cast(s.words());
      })
      .def_property_readonly("unwrapped_points", &Simulation::unwrapped_points)
      .def_property_readonly("name", [](const Simulation& s) { return s.scene().name; })
      .def_property_readonly("method", [](const Simulation& s) { return s.scene().integrator.method; })
      // method = "auto": why it picked `method` and `dt` (None for a named method).
      .def_property_readonly("auto_reason", [](const Simulation& s) -> py::object {
        const auto& a = s.scene().integrator.auto_choice;
        if (!a) return py::none();
        return py::str(a->reason);
      })
      .def_property_readonly("dt", [](const Simulation& s) -> py::object {
        if (!s.scene().integrator.dt) return py::none();
        return py::float_(*s.scene().integrator.dt);
      })
      .def_property_readonly("t_end", [](const Simulation& s) -> py::object {
        if (!s.scene().integrator.t_end) return py::none();
        return py::float_(*s.scene().integrator.t_end);
      })
      .def_property_readonly("output_every", [](const Simulation& s) { return s.scene().integrator.output_every; })
      .def_property_readonly("q", &Simulation::q)
      .def_property_readonly("p", &Simulation::p)
      .def_property_readonly("x", &Simulation::x)
      .def_property_readonly("v", &Simulation::v)
      .def_property_readonly("masses", &Simulation::masses)
      .def_property_readonly("momentum_names", &Simulation::momentum_names)
      .def("energy", &Simulation::energy)
      .def("momentum_map", &Simulation::momentum_map)
      .def("set_method", &Simulation::set_method)
      .def("set_dt", &Simulation::set_dt)
      .def("set_energy_guard", &Simulation::set_energy_guard)
      .def("set_threads", &Simulation::set_threads)
      .def("set_check_every", &Simulation::set_check_every)
      .def("set_thermostat", [](Simulation& s, py::object value) {
        if (value.is_none()) return s.set_thermostat(std::nullopt);
        s.set_thermostat(thermostat_of(value, "<simulation>"));
      })
      .def_property_readonly("thermostat", [](const Simulation& s) -> py::object {
        if (!s.scene().thermostat) return py::none();
        return thermostat_dict(*s.scene().thermostat);
      })
      .def("integrate", [](Simulation& s, double t) {
        const sesi::python::Report report = s.advance(t, std::numeric_limits<long>::max(), nullptr);
        if (report.interrupted) throw py::error_already_set();  // the KeyboardInterrupt raised at Ctrl-C
        return report;
      })
      .def("run", [](Simulation& s, double t, long output_every) {
        sesi::python::Rows rows;
        const sesi::python::Report report = s.advance(t, output_every, &rows);
        if (report.interrupted) throw py::error_already_set();
        const Eigen::Index n = s.bodies();
        const Eigen::Index dim = s.scene().dim();
        const Eigen::Index ambient = rows.x.empty() ? dim : rows.x.front().cols();
        py::dict out;
        out["t"] = py::array_t<double>(static_cast<py::ssize_t>(rows.t.size()), rows.t.data());
        out["energy"] = py::array_t<double>(static_cast<py::ssize_t>(rows.energy.size()), rows.energy.data());
        out["q"] = stack(rows.q, n, dim);
        out["p"] = stack(rows.p, n, dim);
        out["x"] = stack(rows.x, n, ambient);
        out["v"] = stack(rows.v, n, ambient);
        const Eigen::Index components = rows.momentum.empty() ? 0 : rows.momentum.front().size();
        py::array_t<double> momentum({static_cast<py::ssize_t>(rows.momentum.size()), static_cast<py::ssize_t>(components)});
        auto view = momentum.mutable_unchecked<2>();
        for (std::size_t r = 0; r < rows.momentum.size(); ++r) {
          for (Eigen::Index c = 0; c < components; ++c) view(static_cast<py::ssize_t>(r), c) = rows.momentum[r](c);
        }
        out["momentum"] = momentum;
        if (s.scene().space.has_topology()) out["unwrapped_points"] = stack(rows.unwrapped, n, ambient);
        if (!s.scene().space.box.empty()) {
          py::array_t<std::int64_t> counts({static_cast<py::ssize_t>(rows.image_counts.size()),
                                            static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(dim)});
          auto c = counts.mutable_unchecked<3>();
          for (std::size_t r = 0; r < rows.image_counts.size(); ++r) {
            for (Eigen::Index b = 0; b < n; ++b) {
              for (Eigen::Index k = 0; k < dim; ++k) c(static_cast<py::ssize_t>(r), b, k) = rows.image_counts[r](b, k);
            }
          }
          out["image_counts"] = counts;
        }
        if (s.scene().space.genus != 0) out["words"] = py::cast(rows.words);
        return py::make_tuple(report, out);
      });
}
