#pragma once
// Test fixtures: small systems with closed forms or known behaviour, shared by the
// integrator and control tests.
#include <cmath>

#include <Eigen/Dense>

#include "freeflex/control/tvlqr.hpp"
#include "freeflex/sim/integrator.hpp"

namespace freeflex_test {

/// x'' = -w^2 x as a first-order system, counting the right-hand side calls in *calls.
inline freeflex::OdeSystem oscillator(double w, long* calls) {
  freeflex::OdeSystem sys;
  sys.dim = 2;
  sys.rhs = [w, calls](const freeflex::Instant&, const Eigen::Ref<const Eigen::VectorXd>& x,
                       Eigen::Ref<Eigen::VectorXd> xd) {
    ++*calls;
    xd(0) = x(1);
    xd(1) = -w * w * x(0);
    return true;
  };
  return sys;
}

/// x' = a x + b u: the scalar system of the Riccati closed forms.
inline freeflex::LtvSystem scalar_system(double a, double b) {
  freeflex::LtvSystem sys;
  sys.state_size = 1;
  sys.input_size = 1;
  sys.state_space = [a, b](const freeflex::Instant&) {
    return freeflex::StateSpace{Eigen::MatrixXd::Constant(1, 1, a), Eigen::MatrixXd::Constant(1, 1, b),
                                Eigen::VectorXd::Zero(1)};
  };
  return sys;
}

/// Two states, one input, A(t), B(t), g(t) smooth with one breakpoint at 0.8 s where g
/// jumps (from 2 to -1 in the second row).
inline freeflex::LtvSystem forced_system() {
  freeflex::LtvSystem sys;
  sys.state_size = 2;
  sys.input_size = 1;
  sys.breakpoints = {0.8};
  sys.state_space = [](const freeflex::Instant& at) {
    const double t = at.t;
    freeflex::StateSpace m;
    m.A.resize(2, 2);
    m.A << 0.0, 1.0, -4.0 - std::sin(3.0 * t), -0.1;
    m.B.resize(2, 1);
    m.B << 0.0, 1.0 + 0.3 * std::cos(2.0 * t);
    m.g.resize(2);
    m.g << 0.0, at.piece_mid < 0.8 ? 2.0 : -1.0;
    return m;
  };
  return sys;
}

}  // namespace freeflex_test
