#pragma once
/// @file thermostat_stepper.hpp
/// The stepper of a thermostatted run (Scene::thermostat; docs/thermostats.md): the composition
/// engine's kick-drift-kick Strang step with sesi::Thermostat as its stage (include/sesi/
/// thermostat.hpp), re-charting on S^n and H^n as ProgramComposition does. One type for every
/// thermostat kind, so each (space, dimension) instantiates one more engine, not four.
/// Needs Random123's headers (the noise; include/sesi/random.hpp).

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <sesi/coefficients.hpp>
#include <sesi/recharting.hpp>
#include <sesi/stepper.hpp>
#include <sesi/thermostat.hpp>

#include "methods.hpp"
#include "scene.hpp"

namespace sesi::program {

/// The thermostatted engine of the program for a chart: Strang's table as runtime weights (the
/// program's engines all hold their tables as data), the thermostat as the stage.
template <class Chart>
using ThermostatEngine = sesi::Composition<coefficients::Runtime, Chart, sesi::Splitting::kick_drift_kick,
                                           sesi::Thermostat<Chart>>;
template <class Chart>
using ProgramThermostatted =
    std::conditional_t<sesi::Rechartable<Chart>, sesi::Recharting<ThermostatEngine<Chart>>, ThermostatEngine<Chart>>;

/// The library's kind of a scene's `kind` (the scene reader admits these four only).
inline sesi::ThermostatKind thermostat_kind(const std::string& kind) {
  if (kind == "langevin") return sesi::ThermostatKind::langevin;
  if (kind == "nose-hoover") return sesi::ThermostatKind::nose_hoover;
  if (kind == "csvr") return sesi::ThermostatKind::csvr;
  if (kind == "brownian") return sesi::ThermostatKind::brownian;
  throw std::logic_error("unknown thermostat kind '" + kind + "' (the scene reader admits four)");
}

/// The thermostat of spec at its schedule's first temperature (the run loop sets each step's).
inline sesi::ThermostatParams<double> thermostat_params(const ThermostatSpec& spec) {
  sesi::ThermostatParams<double> params;
  params.kind = thermostat_kind(spec.kind);
  params.kT = spec.temperature_at(0.0);
  params.gamma = spec.gamma;
  params.tau = spec.tau;
  params.chain = spec.chain;
  params.seed = spec.seed;
  return params;
}

/// A thermostatted run's stepper for Sys (method sesi2 only: the scene checks refuse others).
template <class Sys>
class ThermostatStepper final : public AnyStepper<Sys> {
  using Chart = typename Sys::Chart;
  using Engine = ProgramThermostatted<Chart>;

 public:
  ThermostatStepper(const Sys& sys, const ThermostatSpec& spec) : sys_(sys), engine_(make_engine(spec)) {}
  void step(typename Sys::StateType& x, double t, double dt) override {
    engine_.do_step(std::cref(sys_), x, t, dt);
  }
  typename Sys::Workspace* workspace() override { return &engine_.workspace(); }
  sesi::Thermostat<Chart>& thermostat() { return engine_.stage(); }
  const sesi::Thermostat<Chart>& thermostat() const { return engine_.stage(); }

 private:
  static Engine make_engine(const ThermostatSpec& spec) {
    sesi::Thermostat<Chart> thermostat(thermostat_params(spec));
    auto engine = ThermostatEngine<Chart>::template of<coefficients::Strang>(std::move(thermostat));
    if constexpr (sesi::Rechartable<Chart>) {
      return Engine(sesi::RechartPolicy<typename Chart::Scalar>{}, std::move(engine));
    } else {
      return engine;
    }
  }
  const Sys& sys_;
  Engine engine_;
};

}  // namespace sesi::program
