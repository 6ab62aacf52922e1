// The collocation NLP (trajopt/collocation.hpp): its gradient, constraint Jacobian and
// Hessian of the Lagrangian against central differences at random points, for every
// transcription, objective, fixed and free duration and rate bounds; then Ipopt's own
// derivative checker on the same NLPs; then the bad-input messages.
#include <catch2/catch.hpp>

#include <random>
#include <set>
#include <tuple>
#include <unordered_map>

#include "freeflex/trajopt/collocation.hpp"
#include "freeflex/trajopt/solve.hpp"
#include "trajopt/slot_table.hpp"

using namespace freeflex;
using Catch::Matchers::Contains;

namespace {

FlexibleBody rich_body() {
  BeamProperties p;
  p.segments = {{0.6, 1.2, 2.0}, {0.5, 0.7, 1.1}};
  p.reference_m = 0.3;  // S_o != 0
  p.hub_mass_kg = 0.3;
  p.point_masses = {{1.1, 0.25}};
  std::vector<ForceElement> el;
  el.push_back({"force", ForceElement::Type::Force, 0.9, {0.3, -0.8}, false});
  el.push_back({"thruster", ForceElement::Type::Thruster, 0.1, {-0.5, 0.4}, true});
  el.push_back({"torque", ForceElement::Type::Torque, 0.7, {0.0, 0.0}, false});
  return FlexibleBody(Beam(p), 2, el);
}

ManeuverProblem rich_problem(bool free_time, double w_energy, double w_time, double w_smooth, bool rates) {
  ManeuverProblem p;
  p.actuators = {0, 1, 2};
  p.u_min = Eigen::Vector3d(-2.0, -1.0, -0.5);
  p.u_max = Eigen::Vector3d(2.0, 1.5, 0.5);
  if (rates) p.du_max = Eigen::Vector3d(5.0, ManeuverProblem::inf, 3.0);
  p.x_final << 0.3, -0.2, 1.0, 0.0, 0.0, 0.0;
  p.free_time = free_time;
  p.duration_s = 1.7;
  p.t_min_s = 0.5;
  p.t_max_s = 4.0;
  p.w_energy = w_energy;
  p.w_time = w_time;
  p.w_smooth = w_smooth;
  p.energy_weights = Eigen::Vector3d(1.0, 0.5, 2.0);
  return p;
}

Eigen::MatrixXd dense_jacobian(const CollocationNlp& nlp, const Eigen::VectorXd& w) {
  CollocationNlp::Data data = nlp.create_data();
  const Eigen::VectorXd v = nlp.jacobian_values(data, w);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(nlp.num_constraints(), nlp.num_variables());
  for (int i = 0; i < v.size(); ++i) J(nlp.jacobian_rows()[i], nlp.jacobian_cols()[i]) += v(i);
  return J;
}

Eigen::VectorXd lagrangian_gradient(const CollocationNlp& nlp, const Eigen::VectorXd& w, double sigma,
                                    const Eigen::VectorXd& lam) {
  const Eigen::VectorXd g = nlp.objective_gradient(w);
  return sigma * g + dense_jacobian(nlp, w).transpose() * lam;
}

/// Relative errors (max |analytic − central difference| / max |analytic|) of the
/// objective gradient, the constraint Jacobian and the Lagrangian's Hessian at w.
struct DerivativeErrors {
  double gradient, jacobian, hessian;              ///< relative
  double gradient_abs, jacobian_abs, hessian_abs;  ///< max |analytic − central difference|
};

DerivativeErrors derivative_errors(const CollocationNlp& nlp, const Eigen::VectorXd& w, double sigma,
                                   const Eigen::VectorXd& lam, double h) {
  const int n = nlp.num_variables(), m = nlp.num_constraints();
  CollocationNlp::Data data = nlp.create_data();
  const Eigen::VectorXd grad = nlp.objective_gradient(w);
  const Eigen::MatrixXd J = dense_jacobian(nlp, w);
  Eigen::MatrixXd Jfd(m, n), Hfd(n, n);
  Eigen::VectorXd gradfd(n);
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd wp = w, wm = w;
    wp(i) += h;
    wm(i) -= h;
    gradfd(i) = (nlp.objective(wp) - nlp.objective(wm)) / (2 * h);
    const Eigen::VectorXd gp = nlp.constraints(data, wp);
    const Eigen::VectorXd gm = nlp.constraints(data, wm);
    Jfd.col(i) = (gp - gm) / (2 * h);
    Hfd.col(i) = (lagrangian_gradient(nlp, wp, sigma, lam) - lagrangian_gradient(nlp, wm, sigma, lam)) / (2 * h);
  }
  const Eigen::VectorXd hv = nlp.hessian_values(data, w, sigma, lam);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < hv.size(); ++i) {
    const int r = nlp.hessian_rows()[i], cc = nlp.hessian_cols()[i];
    H(r, cc) += hv(i);
    if (r != cc) H(cc, r) += hv(i);
  }
  const double eg = (grad - gradfd).cwiseAbs().maxCoeff(), eJ = (J - Jfd).cwiseAbs().maxCoeff(),
               eH = (H - Hfd).cwiseAbs().maxCoeff();
  return {eg / std::max(1e-300, grad.cwiseAbs().maxCoeff()), eJ / J.cwiseAbs().maxCoeff(), eH / H.cwiseAbs().maxCoeff(),
          eg, eJ, eH};
}

