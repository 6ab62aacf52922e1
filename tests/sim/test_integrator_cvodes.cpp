// The piecewise CVODES integrator: a change of integration variables, and the steps of
// plain CVODES reproduced bit for bit (the compiled error weights and vector kernels).
#include <catch2/catch.hpp>

#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "freeflex/sim/integrator.hpp"
#include "sim/fast_nvector.hpp"
#include "support/integration.hpp"

using namespace freeflex;
using namespace freeflex_test;
using Catch::Matchers::Contains;

TEST_CASE("a change of variables: the rotating-frame oscillator is exact, and a failing map is reported", "[sim]") {
  // x'' = -w² x + u(t), u = 1 on [0, 1), 0 after. Integrated in the amplitudes of the free
  // oscillation about the piece's static deflection, x = u/w² + a cos w(t - t_s) + b sin w(t - t_s):
  // a' = b' = 0 inside a piece, so CVODE takes a handful of steps, and the outputs must be
  // the closed form mapped back at every output time and restart.
  const double w = 2.0 * kPi;
  auto u = [](const Instant& at) { return at.piece_mid < 1.0 ? 1.0 : 0.0; };
  double t_s = 0.0, x_s = 0.0;
  OdeSystem sys;
  sys.dim = 2;
  sys.rhs = [](const Instant&, const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::VectorXd> yd) {
    yd.setZero();
    return true;
  };
  sys.variables.enter_piece = [&](const Instant& start, const Eigen::Ref<const Eigen::VectorXd>& x,
                                  Eigen::Ref<Eigen::VectorXd> y) {
    t_s = start.t;
    x_s = u(start) / (w * w);
    y << x(0) - x_s, x(1) / w;
    return true;
  };
  sys.variables.to_x = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& y,
                           Eigen::Ref<Eigen::VectorXd> x) {
    const double c = std::cos(w * (at.t - t_s)), s = std::sin(w * (at.t - t_s));
    x << x_s + y(0) * c + y(1) * s, w * (y(1) * c - y(0) * s);
  };
  IntegratorOptions opt;
  opt.rtol = 1e-10;
  opt.atol = 1e-12;
  const std::vector<double> times = linspace(0.0, 2.5, 26);
  const auto r = integrate(sys, Eigen::Vector2d::Zero(), times, {1.0}, opt);
  INFO(r.message);
  REQUIRE(r.ok());
  // closed form: x = (1 - cos w t)/w² for t < 1; free oscillation from x(1), x'(1) after
  const double x1 = (1.0 - std::cos(w)) / (w * w), v1 = std::sin(w) / w;
  double err = 0.0;
  for (int i = 0; i < r.t.size(); ++i) {
    const double t = r.t(i);
    const double x = t <= 1.0 ? (1.0 - std::cos(w * t)) / (w * w)
                              : x1 * std::cos(w * (t - 1.0)) + v1 / w * std::sin(w * (t - 1.0));
    err = std::max(err, std::abs(r.x(i, 0) - x));
  }
  CHECK(err < 1e-15);  // the map is the closed form: only round-off remains
  CHECK(r.steps < 20);  // constant amplitudes: CVODE's first steps reach the end

  // A map that fails at the restart ends the run there, with the reason.
  sys.variables.enter_piece = [&](const Instant& start, const Eigen::Ref<const Eigen::VectorXd>&,
                                  Eigen::Ref<Eigen::VectorXd> y) {
    y.setZero();
    return start.t < 0.5;
  };
  sys.last_error = [] { return std::string("modal force not finite"); };
  const auto bad = integrate(sys, Eigen::Vector2d::Zero(), times, {1.0}, opt);
  CHECK_FALSE(bad.ok());
  CHECK(bad.failure_time == 1.0);
  CHECK_THAT(bad.message, Contains("t = 1") && Contains("modal force not finite"));
  CHECK(bad.t.size() == 11);  // outputs up to the restart at t = 1 are kept
}

