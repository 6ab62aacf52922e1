// Issue 20's gaps, each with the case that found it: text bytes that reach a figure,
// the [free_vibration] counts, [maneuver.ipopt] checked against Ipopt's registry before
// any work, gnuplot under a time limit, and messages that name what the user can see.
#include <catch2/catch.hpp>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "freeflex/io/design.hpp"
#include "freeflex/io/plot.hpp"
#include "io/run_program.hpp"
#include "io/system_error.hpp"
#include "support/designs.hpp"
#include "support/files.hpp"
#include "support/cli.hpp"

using namespace freeflex;
using namespace freeflex_test;
using Catch::Contains;

namespace {
// A maneuver with one hub torque; [maneuver] on line 9, `extra` from line 12 on.
std::string maneuver(const std::string& extra) {
  return kPaperBeam + "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\n" +
         "[maneuver]\nactuators = [\"hub\"]\nduration_s = 3.0\n" + extra;
}
}  // namespace

TEST_CASE("the title is bounded in bytes before any work", "[io][issue20]") {
  const std::size_t most = design_limits::kMaxTitleBytes;
  // the defect: a 41 KB title of tabs was accepted and stalled gnuplot for minutes
  CHECK_THAT(problems_of("title = \"" + repeated("\\t", 41000) + "\"\n" + kPaperBeam),
             Contains("line 1: title is 41000 bytes long; at most 256"));
  CHECK(problems_of("title = \"" + std::string(most, 'x') + "\"\n" + kPaperBeam).empty());
  CHECK_THAT(problems_of("title = \"" + std::string(most + 1, 'x') + "\"\n" + kPaperBeam),
             Contains("title is 257 bytes long; at most 256"));
}

TEST_CASE("[free_vibration] mode shapes and the NOA sweep are bounded", "[io][issue20]") {
  const std::string fv = kPaperBeam + "[free_vibration]\n";  // line 5
  auto shape = [](int i, int points) {
    return "[[free_vibration.mode_shape]]\nname = \"m" + std::to_string(i) + "\"\nnoa = 100\nmode = 100\npoints = " +
           std::to_string(points) + "\n";
  };
  // the defect: three shapes of 100 000 points (300 000 rows) passed
  const std::string three = fv + shape(1, 100000) + shape(2, 100000) + shape(3, 100000);
  CHECK_THAT(problems_of(three), Contains("line 6: free_vibration.mode_shape: the 3 mode shapes' points add up to "
                                          "300000 rows; at most 200000"));
  CHECK(problems_of(fv + shape(1, 100000) + shape(2, 100000)).empty());  // at the bound
  CHECK_THAT(problems_of(fv + shape(1, 100001)), Contains("points = 100001, must be a whole number in [2, 100000]"));
  std::string many = fv;
  for (int i = 0; i < design_limits::kMaxModeShapes; ++i) many += shape(i, 10);
  CHECK(problems_of(many).empty());
  CHECK_THAT(problems_of(many + shape(99, 10)), Contains("free_vibration.mode_shape: 21 tables; at most 20"));
  // the defect: 20 000 entries (x 100 modes: 2 M rows) passed
  auto sweep = [](int n) {
    std::string s = "noa_sweep = [";
    for (int i = 0; i < n; ++i) s += (i ? ", " : "") + std::to_string(1 + i % 100);
    return s + "]\nmodes = 100\n";
  };
  CHECK(problems_of(fv + sweep(design_limits::kMaxNoaSweep)).empty());
  CHECK_THAT(problems_of(fv + sweep(101)), Contains("line 6: free_vibration.noa_sweep has 101 entries; at most 100"));
  CHECK_THAT(problems_of(fv + sweep(20000)), Contains("free_vibration.noa_sweep has 20000 entries; at most 100"));
}