/// The rich problem with the elastic part: modes at rest, vibration weight, tip bound.
ManeuverProblem elastic_problem(bool free_time, int modes) {
  ManeuverProblem p = rich_problem(free_time, 0.5, free_time ? 1.0 : 0.0, 0.1, true);
  p.elastic = true;
  p.modes_at_rest = modes;
  p.w_vibration = 3.0;
  p.tip_deflection_limit_m = 0.05;
  return p;
}

}  // namespace

TEST_CASE("the Hessian's slot table agrees with std::unordered_map, growing from a small start", "[trajopt]") {
  // keys r n + c of a banded pattern and scattered large ones; the table starts with room
  // for 4 entries, so it grows many times on the way to 20 000
  detail::SlotTable table(4);
  std::unordered_map<long long, int> reference;
  std::mt19937_64 rng(11);
  const long long n = 50000;
  auto add = [&](long long key) {
    const int known = table.find(key);
    const auto it = reference.find(key);
    REQUIRE((known >= 0) == (it != reference.end()));
    if (known >= 0) {
      CHECK(known == it->second);
      return;
    }
    const int slot = static_cast<int>(reference.size());
    table.insert(key, slot);
    reference.emplace(key, slot);
  };
  for (long long r = 0; r < 2000; ++r)
    for (long long c = std::max(0LL, r - 4); c <= r; ++c) add(r * n + c);
  for (int k = 0; k < 10000; ++k) add(static_cast<long long>(rng() % (n * n)));
  for (long long r = 0; r < 2000; ++r) add(r * n + r);  // all present already
  REQUIRE(reference.size() > 15000);
  for (const auto& [key, slot] : reference) CHECK(table.find(key) == slot);
  CHECK(table.find(n * n + 7) == -1);  // absent
}

TEST_CASE("collocation NLP derivatives match central differences", "[trajopt]") {
  const FlexibleBody body = rich_body();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  // (free time, w_energy, w_time, w_smooth, rate bounds)
  const std::vector<std::tuple<bool, double, double, double, bool>> cases = {
      {false, 1.0, 0.0, 0.0, false}, {false, 0.0, 0.0, 1.0, true}, {true, 1.0, 0.0, 0.0, false},
      {true, 0.0, 1.0, 0.0, true},   {true, 0.7, 0.3, 0.2, true}};
  for (Transcription tr :
       {Transcription::Trapezoidal, Transcription::HermiteSimpson, Transcription::HermiteSimpsonCompressed})
    for (const auto& c : cases) {
      const ManeuverProblem p =
          rich_problem(std::get<0>(c), std::get<1>(c), std::get<2>(c), std::get<3>(c), std::get<4>(c));
      // a non-uniform mesh exercises the per-interval h_k
      const CollocationNlp nlp(body, p, tr, std::vector<double>{0.2, 0.5, 0.3});
      const int n = nlp.num_variables(), m = nlp.num_constraints();
      INFO(to_string(tr) << " free " << std::get<0>(c) << " we " << std::get<1>(c) << " wt " << std::get<2>(c)
                         << " ws " << std::get<3>(c) << " rates " << std::get<4>(c));
      Eigen::VectorXd w(n), lam(m);
      for (int i = 0; i < n; ++i) w(i) = U(rng);
      for (int i = 0; i < m; ++i) lam(i) = U(rng);
      if (nlp.free_time()) w(nlp.time_index()) = 1.3;
      const double sigma = 0.8;

      // Structure: no duplicates, Hessian entries in the lower triangle.
      std::set<std::pair<int, int>> seen_j, seen_h;
      for (int i = 0; i < nlp.jacobian_nonzeros(); ++i)
        CHECK(seen_j.insert({nlp.jacobian_rows()[i], nlp.jacobian_cols()[i]}).second);
      for (int i = 0; i < nlp.hessian_nonzeros(); ++i) {
        CHECK(nlp.hessian_rows()[i] >= nlp.hessian_cols()[i]);
        CHECK(seen_h.insert({nlp.hessian_rows()[i], nlp.hessian_cols()[i]}).second);
      }

      const double h = 1e-6;  // truncation ~h^2 ~1e-12, round-off ~1e-16/h ~1e-10 (entries O(1..10))
      const DerivativeErrors e = derivative_errors(nlp, w, sigma, lam, h);
      CHECK(e.gradient_abs < 1e-7);  // see h
      CHECK(e.jacobian_abs < 1e-7);  // also: FD is zero wherever the pattern has no entry
      CHECK(e.hessian_abs < 1e-6);  // differences of analytic gradients, entries up to ~1e2
    }
}

