// Issue 20, item 2: the counts and the work a design implies that were not bounded before
// (beam pieces, sensors, motion tables, the [lqg] and [sweep] samples and what they keep,
// a sweep's least work, [export]'s model grid and poles, the finite-element models of
// [free_vibration], an elastic maneuver's NLP), each at its bound accepted and one past it
// refused with key and line, before any work.
#include <catch2/catch.hpp>

#include <string>

#include "freeflex/io/design.hpp"
#include "support/designs.hpp"

using namespace freeflex;
using namespace freeflex_test;
using Catch::Contains;

namespace {

std::string numbers(int n, double first, double step) {
  std::string s = "[";
  for (int i = 0; i < n; ++i) s += (i ? ", " : "") + std::to_string(first + i * step);
  return s + "]";
}

// A hub torque at o (four lines)
const std::string kHub = "[[actuator]]\nname = \"hub\"\ntype = \"torque\"\nposition_m = 0.5\n";

/// The paper's beam at `noa` (lines 1-6), the force pulse (7-15), the hub (16-19) and a
/// [controller] over `horizon` (line 20 on; `extra` from line 23).
std::string controller(int noa, const std::string& horizon, const std::string& extra = "") {
  return kPaperBeam + "[model]\nnoa = " + std::to_string(noa) + "\n" + kLoad + kHub +
         "[controller]\nactuators = [\"hub\"]\nhorizon_s = " + horizon + "\n" + extra;
}

}  // namespace

TEST_CASE("beam segments and point masses are bounded", "[io][issue20]") {
  const std::string segment = "[[beam.segment]]\nlength_m = 0.01\nmass_per_length_kg_m = 1.0\nbending_stiffness_Nm2 = 1.0\n";
  CHECK(problems_of(repeated(segment, design_limits::kMaxBeamPieces)).empty());
  // each table is 4 lines: the first on line 1
  CHECK_THAT(problems_of(repeated(segment, design_limits::kMaxBeamPieces + 1)),
             Contains("line 1: beam: 101 [[beam.segment]] tables; at most 100"));
  const std::string mass = "[[beam.point_mass]]\nposition_m = 0.5\nmass_kg = 0.001\n";
  CHECK(problems_of(kPaperBeam + repeated(mass, 100)).empty());
  CHECK_THAT(problems_of(kPaperBeam + repeated(mass, 101)),
             Contains("line 5: beam: 101 [[beam.point_mass]] tables; at most 100"));
}

TEST_CASE("sensors are bounded", "[io][issue20]") {
  const std::string sensor = "[[sensor]]\nname = \"g\"\ntype = \"gyro_rate\"\nnoise_density = 1e-5\n";
  std::string many;
  for (int i = 0; i < design_limits::kMaxSensors; ++i)
    many += "[[sensor]]\nname = \"g" + std::to_string(i) + "\"\ntype = \"gyro_rate\"\nnoise_density = 1e-5\n";
  CHECK(problems_of(kPaperBeam + many).empty());
  CHECK_THAT(problems_of(kPaperBeam + many + sensor), Contains("line 5: 65 [[sensor]] tables; at most 64"));
}

TEST_CASE("motion tables count with the load profiles' times", "[io][issue20]") {
  auto theta = [](int n) {
    return "[motion.theta]\ntype = \"table\"\ntimes_s = " + numbers(n, 0.0, 0.001) +
           "\nvalues_deg = " + numbers(n, 0.0, 0.0) + "\nrates_deg_s = " + numbers(n, 0.0, 0.0) +
           "\naccelerations_deg_s2 = " + numbers(n, 0.0, 0.0) + "\n";
  };
  // [motion] on line 14, [motion.theta] on 15, times_s on 17; the force pulse has 3 times
  const std::string head = kPaperBeam + kLoad + "[motion]\n";
  CHECK(problems_of(head + theta(9997)).empty());
  CHECK_THAT(problems_of(head + theta(9998)),
             Contains("line 17: motion.theta.times_s: the load profiles and motion tables have 10001 times_s entries "
                      "up to here; at most 10000 together"));
}

TEST_CASE("the [lqg] filter and digital law are bounded in what they keep", "[io][issue20]") {
  // noa 6: n = 18 states, one actuator, one sensor; simulate_until_s = horizon_s, so the
  // law reuses the filter's model: 4 n² + n (m + p + 1) + n m = 1368 doubles a sample, at
  // most 36549 samples (1000 Hz over 36.548 s)
  const std::string lqg = "[[sensor]]\nname = \"gyro\"\ntype = \"gyro_attitude\"\nnoise_density = 1e-5\n"
                          "[lqg]\nsample_rate_hz = 1000\n";  // [lqg] on line 27, the rate on 28
  CHECK(problems_of(controller(6, "36.548", lqg)).empty());
  CHECK_THAT(problems_of(controller(6, "36.549", lqg)),
             Contains("line 28: lqg.sample_rate_hz = 1000 keeps the Kalman filter over controller.simulate_until_s = "
                      "36.549 s and the digital TV-LQR over horizon_s = 36.549 s at noa = 6 (18 states): 50000400 "
                      "doubles; at most 5e+07 (400 MB)"));
}

