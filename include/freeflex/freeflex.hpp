#pragma once
// The whole public API of freeflex in one include, layer by layer (each layer uses only
// those before it): model → dynamics → analysis → sim → trajopt / control → io → app.
// docs/api.md states the conventions (results, Options and validate, Data workspaces,
// units, errors).
#include "freeflex/enum_names.hpp"
#include "freeflex/validation.hpp"
#include "freeflex/version.hpp"

#include "freeflex/model/basis.hpp"
#include "freeflex/model/beam.hpp"
#include "freeflex/model/instant.hpp"
#include "freeflex/model/loads.hpp"
#include "freeflex/model/modal_integrals.hpp"
#include "freeflex/model/quadrature.hpp"

#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/dynamics/full_model.hpp"
#include "freeflex/dynamics/zero_order.hpp"

#include "freeflex/analysis/exact_free_free.hpp"
#include "freeflex/analysis/free_vibration.hpp"
#include "freeflex/analysis/paper_reference.hpp"

#include "freeflex/sim/integrator.hpp"
#include "freeflex/sim/maneuver.hpp"
#include "freeflex/sim/prescribed.hpp"
#include "freeflex/sim/simulate.hpp"

#include "freeflex/trajopt/chattering.hpp"
#include "freeflex/trajopt/collocation.hpp"
#include "freeflex/trajopt/elastic_dynamics.hpp"
#include "freeflex/trajopt/maneuver_dynamics.hpp"
#include "freeflex/trajopt/problem.hpp"
#include "freeflex/trajopt/replay.hpp"
#include "freeflex/trajopt/rigid_dynamics.hpp"
#include "freeflex/trajopt/solve.hpp"
#include "freeflex/trajopt/trajectory.hpp"

#include "freeflex/control/closed_loop.hpp"
#include "freeflex/control/lqg.hpp"
#include "freeflex/control/lqr.hpp"
#include "freeflex/control/lyapunov.hpp"
#include "freeflex/control/metrics.hpp"
#include "freeflex/control/suppression.hpp"
#include "freeflex/control/switch_time.hpp"
#include "freeflex/control/tvlqr.hpp"

#include "freeflex/io/design.hpp"
#include "freeflex/io/output.hpp"
#include "freeflex/io/plot.hpp"

#include "freeflex/app/progress.hpp"
#include "freeflex/app/run.hpp"
#include "freeflex/app/studies.hpp"
#include "freeflex/app/sweep.hpp"