TEST_CASE("Ipopt's derivative checker finds no error in the collocation NLP", "[trajopt]") {
  const FlexibleBody body = rich_body();
  // (free time, w_energy, w_time, w_smooth, rates): energy, time and smoothness objectives
  const std::vector<std::tuple<bool, double, double, double, bool>> cases = {
      {false, 1.0, 0.0, 0.0, false}, {true, 1.0, 0.0, 0.0, false}, {true, 0.0, 1.0, 0.0, true},
      {false, 0.0, 0.0, 1.0, true},  {true, 0.0, 0.1, 1.0, true}};
  for (Transcription tr :
       {Transcription::Trapezoidal, Transcription::HermiteSimpson, Transcription::HermiteSimpsonCompressed})
    for (const auto& c : cases) {
      const ManeuverProblem p =
          rich_problem(std::get<0>(c), std::get<1>(c), std::get<2>(c), std::get<3>(c), std::get<4>(c));
      TrajoptOptions o;
      o.transcription = tr;
      o.intervals = 4;
      o.derivative_test = "second-order";
      o.max_iter = 0;  // only the check
      // Ipopt checks at a random perturbation of this start (point_perturbation_radius);
      // non-zero controls make every second-derivative term active.
      o.guess.control = [](double t) { return Eigen::Vector3d(std::sin(3 * t), 0.5 * std::cos(2 * t), 0.3); };
      const TrajoptResult r = solve_maneuver(body, p, o);
      INFO(to_string(tr) << " objective weights " << std::get<1>(c) << " " << std::get<2>(c) << " "
                         << std::get<3>(c) << "\n"
                         << r.log);
      // The log holds the verdict once: "No errors detected" or "detected N error(s)".
      CHECK(r.log.find("Starting derivative checker for second derivatives") != std::string::npos);
      CHECK(r.derivative_test_errors == 0);
    }
}

TEST_CASE("elastic collocation NLP: derivatives within 1e-6 relative of central differences", "[trajopt]") {
  const FlexibleBody body = rich_body();
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (Transcription tr :
       {Transcription::Trapezoidal, Transcription::HermiteSimpson, Transcription::HermiteSimpsonCompressed})
    for (const auto& c : {std::make_tuple(false, 2, -1), std::make_tuple(true, int(ManeuverProblem::all_modes), -1),
                          std::make_tuple(true, 1, 1)}) {
      // (free time, modes at rest, elastic_modes): the last a modal truncation with zero end commands
      ManeuverProblem p = elastic_problem(std::get<0>(c), std::get<1>(c));
      p.elastic_modes = std::get<2>(c);
      p.zero_end_commands = p.elastic_modes > 0;
      const CollocationNlp nlp(body, p, tr, std::vector<double>{0.2, 0.5, 0.3});
      REQUIRE(nlp.state_size() == 6 + 4 + 2 * (p.elastic_modes > 0 ? p.elastic_modes : body.n()));
      const int n = nlp.num_variables(), m = nlp.num_constraints();
      Eigen::VectorXd w(n), lam(m);
      for (int i = 0; i < n; ++i) w(i) = U(rng);
      for (int i = 0; i < m; ++i) lam(i) = U(rng);
      if (nlp.free_time()) w(nlp.time_index()) = 1.3;
      const DerivativeErrors e = derivative_errors(nlp, w, 0.8, lam, 1e-5);
      INFO(to_string(tr) << " free " << std::get<0>(c) << " elastic_modes " << std::get<2>(c) << ": relative errors gradient " << e.gradient << " Jacobian "
                         << e.jacobian << " Hessian " << e.hessian);
      // h = 1e-5: truncation ~h² ~1e-10 and round-off ~1e-16/h ~1e-11 of the largest entries;
      // measured up to ~1e-9
      CHECK(e.gradient < 1e-6);
      CHECK(e.jacobian < 1e-6);
      CHECK(e.hessian < 1e-6);
    }
}