TEST_CASE("[maneuver.ipopt] is checked against Ipopt's registry, every problem at once with its line",
          "[io][issue20]") {
  // the defect: max_iter = -1 gave exit 2 only when the maneuver ran, without file or
  // line, and tol = -1 beside it was not reported
  const std::string two = problems_of(maneuver("[maneuver.ipopt]\nmax_iter = -1\ntol = -1.0\n"));
  CHECK_THAT(two, Contains("design 't.toml' line 13: maneuver.ipopt.max_iter = -1, must be a whole number >= 0 "
                           "(Ipopt's max_iter)"));
  CHECK_THAT(two, Contains("design 't.toml' line 14: maneuver.ipopt.tol = -1, must be a number > 0 (Ipopt's tol)"));
  const std::string more = problems_of(maneuver("[maneuver.ipopt]\nmax_itr = 5\nmu_strategy = \"clever\"\n"
                                                "print_level = 99\nacceptable_tol = \"small\"\nhessian_approximation = 3\n"
                                                "option_file_name = \"ipopt.opt\"\nmax_iter = 2000000\n"));
  CHECK_THAT(more, Contains("line 13: maneuver.ipopt.max_itr = 5 is not an Ipopt option (did you mean 'max_iter'?)"));
  CHECK_THAT(more, Contains("line 14: maneuver.ipopt.mu_strategy = \"clever\", must be one of 'monotone', 'adaptive'"));
  CHECK_THAT(more, Contains("line 15: maneuver.ipopt.print_level = 99, must be a whole number in [0, 12]"));
  CHECK_THAT(more, Contains("line 16: maneuver.ipopt.acceptable_tol = \"small\", must be a number > 0"));
  CHECK_THAT(more, Contains("line 17: maneuver.ipopt.hessian_approximation = 3, must be a string, one of 'exact', "
                            "'limited-memory'"));
  CHECK_THAT(more, Contains("line 18: maneuver.ipopt.option_file_name = \"ipopt.opt\": options files are not read"));
  CHECK_THAT(more, Contains("line 19: maneuver.ipopt.max_iter = 2000000, must be at most 1000000"));
  // what Ipopt accepts loads, in every form TOML gives it
  CHECK(problems_of(maneuver("[maneuver.ipopt]\nmax_iter = 50\ntol = 1e-6\nacceptable_tol = 1\n"
                             "mu_strategy = \"adaptive\"\nprint_level = 0\nmax_cpu_time = 60\n"))
            .empty());
}

TEST_CASE("Ipopt's derivative checker is bounded by the NLP's size", "[io][issue20]") {
  // the defect: "second-order" with quiet = true ran more than 10 minutes with no output
  // (default 100 intervals, Hermite-Simpson: 201 points x 7 = 1407 unknowns)
  CHECK_THAT(problems_of(maneuver("quiet = true\n[maneuver.ipopt]\nderivative_test = \"second-order\"\n")),
             Contains("line 14: maneuver.ipopt.derivative_test = \"second-order\" with maneuver.intervals = 100 tests "
                      "1407 NLP unknowns; at most 400 for this test"));
  // 28 intervals: 57 x 7 = 399 unknowns; 29: 413
  CHECK(problems_of(maneuver("intervals = 28\n[maneuver.ipopt]\nderivative_test = \"second-order\"\n")).empty());
  CHECK_THAT(problems_of(maneuver("intervals = 29\n[maneuver.ipopt]\nderivative_test = \"only-second-order\"\n")),
             Contains("tests 413 NLP unknowns; at most 400"));
  // first order: 142 intervals give 285 x 7 = 1995, 143 give 2009
  CHECK(problems_of(maneuver("intervals = 142\n[maneuver.ipopt]\nderivative_test = \"first-order\"\n")).empty());
  CHECK_THAT(problems_of(maneuver("intervals = 143\n[maneuver.ipopt]\nderivative_test = \"first-order\"\n")),
             Contains("tests 2009 NLP unknowns; at most 2000"));
  // the compressed form has no midpoint states: N + 1 points of 7 and N midpoint controls
  CHECK_THAT(problems_of(maneuver("intervals = 300\ntranscription = \"hermite_simpson_compressed\"\n"
                                  "[maneuver.ipopt]\nderivative_test = \"first-order\"\n")),
             Contains("tests 2407 NLP unknowns; at most 2000"));
  const Design d = parse_design(maneuver("intervals = 10\n[maneuver.ipopt]\nderivative_test = \"first-order\"\n"), "t");
  REQUIRE(d.maneuver);
  CHECK(d.maneuver->options.derivative_test == "first-order");
}