TEST_CASE("a [sweep]'s samples, their storage and their least work are bounded", "[io][issue20]") {
  // [sweep] on line 23, the rate on 24, samples on 25 (one line later after simulate_until_s)
  auto sweep = [](long samples) {
    return "[sweep]\nsample_rate_hz = 1000\nsamples = " + std::to_string(samples) +
           "\nrequirement_energy_J = 1e-5\n[sweep.actuator_gain]\ndistribution = \"uniform\"\nmin = 0.9\nmax = 1.1\n";
  };
  // full state: the digital law's own discretization over the horizon, 2 n² + n (2 m + 1)
  // = 702 doubles a sample at noa 6: at most 71225 samples (1000 Hz over 71.224 s)
  CHECK(problems_of(controller(6, "71.224", sweep(1))).empty());
  CHECK_THAT(problems_of(controller(6, "71.225", sweep(1))),
             Contains("line 24: sweep.sample_rate_hz = 1000 keeps the digital TV-LQR over horizon_s = 71.225 s at noa "
                      "= 6 (18 states): 50000652 doubles; at most 5e+07"));
  // each flight keeps every sample: at most 200000 over simulate_until_s
  CHECK(problems_of(controller(6, "2", "simulate_until_s = 199.999\n" + sweep(1))).empty());
  CHECK_THAT(problems_of(controller(6, "2", "simulate_until_s = 200\n" + sweep(1))),
             Contains("line 25: sweep.sample_rate_hz = 1000 with controller.simulate_until_s = 200 gives 200001 "
                      "samples of each flight; at most 200000"));
  // least work: 3000 intervals of 400 units and the plant, 729 x 16 + 40 x 16 x 1 = 12304
  // units: 1212304 a sample, at most 824875 samples in 1e12
  CHECK(body_build_work(parse_design(kPaperBeam, "t")) == 729 * 16 + 40 * 16);
  CHECK(problems_of(controller(6, "3", sweep(824875))).empty());
  CHECK_THAT(problems_of(controller(6, "3", sweep(824876))),
             Contains("line 25: sweep.samples = 824876 gives 824876 samples of 3000 sample intervals each "
                      "(sweep.sample_rate_hz = 1000), at least 1000000474304 work units (one step per interval and the "
                      "plant built, 1212304 a sample); at most 1e+12 for a sweep"));
}

TEST_CASE("[export]'s model grid is bounded in memory and its poles in work", "[io][issue20]") {
  // the model grid: model_step_s over 3 s and the gains' 601 points; at noa 6 and one
  // actuator each point keeps n² + n (m + 6) + m = 451 doubles: at most 110864 points
  auto exported = [](int noa, const std::string& step) {
    return controller(noa, "3", "[export]\nmodel_step_s = " + step + "\n");  // model_step_s on line 24
  };
  CHECK(problems_of(exported(6, "2.7208e-5")).empty());  // 110263 + 601 points
  CHECK_THAT(problems_of(exported(6, "2.72079e-5")),
             Contains("line 24: export: the model grid of up to 110865 points (model_step_s = 2.72079e-05 over 3 s "
                      "and the gains' grid_step_s = 0.005 over horizon_s = 3) at noa = 6 (18 states) keeps 50000115 "
                      "doubles (A, B, g, x0, u0, poles); at most 5e+07 (400 MB)"));
  // poles: at noa 30, n³ = 287496 a point, at most 8695 points in 2.5e9
  CHECK(problems_of(exported(30, "3.7071e-4")).empty());
  CHECK_THAT(problems_of(exported(30, "3.7068e-4")),
             Contains("line 24: export: the model grid of up to 8696 points") &&
                 Contains("asks for 2 eigenvalue problems of 66 x 66 at each point: points x n³ = 2500065216; at most "
                          "2.5e+09"));
  // without "poles" the same grid is within the memory bound
  CHECK(problems_of(exported(30, "3.7068e-4") + "contents = [\"gains\", \"model\"]\n").empty());
}