TEST_CASE("Ipopt's derivative checker finds no error in the elastic NLP", "[trajopt]") {
  // The paper's beam with o off centre (S_o != 0), a hub and every element type: its
  // elastic frequencies (tens of rad/s at NOA 2) keep the defects O(1..100).
  BeamProperties bp = BeamProperties::uniform(1.0, 1.0, 1.0);
  bp.reference_m = 0.4;
  bp.hub_mass_kg = 0.2;
  std::vector<ForceElement> el;
  el.push_back({"force", ForceElement::Type::Force, 0.9, {0.3, -0.8}, false});
  el.push_back({"thruster", ForceElement::Type::Thruster, 0.1, {-0.5, 0.4}, true});
  el.push_back({"torque", ForceElement::Type::Torque, 0.7, {0.0, 0.0}, false});
  const FlexibleBody body(Beam(bp), 2, el);
  for (Transcription tr :
       {Transcription::Trapezoidal, Transcription::HermiteSimpson, Transcription::HermiteSimpsonCompressed})
    for (bool free_time : {false, true}) {
      TrajoptOptions o;
      o.transcription = tr;
      o.intervals = 3;
      o.derivative_test = "second-order";
      // Ipopt's checker uses forward differences: with its default step 1e-8 the round-off
      // of the elastic rows reaches 1e-4 relative, with a step of 1e-6 the truncation is
      // ~5e-6 (measured), so it runs at its default tolerance 1e-4 with that step; the 1e-6
      // relative agreement is the central-difference test above (measured 1.3e-10). The
      // point is perturbed by up to 0.1 (the default 10 makes the rows ~1e4: more round-off).
      o.ipopt_options = {{"point_perturbation_radius", "0.1"}, {"derivative_test_perturbation", "1e-6"}};
      o.max_iter = 0;
      o.guess.control = [](double t) { return Eigen::Vector3d(std::sin(3 * t), 0.5 * std::cos(2 * t), 0.3); };
      ManeuverProblem p = elastic_problem(free_time, 2);
      // forward differences of w_vibration K q (K up to 4e3 here) have a truncation error
      // ~step w_vibration K²/2; a small weight keeps the term and the check meaningful
      p.w_vibration = 0.01;
      const TrajoptResult r = solve_maneuver(body, p, o);
      INFO(to_string(tr) << " free " << free_time << "\n" << r.log);
      CHECK(r.log.find("Starting derivative checker for second derivatives") != std::string::npos);
      CHECK(r.derivative_test_errors == 0);
    }
}

TEST_CASE("the derivative-checker verdict is read from Ipopt's log", "[trajopt]") {
  // A tolerance below finite-difference noise makes Ipopt flag correct derivatives: the
  // count must then be positive, so the zero above is a real verdict.
  const FlexibleBody body = rich_body();
  TrajoptOptions o;
  o.transcription = Transcription::HermiteSimpsonCompressed;
  o.intervals = 3;
  o.derivative_test = "second-order";
  o.max_iter = 0;
  o.guess.control = [](double t) { return Eigen::Vector3d(std::sin(3 * t), 0.5 * std::cos(2 * t), 0.3); };
  o.ipopt_options = {{"derivative_test_tol", "1e-14"}};
  const TrajoptResult r = solve_maneuver(body, rich_problem(true, 1.0, 0.5, 0.0, false), o);
  CHECK(r.derivative_test_errors > 0);
  CHECK(r.log.find("Derivative checker detected") != std::string::npos);
  o.derivative_test = "none";
  CHECK(solve_maneuver(body, rich_problem(true, 1.0, 0.5, 0.0, false), o).derivative_test_errors == -1);
}