TEST_CASE("the optimizer's work is bounded before any work", "[io][issue20]") {
  // 5000 intervals, one actuator, fixed duration: 10 001 points x 7 = 70 007 unknowns, and
  // the coarse start's (625 intervals) 1 251 x 7 = 8 757 for at most 500 iterations: 580
  // iterations give 4.4983e7 iteration-unknowns, 581 give 4.5053e7
  CHECK(problems_of(maneuver("intervals = 5000\nmax_iterations = 580\n")).empty());
  CHECK_THAT(problems_of(maneuver("intervals = 5000\nmax_iterations = 581\n")),
             Contains("line 13: maneuver.max_iterations = 581 with intervals = 5000 and mesh_refinements = 0 allows "
                      "45052567 Ipopt iteration-unknowns (iterations x NLP unknowns, 70007 unknowns over the rounds, "
                      "the coarse start's 8757 for at most 500 iterations (coarse_start = false drops it))"));
  // without the coarse start, 642 and 643 (4.4944e7 and 4.5015e7)
  CHECK(problems_of(maneuver("intervals = 5000\nmax_iterations = 642\ncoarse_start = false\n")).empty());
  CHECK_THAT(problems_of(maneuver("intervals = 5000\nmax_iterations = 643\ncoarse_start = false\n")),
             Contains("allows 45014501 Ipopt iteration-unknowns"));
  // the default 3000 iterations; Ipopt's own max_iter counts when given there
  CHECK_THAT(problems_of(maneuver("intervals = 5000\n")), Contains("line 12: maneuver.max_iterations = 3000"));
  CHECK_THAT(problems_of(maneuver("intervals = 5000\n[maneuver.ipopt]\nmax_iter = 1000\n")),
             Contains("maneuver.ipopt.max_iter = 1000 with intervals = 5000"));
  // refinement rounds add up: 100 intervals, 4 rounds: 100 + 200 + 400 + 800 + 1600
  CHECK_THAT(problems_of(maneuver("mesh_refinements = 4\n")),
             Contains("line 12: maneuver.max_iterations = 3000 with intervals = 100 and mesh_refinements = 4"));
  CHECK(problems_of(maneuver("mesh_refinements = 2\n")).empty());
}

TEST_CASE("the TV-LQR's stored gains are bounded with the grid", "[io][issue20]") {
  // two actuators at noa = 100: 2 x 206 doubles per grid point, at most 121359 points
  const std::string two = "[[actuator]]\nname = \"a\"\ntype = \"torque\"\nposition_m = 0.5\n"
                          "[[actuator]]\nname = \"b\"\ntype = \"torque\"\nposition_m = 0.2\n";
  const std::string ctl = kPaperBeam + "[model]\nnoa = 100\n" + kLoad + two +
                          "[controller]\nactuators = [\"a\", \"b\"]\nhorizon_s = 1.2\n";  // [controller] line 24
  CHECK(problems_of(ctl + "grid_step_s = 1e-5\n").empty());  // 120001 points
  CHECK_THAT(problems_of(ctl + "grid_step_s = 0.9e-5\n"),
             Contains("line 27: controller.grid_step_s = 9e-06 and 2 actuator(s) at noa = 100 with horizon_s = 1.2 "
                      "gives 133335 TV-LQR gain grid points of 412 doubles each; at most 121359"));
}

TEST_CASE("force elements and load profile times are bounded", "[io][issue20]") {
  auto loads = [](int n, int times) {
    std::string s;
    for (int i = 0; i < n; ++i) {
      s += "[[load]]\nname = \"F" + std::to_string(i) + "\"\ntype = \"torque\"\nposition_m = 0.5\n"
           "[load.profile]\ntype = \"linear\"\ntimes_s = [";
      for (int k = 0; k < times; ++k) s += (k ? ", " : "") + std::to_string(k);
      s += "]\nvalues = [";
      for (int k = 0; k < times; ++k) s += k ? ", 1.0" : "1.0";
      s += "]\n";
    }
    return s;
  };
  CHECK(problems_of(kPaperBeam + loads(64, 2)).empty());
  CHECK_THAT(problems_of(kPaperBeam + loads(65, 2)),
             Contains("line 5: 65 [[load]] and 0 [[actuator]] tables; at most 64 together"));
  CHECK(problems_of(kPaperBeam + loads(2, 5000)).empty());
  CHECK_THAT(problems_of(kPaperBeam + loads(2, 5001)),
             Contains("line 17: load[2].profile: the load profiles have 10002 times_s entries up to here; at most 10000"));
}

