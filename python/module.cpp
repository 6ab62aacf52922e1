// The Python module `freeflex` (pybind11): designs and their studies, beams, loads and
// actuators built in code, maneuvers, the first-order model, TV-LQR, open- and
// closed-loop simulation. Results come back as NumPy arrays (copies); enums are their
// names as in design files ("hermite_simpson", "thruster"); library errors become
// Python exceptions with the library's message: std::invalid_argument -> ValueError,
// DesignError -> freeflex.DesignError (a ValueError), IoError -> OSError; a wrong Python
// type -> TypeError (pybind11). Numerical failure is a result with .ok and .message.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <sstream>

#include "freeflex/freeflex.hpp"

namespace py = pybind11;
using namespace freeflex;

namespace {

template <class E>
E enum_from(const std::string& what, const std::string& name) {
  try {
    return from_string<E>(name);
  } catch (const std::exception& e) {
    throw std::invalid_argument(what + ": " + e.what());
  }
}

void finite_or_throw(const std::string& what, double v) {
  if (!std::isfinite(v)) throw std::invalid_argument(what + " = " + std::to_string(v) + ", must be finite");
}

/// The first-order model with everything it refers to kept alive.
struct PyFirstOrderModel {
  std::shared_ptr<const FlexibleBody> body;
  std::shared_ptr<const RigidTrajectory> nominal;
  Excitation loads;
  ActuatorCommandFunction u0;
  std::vector<int> actuators;
  std::unique_ptr<FirstOrderModel> model;
};

std::shared_ptr<PyFirstOrderModel> make_first_order(std::shared_ptr<FlexibleBody> body,
                                                     const std::optional<FlownManeuver>& maneuver, Excitation loads,
                                                     std::vector<int> actuators, double until_s,
                                                     const SimulationOptions& sim) {
  auto m = std::make_shared<PyFirstOrderModel>();
  const int ne = static_cast<int>(body->elements().size());
  if (loads.profiles.empty()) loads.profiles.assign(static_cast<std::size_t>(ne), std::nullopt);
  if (static_cast<int>(loads.profiles.size()) != ne)
    throw std::invalid_argument("first_order_model: loads has " + std::to_string(loads.profiles.size()) +
                                " profile slots, the body " + std::to_string(ne) + " elements");
  if (actuators.empty()) throw std::invalid_argument("first_order_model: actuators is empty; give at least one element index");
  for (int a : actuators)
    if (a < 0 || a >= ne)
      throw std::invalid_argument("first_order_model: actuators: " + std::to_string(a) + " is not an element (0.." +
                                  std::to_string(ne - 1) + ")");
  m->body = body;
  m->loads = loads;
  m->actuators = actuators;
  if (maneuver) {
    if (!maneuver->motion || !maneuver->commands) throw std::invalid_argument("first_order_model: the maneuver is empty");
    std::vector<int> slot;
    for (int a : maneuver->actuators) {
      auto it = std::find(actuators.begin(), actuators.end(), a);
      if (it == actuators.end())
        throw std::invalid_argument("first_order_model: actuators must include the maneuver's element " + std::to_string(a));
      slot.push_back(static_cast<int>(it - actuators.begin()));
    }
    const auto commands = maneuver->commands;
    const double end = maneuver->duration_s;
    m->u0 = [commands, slot, end](const Instant& at, Eigen::Ref<Eigen::VectorXd> u) {
      u.setZero();
      if (at.piece_mid > end) return;
      Eigen::VectorXd c(static_cast<Eigen::Index>(slot.size()));
      commands(at, c);
      for (std::size_t k = 0; k < slot.size(); ++k) u(slot[k]) = c(static_cast<Eigen::Index>(k));
    };
    m->nominal = maneuver->nominal();
  } else {
    finite_or_throw("first_order_model: until_s", until_s);
    if (!(until_s > 0)) throw std::invalid_argument("first_order_model: until_s must be > 0 without a maneuver");
    SimulationOptions s = with_reusable_nominal(sim);  // the model's nominal motion
    s.duration_s = until_s;
    const PerturbationResult p = simulate_perturbation(*body, loads, s);
    if (!p.total.ok()) throw std::runtime_error("first_order_model: the zero-order motion failed: " + p.total.message);
    m->nominal = p.nominal;
  }
  m->model = std::make_unique<FirstOrderModel>(*m->body, *m->nominal,
                                               nominal_element_commands(m->loads, m->actuators, m->u0), m->actuators);
  return m;
}

py::array_t<double> gains_array(const TvlqrResult& r) {
  if (r.K.empty()) return py::array_t<double>(std::vector<py::ssize_t>{0, 0, 0});
  const py::ssize_t G = static_cast<py::ssize_t>(r.K.size()), m = r.K[0].rows(), n = r.K[0].cols();
  py::array_t<double> a(std::vector<py::ssize_t>{G, m, n});
  auto v = a.mutable_unchecked<3>();
  for (py::ssize_t i = 0; i < G; ++i)
    for (py::ssize_t j = 0; j < m; ++j)
      for (py::ssize_t k = 0; k < n; ++k) v(i, j, k) = r.K[static_cast<std::size_t>(i)](j, k);
  return a;
}

std::string summary_text(const Design& d, const RunResult& r) { return summary_json(d, r).dump(); }

}  // namespace

