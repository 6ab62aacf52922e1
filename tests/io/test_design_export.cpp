// [export] and the closed-loop settings of [controller]: what the keys set, and bad
// values reported with key and line.
#include <catch2/catch.hpp>

#include "freeflex/io/design.hpp"
#include "support/designs.hpp"

using namespace freeflex;
using namespace freeflex_test;
using Catch::Contains;

namespace {
const std::string kController = kPaperBeam + kLoad +  // lines 1-13
                                "[[actuator]]\nname = \"tau\"\ntype = \"torque\"\nposition_m = 0.5\nlimit = 1.0\n"  // 14-18
                                "[controller]\nactuators = [\"tau\"]\nhorizon_s = 2.0\n";  // 19-21
}  // namespace

TEST_CASE("[export] keys choose formats, contents, name and grid", "[io]") {
  const Design d = parse_design(kController + "closed_loop_rtol = 1e-12\n[export]\nname = \"law\"\nformats = [\"mat\"]\n"
                                              "contents = [\"gains\", \"poles\"]\nmodel_step_s = 0.001\n",
                                "t.toml");
  REQUIRE(d.exports);
  CHECK(d.exports->name == "law");
  CHECK(d.exports->mat);
  CHECK(!d.exports->csv);
  CHECK(d.exports->gains);
  CHECK(d.exports->poles);
  CHECK(!d.exports->model);
  CHECK(!d.exports->histories);
  CHECK(d.exports->model_step_s == 0.001);
  CHECK(d.controller->closed_loop_rtol == 1e-12);
  CHECK(d.controller->closed_loop_atol == closed_loop_integrator().atol);

  const Design all = parse_design(kController + "[export]\n", "t.toml");
  REQUIRE(all.exports);
  CHECK((all.exports->csv && all.exports->mat && all.exports->gains && all.exports->nominal && all.exports->model &&
         all.exports->poles && all.exports->histories));
  CHECK(all.exports->model_step_s == 0.0);
}

TEST_CASE("bad [export] keys are reported with key and line", "[io]") {
  const std::string p = problems_of(kController + "[export]\nformats = [\"xlsx\"]\ncontents = [\"everything\"]\n"
                                                  "model_step_s = -1.0\nname = \"comparison\"\n");
  CHECK_THAT(p, Contains("line 23") && Contains("export.formats") && Contains("\"xlsx\""));
  CHECK_THAT(p, Contains("line 24") && Contains("\"everything\""));
  CHECK_THAT(p, Contains("line 25") && Contains("model_step_s"));
  CHECK_THAT(problems_of(kPaperBeam + "[export]\n"), Contains("add a [controller]"));
  CHECK_THAT(problems_of(kController + "closed_loop_rtol = 0.0\n"), Contains("closed_loop_rtol"));
  // the export's files must not clash with the study's own
  CHECK_THAT(problems_of(kController + "[free_vibration]\ntable_name = \"law_gains\"\n[export]\nname = \"law\"\n"),
             Contains("output files must have distinct names"));
}

TEST_CASE("[controller] closed_loop_first_order_method and closed_loop_gauss_steps", "[io]") {
  const Design d = parse_design(kController + "closed_loop_first_order_method = \"gauss\"\nclosed_loop_gauss_steps = 12\n", "t");
  REQUIRE(d.controller);
  CHECK(d.controller->closed_loop_first_order_method == ClosedLoopMethod::Gauss);
  CHECK(d.controller->closed_loop_gauss_steps == 12);
  const Design plain = parse_design(kController, "t");
  CHECK(plain.controller->closed_loop_first_order_method == ClosedLoopMethod::Cvodes);
  CHECK(plain.controller->closed_loop_gauss_steps == ClosedLoopOptions{}.gauss_steps);
  CHECK_THAT(problems_of(kController + "closed_loop_first_order_method = \"rk4\"\n"),
             Contains("line 22") && Contains("closed_loop_first_order_method") && Contains("'gauss'"));
  CHECK_THAT(problems_of(kController + "closed_loop_gauss_steps = 0\n"), Contains("closed_loop_gauss_steps"));
  // the work bound: 400 + 400 intervals (2 s at 5 ms) x 1000 steps x (10 (3 + 6))³ = 5.8e11
  // is within 6e11; at a 1 ms gain grid (2000 + 400) it is not
  CHECK(problems_of(kController + "closed_loop_first_order_method = \"gauss\"\nclosed_loop_gauss_steps = 1000\n").empty());
  CHECK_THAT(problems_of(kController + "grid_step_s = 0.001\nclosed_loop_first_order_method = \"gauss\"\n"
                                       "closed_loop_gauss_steps = 1000\n"),
             Contains("closed_loop_gauss_steps") && Contains("units of work"));
}

TEST_CASE("[controller] tvlqr_method", "[io]") {
  const Design d = parse_design(kController + "tvlqr_method = \"exponential\"\n", "t");
  REQUIRE(d.controller);
  CHECK(d.controller->tvlqr_method == TvlqrOptions::Method::Exponential);
  CHECK(parse_design(kController + "tvlqr_method = \"bdf\"\n", "t").controller->tvlqr_method == TvlqrOptions::Method::Bdf);
  CHECK(parse_design(kController, "t").controller->tvlqr_method == TvlqrOptions::Method::Auto);
  CHECK_THAT(problems_of(kController + "tvlqr_method = \"rk4\"\n"),
             Contains("line 22") && Contains("tvlqr_method") && Contains("'exponential'"));
}
