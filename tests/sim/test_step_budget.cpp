// The integration's total step budget (IntegratorOptions::max_total_steps), which design
// files set so that no simulation runs unbounded: spending it is a failure with the time
// reached, and a budget that is not spent changes nothing.
#include <catch2/catch.hpp>

#include "freeflex/sim/integrator.hpp"
#include "support/integration.hpp"

using namespace freeflex_test;
using freeflex::Instant;
using freeflex::integrate;
using freeflex::IntegratorOptions;
using freeflex::OdeSystem;
using Catch::Matchers::Contains;

namespace {
OdeSystem oscillator(double w) {
  OdeSystem sys;
  sys.dim = 2;
  sys.rhs = [w](const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> xd) {
    xd(0) = x(1);
    xd(1) = -w * w * x(0);
    return true;
  };
  return sys;
}
}  // namespace

TEST_CASE("the total step budget stops the whole integration, with the time reached", "[sim][issue20]") {
  const OdeSystem sys = oscillator(2.0 * kPi);
  const std::vector<double> times = linspace(0.0, 10.0, 101);  // each 0.1 s interval needs far fewer than max_steps
  IntegratorOptions opt;
  const auto free = integrate(sys, Eigen::Vector2d(1.0, 0.0), times, {}, opt);
  REQUIRE(free.ok());
  REQUIRE(free.steps > 400);
  opt.max_total_steps = 400;
  const auto r = integrate(sys, Eigen::Vector2d(1.0, 0.0), times, {}, opt);
  CHECK_FALSE(r.ok());
  CHECK_THAT(r.message, Contains("max_total_steps = 400, is spent"));
  CHECK(r.steps == 400);
  CHECK(r.failure_time > 0.0);
  CHECK(r.failure_time < 10.0);
  // a budget that suffices gives the same bits as none
  opt.max_total_steps = free.steps;
  const auto same = integrate(sys, Eigen::Vector2d(1.0, 0.0), times, {}, opt);
  REQUIRE(same.ok());
  CHECK(same.steps == free.steps);
  CHECK(same.x == free.x);
}