TEST_CASE("bad maneuver input throws with the field, the expectation and the value", "[trajopt]") {
  const FlexibleBody body = rich_body();
  const ManeuverProblem good = rich_problem(false, 1.0, 0.0, 0.0, false);
  TrajoptOptions o;
  o.transcription = Transcription::HermiteSimpsonCompressed;
  o.intervals = 5;

  TrajoptOptions bad_n = o;
  bad_n.intervals = 0;
  CHECK_THROWS_WITH(solve_maneuver(body, good, bad_n), Contains("intervals = 0, expected >= 1"));

  ManeuverProblem p = good;
  p.u_min(1) = 3.0;
  CHECK_THROWS_WITH(solve_maneuver(body, p, o), Contains("u_min[1] = 3, u_max[1] = 1.5, expected u_min <= u_max"));

  p = good;
  p.actuators = {0, 7, 2};
  CHECK_THROWS_WITH(solve_maneuver(body, p, o),
                    Contains("actuators[1] = 7, expected an element index in [0, 2]"));

  p = good;
  p.duration_s = 0.0;
  CHECK_THROWS_WITH(solve_maneuver(body, p, o), Contains("duration_s = 0, expected a finite value > 0"));
  p.duration_s = -1.0;
  CHECK_THROWS_WITH(solve_maneuver(body, p, o), Contains("duration_s = -1"));

  p = good;
  p.free_time = true;
  p.t_min_s = 5.0;
  p.t_max_s = 2.0;
  CHECK_THROWS_WITH(solve_maneuver(body, p, o), Contains("t_min_s = 5 > t_max_s = 2, expected t_min_s <= t_max_s"));

  p = good;
  p.u_max.resize(2);
  CHECK_THROWS_WITH(solve_maneuver(body, p, o), Contains("u_max has 2 entries, expected 3"));

  p = good;
  p.w_time = 1.0;
  CHECK_THROWS_WITH(solve_maneuver(body, p, o), Contains("expected free_time = true"));

  // Several problems are reported at once.
  p = good;
  p.duration_s = -2.0;
  p.u_min(0) = 9.0;
  CHECK_THROWS_WITH(solve_maneuver(body, p, o), Contains("duration_s = -2") && Contains("u_min[0] = 9"));

  TrajoptOptions bad_opt = o;
  bad_opt.ipopt_options = {{"no_such_option", "1"}};
  CHECK_THROWS_WITH(solve_maneuver(body, good, bad_opt), Contains("'no_such_option'") && Contains("unknown to Ipopt"));
  bad_opt.ipopt_options = {{"max_cpu_time", "fast"}};
  CHECK_THROWS_WITH(solve_maneuver(body, good, bad_opt), Contains("expected a number"));
  bad_opt.ipopt_options = {{"mu_strategy", "sideways"}};
  CHECK_THROWS_WITH(solve_maneuver(body, good, bad_opt), Contains("rejected by Ipopt"));

  TrajoptOptions bad_guess = o;
  bad_guess.guess.control = [](double) { return Eigen::VectorXd::Zero(2); };
  CHECK_THROWS_WITH(solve_maneuver(body, good, bad_guess), Contains("has 2 entries, expected 3"));
}

