#pragma once
/// @file sesi.hpp
/// Everything of the core library (Eigen only). The odeint interoperation is sesi/odeint.hpp.

#include "sesi/chart.hpp"
#include "sesi/check_chart.hpp"
#include "sesi/coefficients.hpp"
#include "sesi/config.hpp"
#include "sesi/diagnostics.hpp"
#include "sesi/guard.hpp"
#include "sesi/potentials.hpp"
#include "sesi/processed.hpp"
#include "sesi/spaces/euclidean.hpp"
#include "sesi/spaces/hyperbolic.hpp"
#include "sesi/spaces/sphere.hpp"
#include "sesi/special_functions.hpp"
#include "sesi/state.hpp"
#include "sesi/stepper.hpp"
#include "sesi/system.hpp"
#include "sesi/recharting.hpp"
#include "sesi/topologies/hyperbolic_surface.hpp"
#include "sesi/topologies/periodic_box.hpp"
#include "sesi/topology.hpp"