namespace {
/// A pendulum and a Duffing oscillator side by side: nonlinear, four states.
void two_oscillators(const double* x, double* xd) {
  xd[0] = x[2];
  xd[1] = x[3];
  xd[2] = -40.0 * std::sin(x[0]);
  xd[3] = -900.0 * x[1] - 2e4 * x[1] * x[1] * x[1];
}
extern "C" int plain_rhs(sunrealtype, N_Vector y, N_Vector yd, void*) {
  two_oscillators(N_VGetArrayPointer(y), N_VGetArrayPointer(yd));
  return 0;
}
/// Plain CVODES (Adams, fixed-point iteration) on two_oscillators with freeflex's vector
/// kernels and CVODES's own error weights: SS tolerances, or SV with atol_i = atol * scale_i.
Eigen::MatrixXd plain_cvodes(const std::vector<double>& times, const double* x0, double rtol, double atol,
                             const double* scale, long& steps) {
  SUNContext ctx = nullptr;
  REQUIRE(SUNContext_Create(nullptr, &ctx) == 0);
  N_Vector y = N_VNew_Serial(4, ctx);
  freeflex::use_compiled_vector_kernels(y);
  N_Vector abstol = N_VClone(y);
  for (int i = 0; i < 4; ++i) {
    NV_Ith_S(y, i) = x0[i];
    NV_Ith_S(abstol, i) = scale ? atol * scale[i] : atol;
  }
  void* mem = CVodeCreate(CV_ADAMS, ctx);
  REQUIRE(CVodeInit(mem, plain_rhs, 0.0, y) == CV_SUCCESS);
  REQUIRE((scale ? CVodeSVtolerances(mem, rtol, abstol) : CVodeSStolerances(mem, rtol, atol)) == CV_SUCCESS);
  SUNNonlinearSolver nls = SUNNonlinSol_FixedPoint(y, 0, ctx);
  REQUIRE(CVodeSetNonlinearSolver(mem, nls) == CV_SUCCESS);
  REQUIRE(CVodeSetStopTime(mem, times.back()) == CV_SUCCESS);
  Eigen::MatrixXd x(times.size(), 4);
  for (int i = 0; i < 4; ++i) x(0, i) = x0[i];
  for (std::size_t k = 1; k < times.size(); ++k) {
    sunrealtype t = 0.0;
    REQUIRE(CVode(mem, times[k], y, &t, CV_NORMAL) >= 0);
    for (int i = 0; i < 4; ++i) x(static_cast<Eigen::Index>(k), i) = NV_Ith_S(y, i);
  }
  CVodeGetNumSteps(mem, &steps);
  CVodeFree(&mem);
  SUNNonlinSolFree(nls);
  N_VDestroy(abstol);
  N_VDestroy(y);
  SUNContext_Free(&ctx);
  return x;
}
}  // namespace

TEST_CASE("integrate takes the steps of plain CVODES: its error-weight function changes no bit", "[sim]") {
  // freeflex gives CVODES its own error-weight function, which must compute what
  // CVodeSStolerances / CVodeSVtolerances would. The plain run gets the same compiled
  // vector kernels (whose weighted norm sums in another order than SUNDIALS'), so the
  // weights are the only difference left, and the two runs must agree bit for bit.
  const std::vector<double> times = linspace(0.0, 2.0, 41);
  const double x0[4] = {1.0, 0.05, 0.0, 0.0};
  const double rtol = 1e-8, atol = 1e-10;
  long plain_steps = 0;
  const Eigen::MatrixXd plain = plain_cvodes(times, x0, rtol, atol, nullptr, plain_steps);

  OdeSystem sys;
  sys.dim = 4;
  sys.rhs = [](const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> xd) {
    two_oscillators(x.data(), xd.data());
    return true;
  };
  IntegratorOptions o;
  o.method = IntegratorOptions::Method::Adams;
  o.rtol = rtol;
  o.atol = atol;
  const auto r = integrate(sys, Eigen::Map<const Eigen::VectorXd>(x0, 4), times, {}, o);
  REQUIRE(r.ok());
  CHECK(r.steps == plain_steps);
  CHECK(plain_steps > 500);  // enough steps for any difference in a weight to change one
  CHECK((r.x.array() == plain.array()).all());  // bit for bit: no tolerance

  // Per-component atol (a change of variables that sets atol_scale; here the identity).
  const double scale[4] = {1.0, 0.01, 3.0, 0.5};
  const Eigen::MatrixXd plain_sv = plain_cvodes(times, x0, rtol, atol, scale, plain_steps);
  sys.variables.enter_piece = [](const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x,
                                 Eigen::Ref<Eigen::VectorXd> yv) {
    yv = x;
    return true;
  };
  sys.variables.to_x = [](const Instant&, const Eigen::Ref<const Eigen::VectorXd>& yv, Eigen::Ref<Eigen::VectorXd> x) {
    x = yv;
  };
  sys.variables.atol_scale = Eigen::Map<const Eigen::VectorXd>(scale, 4);
  const auto rs = integrate(sys, Eigen::Map<const Eigen::VectorXd>(x0, 4), times, {}, o);
  REQUIRE(rs.ok());
  CHECK(rs.steps == plain_steps);
  CHECK(rs.steps != r.steps);  // the scaled atol does change the steps
  CHECK((rs.x.array() == plain_sv.array()).all());
}