TEST_CASE("bound multipliers carried to another mesh: nearest place of the same kind, scaled by its weight",
          "[trajopt]") {
  const FlexibleBody body = rich_body();
  const ManeuverProblem p = rich_problem(true, 1.0, 0.1, 0.0, false);
  // The quadrature weight of each place (knot, midpoint or midpoint control) from the mesh
  // fractions, by the rule collocation.hpp gives: trapezoid ½ σ at each end of an
  // interval, Simpson σ/6 at the knots and 4σ/6 at the midpoint.
  struct Place {
    int kind;  // 0: knot, 1: midpoint point (separated HS), 2: midpoint control
    double tau, weight;
    int offset, width;
  };
  const auto places = [](const CollocationNlp& nlp) {
    const std::vector<double>& s = nlp.mesh_fractions();
    const int N = nlp.intervals(), nz = nlp.point_size(), nu = nz - nlp.state_size();
    const bool trap = nlp.transcription() == Transcription::Trapezoidal;
    const double end = trap ? 0.5 : 1.0 / 6.0;
    std::vector<Place> out;
    for (int j = 0; j < nlp.num_points(); ++j) {
      if (!nlp.is_knot(j)) {
        out.push_back({1, nlp.point_fraction(j), 4.0 / 6.0 * s[j / 2], nlp.point_offset(j), nz});
        continue;
      }
      const int k = nlp.transcription() == Transcription::HermiteSimpson ? j / 2 : j;  // interval starting here
      const double w = end * ((k > 0 ? s[k - 1] : 0.0) + (k < N ? s[k] : 0.0));
      out.push_back({0, nlp.point_fraction(j), w, nlp.point_offset(j), nz});
    }
    for (int k = 0; k < nlp.num_mid_controls(); ++k)
      out.push_back({2, nlp.mid_fraction(k), 4.0 / 6.0 * s[k], nlp.mid_control_offset(k), nu});
    return out;
  };
  // non-uniform meshes, and uniform ones whose fine places fall halfway between coarse ones
  const std::vector<std::pair<std::vector<double>, std::vector<double>>> meshes = {
      {{1.0, 2.0, 1.0, 3.0}, {1.0, 1.0, 3.0, 2.0, 1.0, 4.0, 1.0, 2.0, 0.5}},
      {std::vector<double>(4, 1.0), std::vector<double>(8, 1.0)}};
  for (Transcription tr :
       {Transcription::Trapezoidal, Transcription::HermiteSimpson, Transcription::HermiteSimpsonCompressed})
    for (const auto& [coarse_mesh, fine_mesh] : meshes) {
      INFO(to_string(tr) << ", " << coarse_mesh.size() << " -> " << fine_mesh.size() << " intervals");
      const CollocationNlp coarse(body, p, tr, coarse_mesh);
      const CollocationNlp fine(body, p, tr, fine_mesh);
      // z on the coarse mesh: its place's weight times a value that tells places and components apart
      const std::vector<Place> cp = places(coarse), fp = places(fine);
      const auto value = [](const Place& pl, int c) { return 1.0 + pl.kind + 0.1 * c + 10.0 * pl.tau; };
      Eigen::VectorXd z = Eigen::VectorXd::Constant(coarse.num_variables(), -1.0);
      for (const Place& pl : cp)
        for (int c = 0; c < pl.width; ++c) z(pl.offset + c) = pl.weight * value(pl, c);
      z(coarse.time_index()) = 7.5;
      const CollocationNlp::Bounds cb = coarse.bounds();
      const Eigen::VectorXd carried = fine.carried_bound_multipliers(coarse, z);
      REQUIRE(carried.size() == fine.num_variables());
      CHECK(carried(fine.time_index()) == 7.5);  // T's multiplier: not a pointwise bound, as it is
      int checked = 0, from_fixed_neighbour = 0;
      for (const Place& pl : fp)
        for (int c = 0; c < pl.width; ++c, ++checked) {
          // brute force: the coarse place of the kind nearest in time (the later on a tie)
          // where component c is not fixed (the boundary states are: they have no multiplier)
          const Place* nearest = nullptr;
          const Place* nearest_any = nullptr;
          for (const Place& q : cp) {
            if (q.kind != pl.kind) continue;
            if (!nearest_any || std::abs(q.tau - pl.tau) <= std::abs(nearest_any->tau - pl.tau)) nearest_any = &q;
            if (cb.w_lower(q.offset + c) == cb.w_upper(q.offset + c)) continue;
            if (!nearest || std::abs(q.tau - pl.tau) <= std::abs(nearest->tau - pl.tau)) nearest = &q;
          }
          REQUIRE(nearest);
          if (nearest != nearest_any) ++from_fixed_neighbour;
          CHECK(carried(pl.offset + c) == Approx(pl.weight * value(*nearest, c)).epsilon(1e-12));  // round-off only
        }
      CHECK(checked + 1 == fine.num_variables());  // every variable is a place's or T
      CHECK(from_fixed_neighbour > 0);             // the boundary states' neighbours were tried
    }
  // layouts that differ: nothing carried
  const CollocationNlp trap(body, p, Transcription::Trapezoidal, 4);
  const CollocationNlp hs(body, p, Transcription::HermiteSimpson, 4);
  CHECK(hs.carried_bound_multipliers(trap, Eigen::VectorXd::Ones(trap.num_variables())).size() == 0);
}
