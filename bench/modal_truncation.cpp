// Not a benchmark: how much of the paper's moment example the lowest elastic modes carry
// (issue 19, "simulation cost that grows gently with NOA"). The full model on a basis of
// the k lowest Ritz modes of NOA n admissible functions (the eigenvectors of K φ = ω² M_c φ,
// M_c the mass seen by q with the rigid momenta held: docs/theory.md section 8) is
// integrated tightly and compared with the full model on all n functions at rtol 1e-13.
// Dropping the modes above ω_k is what any scheme that does not follow them step by step
// (quasi-static high modes, a cutoff) must get right; this prints how far off the angle is.
//
//   build/bench/modal_truncation [NOA...]       (default: 20)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <vector>

#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/sim/simulate.hpp"

using namespace freeflex;

namespace {

/// The functions ψ_j = Σ_i φ_i V_ij of another basis (its n functions, V n x k).
class CombinedBasis : public ShapeBasis {
 public:
  CombinedBasis(std::shared_ptr<const ShapeBasis> base, Eigen::MatrixXd V) : base_(std::move(base)), V_(std::move(V)) {}
  int size() const override { return static_cast<int>(V_.cols()); }
  BasisValues evaluate(double x) const override {
    const BasisValues b = base_->evaluate(x);
    return {b.phi * V_, b.dphi * V_, b.ddphi * V_};
  }
  std::vector<double> cuts() const override { return base_->cuts(); }
  double max_panel_width() const override { return base_->max_panel_width(); }
  std::string name() const override { return base_->name() + " (combined)"; }

 private:
  std::shared_ptr<const ShapeBasis> base_;
  Eigen::MatrixXd V_;
};

double cpu_ms() { return 1e3 * static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

SimulationOptions options(double rtol, IntegratorOptions::Method method) {
  SimulationOptions o;
  o.duration_s = 1.0;
  o.output_step_s = 0.01;
  o.integrator.rtol = rtol;
  o.integrator.atol = rtol * 1e-2;
  o.integrator.method = method;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> noas;
  for (int i = 1; i < argc; ++i) noas.push_back(std::atoi(argv[i]));
  if (noas.empty()) noas = {20};
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  const std::vector<ForceElement> torque{{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}};
  const Excitation pulse{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0})}};
  std::vector<SimulationResult> refs;
  std::vector<Eigen::VectorXd> mean_axis;  // θ + T_θ q of each reference
  std::printf("| NOA | modes kept | ω_k [rad/s] | first dropped [rad/s] | error θ [rad] | error θ + T_θ q [rad] | "
              "error q | CPU [ms] | steps |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (int noa : noas) {
    const FlexibleBody full(beam, noa, torque);
    const int n = full.n();
    const SimulationResult ref = simulate_full(full, pulse, options(1e-13, IntegratorOptions::Method::Adams));
    if (!ref.ok()) {
      std::printf("reference failed: %s\n", ref.message.c_str());
      return 1;
    }
    refs.push_back(ref);
    // Ritz modes at rest and T = M_rr⁻¹ M_rq (the rigid motion each q drags along)
    const RestModes modes = rest_modes(full);
    const Eigen::MatrixXd& T = modes.T;
    mean_axis.push_back(ref.z.col(2) + ref.z.middleCols(3, n) * T.row(2).transpose());
    const std::shared_ptr<const ShapeBasis> base(&full.basis(), [](const ShapeBasis*) {});
    std::vector<int> kept;
    for (int k : {4, 6, 8, 12, 16})
      if (k < n) kept.push_back(k);
    kept.push_back(n);  // all: the check that the combined basis is the same model
    for (int k : kept) {
      const Eigen::MatrixXd V = modes.Phi.leftCols(k);
      const FlexibleBody reduced(beam, std::make_shared<CombinedBasis>(base, V), torque);
      const double t0 = cpu_ms();
      const SimulationResult s = simulate_full(reduced, pulse, options(1e-11, IntegratorOptions::Method::Verner98));
      const double t1 = cpu_ms();
      if (!s.ok()) {
        std::printf("| %d | %d | failed: %s |\n", noa, k, s.message.c_str());
        continue;
      }
      double e_theta = 0.0, e_mean = 0.0, e_q = 0.0;
      for (Eigen::Index i = 0; i < ref.t.size(); ++i) {
        const Eigen::VectorXd q_ref = ref.z.row(i).segment(3, n).transpose();
        const Eigen::VectorXd q_red = V * s.z.row(i).segment(3, k).transpose();
        e_theta = std::max(e_theta, std::abs(ref.z(i, 2) - s.z(i, 2)));
        // the angle of the beam's mean axis, θ + T_θ q: what the dropped modes' deflection
        // at o (the frame's tangent) does not move
        e_mean = std::max(e_mean, std::abs(ref.z(i, 2) + T.row(2).dot(q_ref) - s.z(i, 2) - T.row(2).dot(q_red)));
        e_q = std::max(e_q, (q_ref - q_red).cwiseAbs().maxCoeff());
      }
      std::printf("| %d | %d | %.0f | %s | %.2g | %.2g | %.2g | %.1f | %ld |\n", noa, k,
                  std::sqrt(modes.omega2(k - 1)),
                  k < n ? std::to_string(static_cast<long>(std::lround(std::sqrt(modes.omega2(k))))).c_str()
                        : "none",
                  e_theta, e_mean, e_q, t1 - t0, s.steps);
    }
  }
  // the full model itself against the one on the most functions
  std::printf("\n| NOA | θ against NOA %d [rad] | at 0.5 s | at 1 s | θ + T_θ q against NOA %d |\n| --- | --- | --- | --- | --- |\n",
              noas.back(), noas.back());
  const SimulationResult& last = refs.back();
  for (std::size_t r = 0; r + 1 < refs.size(); ++r) {
    const Eigen::VectorXd d = (refs[r].z.col(2) - last.z.col(2)).cwiseAbs();
    std::printf("| %d | %.2g | %.2g | %.2g | %.2g |\n", noas[r], d.maxCoeff(), d(50), d(d.size() - 1),
                (mean_axis[r] - mean_axis.back()).cwiseAbs().maxCoeff());
  }
  return 0;
}