PYBIND11_MODULE(_freeflex, m) {
  m.doc() = "freeflex: controller design for free-free flexible beams (see README, Python)";
  py::register_exception<DesignError>(m, "DesignError", PyExc_ValueError);
  py::register_exception<IoError>(m, "IoError", PyExc_OSError);
  m.attr("__version__") = version();

  // ---- model
  py::class_<ForceElement>(m, "ForceElement")
      .def(py::init([](const std::string& name, const std::string& type, double position_m, Eigen::Vector2d direction,
                       bool follow_slope) {
             finite_or_throw("ForceElement.position_m", position_m);
             if (!direction.allFinite()) throw std::invalid_argument("ForceElement.direction must be finite");
             return ForceElement{name, enum_from<ForceElement::Type>("ForceElement.type", type), position_m, direction,
                                 follow_slope};
           }),
           py::arg("name"), py::arg("type"), py::arg("position_m"), py::arg("direction") = Eigen::Vector2d(0.0, 1.0),
           py::arg("follow_slope") = false)
      .def_readonly("name", &ForceElement::name)
      .def_property_readonly("type", [](const ForceElement& e) { return std::string(to_string(e.type)); })
      .def_readonly("position_m", &ForceElement::position_m)
      .def_readonly("direction", &ForceElement::direction);

  py::class_<TimeProfile>(m, "TimeProfile")
      .def(py::init([](const std::string& kind, std::vector<double> times, std::vector<double> values) {
             return TimeProfile(enum_from<TimeProfile::Kind>("TimeProfile.kind", kind), times, values);
           }),
           py::arg("kind"), py::arg("times"), py::arg("values"))
      .def("value", py::overload_cast<double>(&TimeProfile::value, py::const_), py::arg("t"))
      .def_property_readonly("times", &TimeProfile::times)
      .def_property_readonly("values", &TimeProfile::values);

  py::class_<Excitation>(m, "Excitation")
      .def(py::init([](std::vector<std::optional<TimeProfile>> profiles) { Excitation e;
             e.profiles = std::move(profiles);
             return e;
           }),
           py::arg("profiles"))
      .def_readonly("profiles", &Excitation::profiles);

  py::class_<FlexibleBody, std::shared_ptr<FlexibleBody>>(m, "Body")
      .def(py::init([](double length_m, double mass_kg, double bending_stiffness_Nm2, int noa,
                       std::vector<ForceElement> elements, std::vector<double> damping_ratios) {
             for (auto [k, v] : {std::pair<const char*, double>{"length_m", length_m}, {"mass_kg", mass_kg},
                                 {"bending_stiffness_Nm2", bending_stiffness_Nm2}})
               finite_or_throw(std::string("Body.") + k, v);
             return std::make_shared<FlexibleBody>(
                 Beam(BeamProperties::uniform(length_m, mass_kg, bending_stiffness_Nm2)), noa, elements, damping_ratios);
           }),
           py::arg("length_m"), py::arg("mass_kg"), py::arg("bending_stiffness_Nm2"), py::arg("noa") = 6,
           py::arg("elements") = std::vector<ForceElement>{}, py::arg("damping_ratios") = std::vector<double>{})
      .def_property_readonly("dofs", &FlexibleBody::dofs)
      .def_property_readonly("n", &FlexibleBody::n)
      .def_property_readonly("elements", &FlexibleBody::elements);
  m.def("body_of_design", [](const Design& d) {
    return std::make_shared<FlexibleBody>(Beam(d.beam), d.noa, d.force_elements(), d.damping_ratios);
  });
  m.def("vibration_energy", [](const FlexibleBody& b, const Eigen::MatrixXd& z, const Eigen::MatrixXd& z_dot) {
    if (z.cols() != b.dofs() || z_dot.cols() != b.dofs() || z.rows() != z_dot.rows())
      throw std::invalid_argument("vibration_energy: z and z_dot must both be T x " + std::to_string(b.dofs()) +
                                  " (rows [Rx, Ry, theta, q]), got " + std::to_string(z.rows()) + " x " +
                                  std::to_string(z.cols()) + " and " + std::to_string(z_dot.rows()) + " x " +
                                  std::to_string(z_dot.cols()));
    const int n = b.n();
    Eigen::VectorXd e(z.rows());
    for (Eigen::Index i = 0; i < z.rows(); ++i)
      e(i) = b.vibration_energy(z.row(i).tail(n).transpose(), z_dot.row(i).tail(n).transpose());
    return e;
  }, py::arg("body"), py::arg("z"), py::arg("z_dot"), "Elastic energy [J] of each row of a history.");
  m.def("tip_deflection", [](const FlexibleBody& b, const Eigen::MatrixXd& z) {
    if (z.cols() != b.dofs())
      throw std::invalid_argument("tip_deflection: z must be T x " + std::to_string(b.dofs()) + ", got " +
                                  std::to_string(z.rows()) + " x " + std::to_string(z.cols()));
    const Eigen::RowVectorXd l = b.basis().value(b.beam().x_left()), r = b.basis().value(b.beam().x_right());
    Eigen::MatrixXd w(z.rows(), 2);
    for (Eigen::Index i = 0; i < z.rows(); ++i) {
      w(i, 0) = l.dot(z.row(i).tail(b.n()));
      w(i, 1) = r.dot(z.row(i).tail(b.n()));
    }
    return w;
  }, py::arg("body"), py::arg("z"), "Elastic deflection [m] of the left and right ends, per row.");
  m.def("vibration_weight", &vibration_weight, py::arg("body"), py::arg("weight_elastic"),
        py::arg("weight_rigid_position"), py::arg("weight_rigid_rate"),
        "The state weight Q of [controller]: energy of the elastic motion plus the rigid errors.");

  // ---- options
  py::class_<IntegratorOptions>(m, "IntegratorOptions")
      .def(py::init<>())
      .def_readwrite("rtol", &IntegratorOptions::rtol)
      .def_readwrite("atol", &IntegratorOptions::atol)
      .def_readwrite("max_steps", &IntegratorOptions::max_steps)
      .def_property(
          "method", [](const IntegratorOptions& o) { return std::string(to_string(o.method)); },
          [](IntegratorOptions& o, const std::string& s) { o.method = enum_from<IntegratorOptions::Method>("method", s); });
  py::class_<SimulationOptions>(m, "SimulationOptions")
      .def(py::init<>())
      .def_readwrite("integrator", &SimulationOptions::integrator)
      .def_readwrite("duration_s", &SimulationOptions::duration_s)
      .def_readwrite("output_step_s", &SimulationOptions::output_step_s)
      .def_readwrite("trajectory_step_s", &SimulationOptions::trajectory_step_s)
      .def_property_readonly("trajectory_step_in_use_s", &trajectory_step,
                             "the sampling step of the zero-order motion these options give (0 above: automatic)")
      .def_property(
          "full_variables", [](const SimulationOptions& o) { return std::string(to_string(o.full_variables)); },
          [](SimulationOptions& o, const std::string& s) {
            o.full_variables = enum_from<SimulationOptions::Variables>("full_variables", s);
          },
          "the full model's integration variables: physical, rest_modes (the same steps, a cheaper right-hand "
          "side at many functions) or modal")
      .def_property(
          "first_order_variables",
          [](const SimulationOptions& o) { return std::string(to_string(o.first_order_variables)); },
          [](SimulationOptions& o, const std::string& s) {
            o.first_order_variables = enum_from<SimulationOptions::Variables>("first_order_variables", s);
          })
      .def_property(
          "first_order_solver",
          [](const SimulationOptions& o) { return std::string(to_string(o.first_order_solver)); },
          [](SimulationOptions& o, const std::string& s) {
            o.first_order_solver = enum_from<SimulationOptions::FirstOrderSolver>("first_order_solver", s);
          });
  py::class_<TvlqrOptions>(m, "TvlqrOptions")
      .def(py::init<>())
      .def_readwrite("grid_step_s", &TvlqrOptions::grid_step_s)
      .def_readwrite("rtol", &TvlqrOptions::rtol)
      .def_readwrite("atol", &TvlqrOptions::atol)
      .def_readwrite("Qf", &TvlqrOptions::Qf)
      .def_readwrite("breakpoints", &TvlqrOptions::breakpoints)
      .def_property(
          "method", [](const TvlqrOptions& o) { return std::string(to_string(o.method)); },
          [](TvlqrOptions& o, const std::string& s) { o.method = enum_from<TvlqrOptions::Method>("TvlqrOptions.method", s); });
  py::class_<TrajoptOptions>(m, "TrajoptOptions")
      .def(py::init<>())
      .def_readwrite("intervals", &TrajoptOptions::intervals)
      .def_readwrite("tol", &TrajoptOptions::tol)
      .def_readwrite("max_iter", &TrajoptOptions::max_iter)
      .def_readwrite("coarse_start", &TrajoptOptions::coarse_start)
      .def_readwrite("verbose", &TrajoptOptions::verbose)
      .def_property(
          "transcription", [](const TrajoptOptions& o) { return std::string(to_string(o.transcription)); },
          [](TrajoptOptions& o, const std::string& s) {
            o.transcription = enum_from<Transcription>("transcription", s);
          })
      .def_property(
          "linear_solver", [](const TrajoptOptions& o) { return std::string(to_string(o.linear_solver)); },
          [](TrajoptOptions& o, const std::string& s) {
            o.linear_solver = enum_from<LinearSolver>("linear_solver", s);
          });
  py::class_<SuppressionOptions>(m, "SuppressionOptions")
      .def(py::init<>())
      .def_readwrite("simulation", &SuppressionOptions::simulation)
      .def_readwrite("tvlqr", &SuppressionOptions::tvlqr)
      .def_readwrite("closed_loop", &SuppressionOptions::closed_loop)
      .def_property(
          "closed_loop_first_order_method",
          [](const SuppressionOptions& o) { return std::string(to_string(o.closed_loop_first_order_method)); },
          [](SuppressionOptions& o, const std::string& s) {
            o.closed_loop_first_order_method = enum_from<ClosedLoopMethod>("closed_loop_first_order_method", s);
          })
      .def_readwrite("closed_loop_gauss_steps", &SuppressionOptions::closed_loop_gauss_steps);

  // ---- results
  py::class_<SimulationResult>(m, "SimulationResult")
      .def_property_readonly("ok", &SimulationResult::ok)
      .def_readonly("message", &SimulationResult::message)
      .def_readonly("t", &SimulationResult::t)
      .def_readonly("z", &SimulationResult::z)
      .def_readonly("z_dot", &SimulationResult::z_dot);
  py::class_<PerturbationResult>(m, "PerturbationResult")
      .def_readonly("total", &PerturbationResult::total)
      .def_readonly("zero_order", &PerturbationResult::zero_order);
  py::class_<ClosedLoopResult>(m, "ClosedLoopResult")
      .def_property_readonly("ok", &ClosedLoopResult::ok)
      .def_readonly("message", &ClosedLoopResult::message)
      .def_readonly("t", &ClosedLoopResult::t)
      .def_readonly("z", &ClosedLoopResult::z)
      .def_readonly("z_dot", &ClosedLoopResult::z_dot)
      .def_readonly("commands", &ClosedLoopResult::commands)
      .def_readonly("demanded", &ClosedLoopResult::demanded)
      .def_readonly("saturated_fraction", &ClosedLoopResult::saturated_fraction)
      .def_readonly("peak_command", &ClosedLoopResult::peak_command);
  py::class_<TvlqrResult>(m, "TvlqrResult")
      .def_property_readonly("ok", &TvlqrResult::ok)
      .def_readonly("message", &TvlqrResult::message)
      .def_property_readonly("t", [](const TvlqrResult& r) { return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(r.t.data(), static_cast<Eigen::Index>(r.t.size()))); })
      .def_property_readonly("K", &gains_array, "gains, shape (grid times, inputs, states)")
      .def_readonly("feedforward", &TvlqrResult::feedforward)
      .def_readonly("P0", &TvlqrResult::P0)
      .def_readonly("Qf", &TvlqrResult::Qf)
      .def_readonly("wall_time_s", &TvlqrResult::wall_time_s)
      .def_property_readonly("method", [](const TvlqrResult& r) { return std::string(to_string(r.method)); })
      .def_readonly("steps", &TvlqrResult::steps)
      .def("gain", [](const TvlqrResult& r, double t) {
        finite_or_throw("gain: t", t);
        if (r.K.empty()) throw std::invalid_argument("gain: the TV-LQR has no gains (it failed: " + r.message + ")");
        return r.gain(t);
      }, py::arg("t"))
      .def("feedforward_at", [](const TvlqrResult& r, double t) {
        finite_or_throw("feedforward_at: t", t);
        if (r.K.empty()) throw std::invalid_argument("feedforward_at: the TV-LQR has no gains (it failed: " + r.message + ")");
        return r.feedforward_at(t);
      }, py::arg("t"));
  py::class_<FlownManeuver>(m, "FlownManeuver")
      .def_readonly("actuators", &FlownManeuver::actuators)
      .def_readonly("duration_s", &FlownManeuver::duration_s)
      .def_readonly("breakpoints", &FlownManeuver::breakpoints);
  py::class_<TrajoptResult>(m, "TrajoptResult")
      .def_property_readonly("ok", &TrajoptResult::ok)
      .def_readonly("message", &TrajoptResult::message)
      .def_property_readonly("status", [](const TrajoptResult& r) { return std::string(to_string(r.status)); })
      .def_readonly("objective", &TrajoptResult::objective)
      .def_readonly("iterations", &TrajoptResult::iterations)
      .def_readonly("warm_start_iterations", &TrajoptResult::warm_start_iterations)
      .def_readonly("warm_started", &TrajoptResult::warm_started)
      .def_readonly("duration_s", &TrajoptResult::duration_s)
      .def_readonly("max_defect", &TrajoptResult::max_defect)
      .def_readonly("t", &TrajoptResult::t)
      .def_readonly("x", &TrajoptResult::x)
      .def_readonly("u", &TrajoptResult::u)
      .def_readonly("x_elastic", &TrajoptResult::x_elastic)
      .def_readonly("terminal_vibration_energy_J", &TrajoptResult::terminal_vibration_energy_J)
      .def_readonly("peak_tip_deflection_m", &TrajoptResult::peak_tip_deflection_m)
      .def_readonly("control_energy", &TrajoptResult::control_energy)
      .def_readonly("mode_frequencies", &TrajoptResult::mode_frequencies)
      .def_readonly("max_interval_s", &TrajoptResult::max_interval_s)
      .def_readonly("unresolved_modes", &TrajoptResult::unresolved_modes,
                    "0-based indices into mode_frequencies of the modes the mesh does not resolve (omega h > 2); "
                    "summary.json and the messages number modes from 1")
      .def_property_readonly("unresolved_modes_message", [](const TrajoptResult& r) { return unresolved_modes_message(r); });
  py::class_<SuppressionResult>(m, "SuppressionResult")
      .def_property_readonly("ok", &SuppressionResult::ok)
      .def_readonly("message", &SuppressionResult::message)
      .def_property_readonly("status", [](const SuppressionResult& r) { return std::string(to_string(r.status)); })
      .def_readonly("open_loop_first_order", &SuppressionResult::open_loop_first_order)
      .def_readonly("open_loop_full", &SuppressionResult::open_loop_full)
      .def_readonly("law", &SuppressionResult::law)
      .def_readonly("closed_loop_first_order", &SuppressionResult::closed_loop_first_order)
      .def_readonly("closed_loop_full", &SuppressionResult::closed_loop_full);

  // ---- maneuvers
  py::class_<ManeuverProblem>(m, "ManeuverProblem")
      .def(py::init<>())
      .def_readwrite("actuators", &ManeuverProblem::actuators)
      .def_readwrite("u_min", &ManeuverProblem::u_min)
      .def_readwrite("u_max", &ManeuverProblem::u_max)
      .def_readwrite("x_initial", &ManeuverProblem::x_initial)
      .def_readwrite("x_final", &ManeuverProblem::x_final)
      .def_readwrite("free_time", &ManeuverProblem::free_time)
      .def_readwrite("duration_s", &ManeuverProblem::duration_s)
      .def_readwrite("t_min_s", &ManeuverProblem::t_min_s)
      .def_readwrite("t_max_s", &ManeuverProblem::t_max_s)
      .def_readwrite("w_energy", &ManeuverProblem::w_energy)
      .def_readwrite("w_time", &ManeuverProblem::w_time)
      .def_readwrite("w_smooth", &ManeuverProblem::w_smooth)
      .def_readwrite("zero_end_commands", &ManeuverProblem::zero_end_commands)
      .def_readwrite("elastic", &ManeuverProblem::elastic)
      .def_readwrite("elastic_modes", &ManeuverProblem::elastic_modes, "-1: every elastic coordinate")
      .def_readwrite("modes_at_rest", &ManeuverProblem::modes_at_rest, "-1: all the problem holds")
      .def_readwrite("w_vibration", &ManeuverProblem::w_vibration)
      .def_readwrite("tip_deflection_limit_m", &ManeuverProblem::tip_deflection_limit_m);
  m.def("solve_maneuver", &solve_maneuver, py::arg("body"), py::arg("problem"), py::arg("options") = TrajoptOptions{},
        py::call_guard<py::gil_scoped_release>(), "The optimal maneuver by collocation and Ipopt: the rigid motion (zero-order model), with the elastic "
        "modes inside the problem when problem.elastic; started from a coarse solution unless "
        "options.coarse_start is False.");
  m.def("flown_maneuver", [](const TrajoptResult& r, const ManeuverProblem& p) {
    if (!r.ok()) throw std::invalid_argument("flown_maneuver: the maneuver was not solved (" + r.message + ")");
    return flown_maneuver(r, p);
  }, py::arg("result"), py::arg("problem"));

  // ---- simulation, first-order model, TV-LQR, closed loop
  m.def("simulate_full", [](const FlexibleBody& b, const Excitation& ex, const SimulationOptions& o) {
    return simulate_full(b, ex, o);
  }, py::arg("body"), py::arg("loads"), py::arg("options") = SimulationOptions{}, py::call_guard<py::gil_scoped_release>());
  m.def("simulate_perturbation", &simulate_perturbation, py::arg("body"), py::arg("loads"),
        py::arg("options") = SimulationOptions{}, py::call_guard<py::gil_scoped_release>());

  py::class_<PyFirstOrderModel, std::shared_ptr<PyFirstOrderModel>>(m, "FirstOrderModel")
      .def_property_readonly("state_size", [](const PyFirstOrderModel& f) { return f.model->state_size(); })
      .def_property_readonly("input_size", [](const PyFirstOrderModel& f) { return f.model->input_size(); })
      .def("state_space", [](const PyFirstOrderModel& f, double t) {
        finite_or_throw("state_space: t", t);
        const StateSpace s = f.model->state_space(Instant::at(t));
        return py::make_tuple(s.A, s.B, s.g);
      }, py::arg("t"), "(A, B, g) of x1' = A x1 + B u1 + g at time t")
      .def("nominal", [](const PyFirstOrderModel& f, double t) {
        finite_or_throw("nominal: t", t);
        const RigidState s = f.nominal->at(Instant::at(t));
        return py::make_tuple(Eigen::Vector3d(s.pos), Eigen::Vector3d(s.vel), Eigen::Vector3d(s.acc));
      }, py::arg("t"));
  m.def("first_order_model", &make_first_order, py::arg("body"), py::arg("maneuver") = std::nullopt,
        py::arg("loads") = Excitation{}, py::arg("actuators") = std::vector<int>{}, py::arg("until_s") = 0.0,
        py::arg("simulation") = SimulationOptions{},
        "The first-order model about a flown maneuver (or about the loads' zero-order motion up to until_s).");
  m.def("solve_tvlqr", [](const PyFirstOrderModel& f, double t0, double tf, const Eigen::MatrixXd& Q,
                          const Eigen::MatrixXd& R, const TvlqrOptions& o) {
    finite_or_throw("solve_tvlqr: t0", t0);
    finite_or_throw("solve_tvlqr: tf", tf);
    TvlqrOptions to = o;
    for (double b : f.loads.breakpoints()) to.breakpoints.push_back(b);
    py::gil_scoped_release release;
    return solve_tvlqr(*f.model, t0, tf, Q, R, to);
  }, py::arg("model"), py::arg("t0"), py::arg("tf"), py::arg("Q"), py::arg("R"), py::arg("options") = TvlqrOptions{});
  auto closed = [](bool full) {
    return [full](const PyFirstOrderModel& f, const TvlqrResult& law, double until_s, Eigen::VectorXd limits,
                  double output_step_s, const IntegratorOptions& integrator, const std::string& method,
                  int gauss_steps) {
      finite_or_throw("until_s", until_s);
      if (law.K.empty()) throw std::invalid_argument("closed loop: the law has no gains (the TV-LQR failed: " + law.message + ")");
      ClosedLoopOptions co;
      co.integrator = integrator;
      co.first_order_method = enum_from<ClosedLoopMethod>("method", method);
      if (full && co.first_order_method != ClosedLoopMethod::Cvodes)
        throw std::invalid_argument("method = \"" + method + "\": the full model's closed loop is integrated by CVODES only");
      co.gauss_steps = gauss_steps;
      co.t_begin = 0.0;
      co.t_end = until_s;
      co.output_step_s = output_step_s;
      co.limits = limits;
      for (double b : f.loads.breakpoints()) co.breakpoints.push_back(b);
      py::gil_scoped_release release;
      return full ? simulate_closed_loop_full(*f.model, f.loads, f.u0, law, co)
                  : simulate_closed_loop_first_order(*f.model, law, f.u0, co);
    };
  };
  m.def("simulate_closed_loop_first_order", closed(false), py::arg("model"), py::arg("law"), py::arg("until_s"),
        py::arg("limits") = Eigen::VectorXd(), py::arg("output_step_s") = 0.005,
        py::arg("integrator") = closed_loop_integrator(), py::arg("method") = "cvodes",
        py::arg("gauss_steps") = ClosedLoopOptions{}.gauss_steps,
        "method: \"cvodes\" (integrator's settings) or \"gauss\" (gauss_steps per interval, ClosedLoopMethod)");
  m.def("simulate_closed_loop_full", closed(true), py::arg("model"), py::arg("law"), py::arg("until_s"),
        py::arg("limits") = Eigen::VectorXd(), py::arg("output_step_s") = 0.005,
        py::arg("integrator") = closed_loop_integrator(), py::arg("method") = "cvodes",
        py::arg("gauss_steps") = ClosedLoopOptions{}.gauss_steps,
        "the full model's closed loop is always integrated by CVODES (method must be \"cvodes\")");

  // ---- the whole chain in one call
  py::class_<SuppressionProblem>(m, "SuppressionProblem")
      .def(py::init<>())
      .def_readwrite("loads", &SuppressionProblem::loads)
      .def_readwrite("maneuver", &SuppressionProblem::maneuver)
      .def_readwrite("actuators", &SuppressionProblem::actuators)
      .def_readwrite("limits", &SuppressionProblem::limits)
      .def_readwrite("Q", &SuppressionProblem::Q)
      .def_readwrite("R", &SuppressionProblem::R)
      .def_readwrite("horizon_s", &SuppressionProblem::horizon_s)
      .def_readwrite("until_s", &SuppressionProblem::until_s);
  m.def("suppress_vibration", [](const FlexibleBody& b, SuppressionProblem p, const SuppressionOptions& o) {
    if (p.loads.profiles.empty()) p.loads.profiles.assign(b.elements().size(), std::nullopt);
    py::gil_scoped_release release;
    return suppress_vibration(b, p, o);
  }, py::arg("body"), py::arg("problem"), py::arg("options") = SuppressionOptions{},
        "maneuver -> nominal motion -> first-order model -> TV-LQR -> closed loops, against the open loop");

  // ---- designs
  py::class_<Design>(m, "Design")
      .def_readonly("source", &Design::source)
      .def_readonly("title", &Design::title)
      .def_readonly("noa", &Design::noa)
      .def_property_readonly("excitation", &Design::excitation);
  m.def("load_design", &load_design, py::arg("path"),
        "Reads and validates a design file; raises DesignError listing every problem (file, line, key).");
  m.def("parse_design", [](const std::string& text, const std::string& source) {
    return parse_design(text, source);
  }, py::arg("text"), py::arg("source") = "<string>");
  py::class_<SuppressionStudyResult::Case>(m, "Case")
      .def_readonly("name", &SuppressionStudyResult::Case::name)
      .def_readonly("model", &SuppressionStudyResult::Case::model)
      .def_readonly("t", &SuppressionStudyResult::Case::t)
      .def_readonly("z", &SuppressionStudyResult::Case::z)
      .def_readonly("z_dot", &SuppressionStudyResult::Case::z_dot)
      .def_readonly("commands", &SuppressionStudyResult::Case::commands)
      .def_property_readonly("residual_vibration_energy_J",
                             [](const SuppressionStudyResult::Case& c) { return c.metrics.residual_vibration_energy_J; })
      .def_readonly("energy_error_estimate_J", &SuppressionStudyResult::Case::energy_error_estimate_J,
                    "change of the residual energy at 10x tighter tolerances (NaN: not estimated)");
  py::class_<SuppressionStudyResult>(m, "SuppressionStudyResult")
      .def_property_readonly("ok", &SuppressionStudyResult::ok)
      .def_readonly("message", &SuppressionStudyResult::message)
      .def_readonly("chain", &SuppressionStudyResult::chain)
      .def_readonly("cases", &SuppressionStudyResult::cases);
  py::class_<ReplayCheck>(m, "ReplayCheck")
      .def_readonly("ok", &ReplayCheck::ok)
      .def_readonly("flagged", &ReplayCheck::flagged)
      .def_readonly("message", &ReplayCheck::message)
      .def_readonly("position_miss_m", &ReplayCheck::position_miss_m)
      .def_readonly("theta_miss_rad", &ReplayCheck::theta_miss_rad)
      .def_readonly("rate_miss", &ReplayCheck::rate_miss)
      .def_readonly("position_scale_m", &ReplayCheck::position_scale_m)
      .def_readonly("theta_scale_rad", &ReplayCheck::theta_scale_rad);
  m.def("check_replay", &check_replay, py::arg("body"), py::arg("problem"), py::arg("result"),
        "The optimized commands flown on the zero-order model against the optimizer's final state.");
  py::class_<ManeuverStudyResult>(m, "ManeuverStudyResult")
      .def_property_readonly("ok", &ManeuverStudyResult::ok)
      .def_readonly("message", &ManeuverStudyResult::message)
      .def_readonly("trajopt", &ManeuverStudyResult::trajopt)
      .def_readonly("replay", &ManeuverStudyResult::replay);
  py::class_<LqgStudyResult::Case>(m, "LqgCase")
      .def_readonly("name", &LqgStudyResult::Case::name)
      .def_property_readonly("t", [](const LqgStudyResult::Case& c) { return c.run.t; })
      .def_property_readonly("z", [](const LqgStudyResult::Case& c) { return c.run.z; })
      .def_property_readonly("commands", [](const LqgStudyResult::Case& c) { return c.run.commands; })
      .def_property_readonly("residual_vibration_energy_J",
                             [](const LqgStudyResult::Case& c) { return c.metrics.residual_vibration_energy_J; })
      .def_readonly("energy_error_estimate_J", &LqgStudyResult::Case::energy_error_estimate_J,
                    "change of the residual energy at 10x tighter tolerances (NaN: not estimated)");
  py::class_<LqgStudyResult>(m, "LqgStudyResult")
      .def_property_readonly("ok", &LqgStudyResult::ok)
      .def_readonly("message", &LqgStudyResult::message)
      .def_readonly("cases", &LqgStudyResult::cases)
      .def_readonly("open_loop_energy_J", &LqgStudyResult::open_loop_energy_J)
      .def_readonly("continuous_energy_J", &LqgStudyResult::continuous_energy_J)
      .def_readonly("final_elastic_std", &LqgStudyResult::final_elastic_std);
  py::class_<SweepStudyResult::ErrorCheck>(m, "SweepErrorCheck")
      .def_readonly("role", &SweepStudyResult::ErrorCheck::role)
      .def_readonly("index", &SweepStudyResult::ErrorCheck::index)
      .def_readonly("energy_J", &SweepStudyResult::ErrorCheck::energy_J)
      .def_readonly("tight_energy_J", &SweepStudyResult::ErrorCheck::tight_energy_J)
      .def_readonly("message", &SweepStudyResult::ErrorCheck::message);
  py::class_<SweepStudyResult>(m, "SweepStudyResult")
      .def_property_readonly("ok", &SweepStudyResult::ok)
      .def_readonly("message", &SweepStudyResult::message)
      .def_readonly("parameter_names", &SweepStudyResult::parameter_names)
      .def_property_readonly("values",
                             [](const SweepStudyResult& r) {
                               Eigen::MatrixXd v(static_cast<Eigen::Index>(r.samples.size()),
                                                 static_cast<Eigen::Index>(r.parameter_names.size()));
                               for (std::size_t i = 0; i < r.samples.size(); ++i)
                                 for (std::size_t k = 0; k < r.samples[i].values.size() && k < r.parameter_names.size(); ++k)
                                   v(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) = r.samples[i].values[k];
                               return v;
                             }, "one row per sample, one column per parameter")
      .def_property_readonly("residual_vibration_energy_J",
                             [](const SweepStudyResult& r) {
                               Eigen::VectorXd e(static_cast<Eigen::Index>(r.samples.size()));
                               for (std::size_t i = 0; i < r.samples.size(); ++i)
                                 e(static_cast<Eigen::Index>(i)) = r.samples[i].metrics.residual_vibration_energy_J;
                               return e;
                             }, "per sample (NaN: the sample failed)")
      .def_readonly("fraction_meeting", &SweepStudyResult::fraction_meeting)
      .def_property_readonly("fraction_meeting_ci95",
                             [](const SweepStudyResult& r) {
                               return std::make_pair(r.fraction_meeting_low, r.fraction_meeting_high);
                             })
      .def_readonly("p95_J", &SweepStudyResult::p95_J)
      .def_readonly("error_checks", &SweepStudyResult::error_checks)
      .def_readonly("max_relative_error_estimate", &SweepStudyResult::max_relative_error_estimate);
  py::class_<RunResult>(m, "RunResult")
      .def_property_readonly("ok", &RunResult::ok)
      .def_readonly("message", &RunResult::message)
      .def_readonly("files", &RunResult::files)
      .def_readonly("warnings", &RunResult::warnings)
      .def_readonly("maneuver", &RunResult::maneuver)
      .def_readonly("suppression", &RunResult::suppression)
      .def_readonly("lqg", &RunResult::lqg)
      .def_readonly("sweep", &RunResult::sweep);
  m.def("run", [](const Design& d, const std::string& out_dir) {
    RunOptions o;
    o.out_dir = out_dir;
    o.quiet = true;
    py::gil_scoped_release release;
    return run_design(d, o);
  }, py::arg("design"), py::arg("out_dir") = "",
        "Runs every study of the design (writing its files to out_dir unless empty), as `freeflex run` does.");
  m.def("summary_json", &summary_text, py::arg("design"), py::arg("result"), "summary.json as text");
}
