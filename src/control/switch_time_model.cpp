// The first-order model of a bang-bang rotation (control/switch_time_model.hpp) and the
// elastic modes a torque excites.
#include "control/switch_time_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "freeflex/dynamics/first_order.hpp"
#include "util/format.hpp"

namespace freeflex {

ExcitedModes excited_modes(const FlexibleBody& body, int element, double theta) {
  const int N = body.dofs(), n = body.n();
  ExcitedModes m;
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(n);
  m.M0 = body.mass_matrix(theta, q0);
  Eigen::MatrixXd K0 = Eigen::MatrixXd::Zero(N, N);
  K0.bottomRightCorner(n, n) = body.integrals().K;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K0, m.M0);
  m.eigenvalues = es.eigenvalues();
  m.eigenvectors = es.eigenvectors();
  const Eigen::VectorXd g = body.element_force(element, theta, q0);
  m.participation = m.eigenvectors.rightCols(n).transpose() * g;
  const double pmax = m.participation.cwiseAbs().maxCoeff();
  for (int j = 0; j < n; ++j)
    if (std::abs(m.participation(j)) > 1e-8 * pmax) m.excited.push_back(j);
  return m;
}

namespace detail {

std::string fmt10(double v) { return util::format_number(v, 10); }

void validate_actuator(const FlexibleBody& body, int actuator, const std::string& where) {
  const int ne = static_cast<int>(body.elements().size());
  if (actuator < 0 || actuator >= ne)
    throw std::invalid_argument(where + ": actuator = " + std::to_string(actuator) + " is not an element of the body (0.." +
                                std::to_string(ne - 1) + ")");
  const ForceElement& el = body.elements()[actuator];
  if (el.type != ForceElement::Type::Torque)
    throw std::invalid_argument(where + ": actuator " + std::to_string(actuator) + " ('" + el.name +
                                "') must be a torque, got a force or thruster");
  const double L = body.beam().length();
  if (std::abs(body.element_x(actuator)) > 1e-9 * L)
    throw std::invalid_argument(where + ": actuator '" + el.name + "' must act at o (x = 0), got x = " +
                                fmt10(body.element_x(actuator)) + " m");
  const ModalIntegrals& mi = body.integrals();
  if (std::abs(mi.S_o) > 1e-9 * mi.m * L)
    throw std::invalid_argument(where + ": o must be the mass centre (S_o = 0), got S_o = " + fmt10(mi.S_o) + " kg m");
}


TargetModes target_modes(const FlexibleBody& body, int actuator, double theta, int modes, const std::string& where) {
  const int N = body.dofs();
  ExcitedModes em = excited_modes(body, actuator, theta);
  if (static_cast<int>(em.excited.size()) < modes)
    throw std::invalid_argument(where + ": the actuator excites only " + std::to_string(em.excited.size()) +
                                " elastic modes of this basis, asked for modes = " + std::to_string(modes));
  TargetModes t;
  t.omega.resize(modes);
  t.participation.resize(modes);
  t.shapes.resize(N, modes);
  for (int i = 0; i < modes; ++i) {
    const int j = em.excited[static_cast<std::size_t>(i)];
    t.omega(i) = std::sqrt(std::max(0.0, em.eigenvalues(3 + j)));
    t.participation(i) = em.participation(j);
    t.shapes.col(i) = em.eigenvectors.col(3 + j);
  }
  t.M0 = std::move(em.M0);
  return t;
}

std::vector<double> switches_of(const std::vector<double>& durations, double& T) {
  std::vector<double> s;
  double t = 0.0;
  for (std::size_t i = 0; i + 1 < durations.size(); ++i) {
    t += durations[i];
    s.push_back(t);
  }
  T = t + durations.back();
  return s;
}

void rigid_end(const std::vector<double>& D, double a, double& theta, double& rate, std::vector<double>* dtheta,
               std::vector<double>* drate) {
  const int M = static_cast<int>(D.size());
  theta = 0.0;
  rate = 0.0;
  std::vector<double> rate_after(M);
  for (int i = 0; i < M; ++i) {
    const double acc = (i % 2 == 0 ? a : -a);
    theta += rate * D[i] + 0.5 * acc * D[i] * D[i];
    rate += acc * D[i];
    rate_after[i] = rate;
  }
  if (dtheta) {
    dtheta->assign(M, 0.0);
    drate->assign(M, 0.0);
    double after = 0.0;  // time after interval i
    for (int i = M - 1; i >= 0; --i) {
      const double acc = (i % 2 == 0 ? a : -a);
      (*dtheta)[i] = rate_after[i] + acc * after;  // more time at acceleration acc, inserted
      (*drate)[i] = acc;
      after += D[i];
    }
  }
}

bool simulate(Problem& P, const std::vector<double>& D, Eigen::VectorXd& x1_end, double* peak_rate) {
  double T = 0.0;
  const std::vector<double> sw = switches_of(D, T);
  const bool sims_left = P.max_simulations == 0 || P.simulations < P.max_simulations;
  const bool steps_left = P.max_steps_all == 0 || P.steps < P.max_steps_all;
  if (P.budget_spent || !sims_left || !steps_left) {
    if (!P.budget_spent)
      P.last_error = sims_left ? "the design's step budget (SwitchTimeOptions::max_total_steps) is spent: " +
                                     std::to_string(P.steps) + " steps"
                               : "the simulations allowed per carried root are spent "
                                 "(SwitchTimeOptions::simulations_per_unknown)";
    P.budget_spent = true;
    return false;
  }
  ++P.simulations;
  if (P.progress) P.progress(P.simulations);
  try {
    const BangBangRotation traj(P.I_o, P.tau, sw, T);
    const int act = P.actuator;
    const FirstOrderModel model(
        *P.body, traj,
        [&traj, act](const Instant& at, Eigen::Ref<Eigen::VectorXd> c) {
          c.setZero();
          c(act) = traj.torque(at);
        },
        {});
    const int N = P.body->dofs();
    FirstOrderModel::Data data = model.create_data();
    OdeSystem sys;
    sys.dim = 2 * N;
    const Eigen::VectorXd none(0);
    sys.rhs = [&model, &data, &none](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x,
                                     Eigen::Ref<Eigen::VectorXd> xd) {
      xd = model.rhs(data, at, x, none);
      return xd.allFinite();
    };
    IntegratorOptions io;
    io.method = IntegratorOptions::Method::Adams;  // undamped oscillations, not stiff
    io.rtol = P.rtol;
    io.atol = P.atol;
    // this simulation's steps: its own limit, and what is left of the design's
    const long left = P.max_steps_all > 0 ? P.max_steps_all - P.steps : 0;
    io.max_total_steps = P.max_total_steps > 0 && left > 0 ? std::min(P.max_total_steps, left)
                                                            : std::max(P.max_total_steps, left);
    io.budget = P.budget;
    const IntegrationResult ir = integrate(sys, Eigen::VectorXd::Zero(2 * N), {0.0, T}, sw, io);
    P.steps += ir.steps;
    P.longest = std::max(P.longest, ir.steps);
    if (!ir.ok()) {
      P.last_error = ir.message;
      if (P.max_steps_all > 0 && P.steps >= P.max_steps_all) {
        P.last_error += "; the design's step budget (SwitchTimeOptions::max_total_steps) is spent: " +
                        std::to_string(P.steps) + " steps";
        P.budget_spent = true;
      }
      return false;
    }
    x1_end = ir.x.row(ir.x.rows() - 1).transpose();
    if (peak_rate) {
      double pk = 0.0;
      for (double s : sw) pk = std::max(pk, std::abs(traj.at(Instant::at(s)).vel(2)));
      *peak_rate = pk;
    }
    return true;
  } catch (const std::exception& e) {
    P.last_error = e.what();
    return false;
  }
}

void modal_from_state(const Problem& P, const Eigen::VectorXd& x1, double* c) {
  const int N = P.body->dofs();
  const Eigen::VectorXd eta = P.modes.shapes.transpose() * (P.modes.M0 * x1.head(N));
  const Eigen::VectorXd eta_d = P.modes.shapes.transpose() * (P.modes.M0 * x1.tail(N));
  for (int j = 0; j < P.k; ++j) {
    c[2 * j] = P.modes.omega(j) * eta(j) / P.scale;
    c[2 * j + 1] = eta_d(j) / P.scale;
  }
}

}  // namespace detail
}  // namespace freeflex