TEST_CASE("[free_vibration] on the finite-element basis is bounded in element-modes", "[io][issue20]") {
  // a uniform beam (no error estimate): 2000 elements x (98 + 2) per NOA value, 15 of them
  // make 3e6; [free_vibration] on line 9, noa_sweep on 10
  const std::string fe = kPaperBeam + "[model]\nbasis = \"finite_element\"\nelements = 2000\nnoa = 6\n[free_vibration]\n";
  auto sweep = [&](int last) {
    std::string s = "noa_sweep = [";
    for (int i = 0; i < 14; ++i) s += "98, ";
    return fe + s + std::to_string(last) + "]\n";
  };
  CHECK(problems_of(sweep(98)).empty());
  CHECK_THAT(problems_of(sweep(99)),
             Contains("line 10: free_vibration: the NOA sweep (with the error estimates' second models), mode shapes "
                      "and spin rates solve element models of 3002000 element-modes together") &&
                 Contains("at most 3e+06"));
  // a stepped beam estimates each NOA's error on a second model, here of half the
  // elements (twice 2000 is past the most): 1.5 times the work
  const std::string stepped = "[[beam.segment]]\nlength_m = 0.5\nmass_per_length_kg_m = 1.0\nbending_stiffness_Nm2 = 1.0\n"
                              "[[beam.segment]]\nlength_m = 0.5\nmass_per_length_kg_m = 2.0\nbending_stiffness_Nm2 = 1.0\n"
                              "[model]\nbasis = \"finite_element\"\nelements = 2000\nnoa = 6\n[free_vibration]\n"
                              "noa_sweep = [98, 98, 98, 98, 98, 98, 98, 98, 98, 98]\n";  // 10 x 300000
  CHECK(problems_of(stepped).empty());
  CHECK_THAT(problems_of(stepped + "[[free_vibration.mode_shape]]\nname = \"m\"\nnoa = 1\nmode = 1\n"),
             Contains("element models of 3006000 element-modes together"));
}

TEST_CASE("an elastic maneuver's NLP is bounded in size and its derivatives count in the optimizer's work",
          "[io][issue20]") {
  auto elastic = [](int intervals, int iterations) {
    return kPaperBeam + "[model]\nnoa = 30\n" + kHub + "[maneuver]\nactuators = [\"hub\"]\nduration_s = 3.0\n" +
           "elastic = true\nintervals = " + std::to_string(intervals) + "\nmax_iterations = " +
           std::to_string(iterations) + "\n[maneuver.final]\ntheta_deg = 90.0\n";  // intervals on line 15
  };
  // 71 unknowns a point (6 + 4 + 2 x 30 states, one control): 495 points x 71² = 2495295
  // and each iteration 35145 unknowns + 495 x (71³ / 100 - 4 x 71) + the rigid
  // counterpart's 3465 + its coarse start's (30 intervals) 61 x 7 = 427 = 1670116.45: at
  // most 26 iterations
  CHECK(problems_of(elastic(247, 26)).empty());
  CHECK_THAT(problems_of(elastic(247, 27)),
             Contains("line 16: maneuver.max_iterations = 27 with intervals = 247 and mesh_refinements = 0 allows "
                      "45093145 Ipopt iteration-unknowns (iterations x NLP unknowns, 35145 unknowns over the rounds, the "
                      "coarse start's 427 for at most 500 iterations (coarse_start = false drops it), the "
                      "elastic derivatives counted as 1631080 more (s³/100 - 4 s at each point of s = 71 unknowns) and "
                      "the rigid counterpart's 3465); at most 4.5e+07"));
  // few elastic modes cost like the rigid problem's unknowns (s = 16: nothing more), but
  // the rigid counterpart's solve still counts
  auto few = [](int iterations) {
    return kPaperBeam + "[model]\nnoa = 6\n" + kHub + "[maneuver]\nactuators = [\"hub\"]\nduration_s = 3.0\n" +
           "elastic = true\nelastic_modes = 2\nintervals = 200\nmax_iterations = " + std::to_string(iterations) +
           "\n[maneuver.final]\ntheta_deg = 90.0\n";
  };
  // 401 points of 15 unknowns (6015), the rigid counterpart's 401 x 7 = 2807 and its coarse
  // start's (25 intervals) 51 x 7 = 357 for at most 500 iterations: 5080 iterations
  CHECK(problems_of(few(5080)).empty());
  CHECK_THAT(problems_of(few(5081)), Contains("allows 45003082 Ipopt iteration-unknowns (iterations x NLP unknowns, "
                                              "6015 unknowns over the rounds, the coarse start's 357 for at most 500 "
                                              "iterations (coarse_start = false drops it), the elastic derivatives "
                                              "counted as 0 more"));
  CHECK_THAT(problems_of(elastic(248, 2)),
             Contains("line 15: maneuver.intervals = 248 with mesh_refinements = 0 gives an elastic NLP of up to 497 "
                      "collocation points of 71 unknowns each (states and controls): points x unknowns² = 2505377; at "
                      "most 2.5e+06"));
}