TEST_CASE("a figure's text is bounded and free of control characters", "[io][issue20]") {
  const std::string dir = freeflex_test::temp_path("plot_text");  // per process: concurrent test runs do not collide
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  PlotSpec spec;
  spec.name = "p";
  spec.title = repeated("\t", 41000) + "it's";  // the defect's title
  PlotOptions no_gnuplot;
  no_gnuplot.gnuplot = "";
  const PlotResult r = render_plot(spec, dir, no_gnuplot);
  CHECK(r.status == PlotResult::Status::NoGnuplot);
  const std::string gp = read_text(dir + "/p.gp");
  CHECK(gp.find('\t') == std::string::npos);
  CHECK(gp.size() < 2 * kMaxFigureTextBytes);  // the script's own text is a few hundred bytes
  spec.title = "\xCE\xB8 = 90\xC2\xB0 \xFF it's";  // UTF-8 kept, an invalid byte shown as '?', quotes doubled
  render_plot(spec, dir, no_gnuplot);
  CHECK_THAT(read_text(dir + "/p.gp"), Contains("'\xCE\xB8 = 90\xC2\xB0 ? it''s'"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("gnuplot runs under a time limit, and hitting it is a result, not a hang", "[io][issue20]") {
  using io_detail::ProgramRun;
  const ProgramRun echo = io_detail::run_program({"/bin/echo", "hi"}, "", 10.0);
  CHECK(echo.ok());
  CHECK(echo.output == "hi\n");
  // a program that would run for a minute, with a child of its own: the whole group is stopped
  const ProgramRun slow = io_detail::run_program({"/bin/sh", "-c", "sleep 60 & sleep 60"}, "", 0.3);
  CHECK(slow.status == ProgramRun::Status::TimedOut);
  CHECK(slow.seconds < 30.0);  // not a speed check: 0.3 s plus at most 1 s of grace, far from 60 s
  const ProgramRun missing = io_detail::run_program({"/nonexistent/gnuplot"}, "", 1.0);
  CHECK(missing.status == ProgramRun::Status::NotStarted);
  CHECK_THAT(missing.error, Contains("cannot run '/nonexistent/gnuplot': No such file or directory"));

  const std::string dir = freeflex_test::temp_path("plot_timeout");  // per process: concurrent test runs do not collide
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string fake = dir + "/stalling-gnuplot";
  std::ofstream(fake) << "#!/bin/sh\nsleep 60\n";
  std::filesystem::permissions(fake, std::filesystem::perms::owner_all);
  PlotSpec spec;
  spec.name = "p";
  PlotOptions stalling;
  stalling.gnuplot = fake;
  stalling.timeout_s = 0.3;
  const PlotResult r = render_plot(spec, dir, stalling);
  CHECK(r.status == PlotResult::Status::TimedOut);
  CHECK_THAT(r.message, Contains("gnuplot did not finish p.gp within 0.3 s and was stopped"));
  CHECK(std::filesystem::exists(dir + "/p.gp"));
  CHECK(!std::filesystem::exists(dir + "/p.png"));
  stalling.timeout_s = 0.0;
  CHECK_THROWS_WITH(render_plot(spec, dir, stalling), Contains("timeout_s = 0, expected in (0, 3600]"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("a full file system is said to be out of space or inodes", "[io][issue20]") {
  CHECK(io_detail::reason(ENOSPC) == std::string(std::strerror(ENOSPC)) +
                                         " (the file system is full or has no free inodes)");
  CHECK(io_detail::reason(EACCES) == std::strerror(EACCES));
}
