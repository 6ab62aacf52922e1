#pragma once
// Exponential collocation for the backward Riccati flow of the TV-LQR (control/tvlqr.hpp
// and docs/theory.md §12 explain the choice). On a step [τ, τ + h] the closed loop is
// frozen at the predicted midpoint, Ā = A(τ_m) − S(τ_m) P_m, and brought to real block-
// diagonal form Ā = V D V⁻¹ (ModalLyapunovSolver, real eigenvalues sorted so that a
// near-defective pair stays one block). In W = Vᵀ P V and w = Vᵀ s the linear part of
//   P' = Āᵀ P + P Ā + N_P(τ, P),   s' = Āᵀ s + N_s(τ, P, s),   c' = 2 sᵀ v + N_c(τ, s)
// acts block by block and is integrated exactly with φ-functions (phi_functions.hpp),
// as is the part of c' linear in s (v = g − S s_m frozen); the remainders N (what the
// frozen loop misses: the model's change over the step, the quadratic terms) are
// interpolated by a quadratic through three Gauss nodes, whose stage values come from a
// fixed-point iteration. Closed-loop oscillations and fast real poles are thus integrated
// exactly, and the step is set by how fast the remainders vary. The local error is
// estimated by the defect of the remainder at the step's end, and any time inside an
// accepted step is served by the same formulas. Private to src/.
#include <array>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "control/phi_functions.hpp"
#include "control/riccati_flow.hpp"

namespace freeflex::detail {

class ExponentialRiccati {
 public:
  struct Settings {
    double rtol = 1e-8, atol = 1e-10;  // of the σ-scaled P, s, c (as CVODES's tolerances)
    double max_condition = 1e6;        // κ₁(V) above which a step has no block-diagonal form
    int max_iterations = 10;           // fixed-point iterations per step
  };
  enum class Outcome { Accepted, Rejected, NoForm, Failed };

  ExponentialRiccati(RiccatiData& d, Settings settings);

  /// The state at τ (σ-scaled P, s, c); evaluates the right-hand side there. False (and
  /// d.error) if the model fails.
  bool start(double tau, const Eigen::MatrixXd& P, const Eigen::VectorXd& s, double c);

  /// One step of size h from the current state. Accepted: the state moves to τ + h and
  /// state_at() serves times inside the step. Rejected: local error or fixed-point test
  /// failed (retry with suggested_step()). NoForm: the frozen closed loop has no
  /// well-conditioned block-diagonal form (take this step another way). Failed: the model
  /// failed (d.error says why).
  Outcome step(double h);
  double suggested_step() const { return h_next_; }
  double tau() const { return tau_; }
  const Eigen::MatrixXd& P() const { return P_; }
  const Eigen::VectorXd& s() const { return s_; }
  double c() const { return c_; }
  const std::string& reject_reason() const { return reject_reason_; }

  /// After an accepted step from τ0 of size h: at τ0 + θh (θ in (0, 1]), Gᵀ P (m x n, G =
  /// B L⁻ᵀ at that time, R = L Lᵀ), s, c, and P itself when P_out is given.
  void state_at(double theta, const Eigen::MatrixXd& G, Eigen::MatrixXd& GtP, Eigen::VectorXd& s, double& c,
                Eigen::MatrixXd* P_out);

  /// The largest |λ| of the last frozen closed loop (0 before the first step): after a
  /// breakpoint its fast poles' transients pass within ~1/|λ|.
  double fastest_rate() const;

  long iterations() const { return iterations_; }
  long rhs_evaluations() const { return rhs_evaluations_; }
  long factorizations() const { return factorizations_; }

 private:
  struct Node {
    Eigen::MatrixXd At, G;
    Eigen::VectorXd g;
  };
  /// The collocation inputs: X[0] = W0 with φ_0, X[j+1] = the remainder's monomial
  /// coefficient M_j with h θ^{j+1} j! φ_{j+1}; Y[k] their products with the blocks' N.
  struct Inputs {
    std::array<Eigen::MatrixXd, 4> X;
    std::array<Eigen::VectorXd, 4> x;
    std::array<std::array<Eigen::MatrixXd, 4>, 4> Y;  // X, NᵀX, XN, NᵀXN
    std::array<std::array<Eigen::VectorXd, 2>, 4> y;  // x, Nᵀx
  };
  struct NodeForm {  // the model at a node in the form: Eᵀ = (V⁻¹ A V − D)ᵀ, V⁻¹ G, V⁻¹ g
    Eigen::MatrixXd Et, G;
    Eigen::VectorXd g;
  };
  struct Coefficients {  // φ_0..φ_4 of every block pair (I <= J) and block at one θ
    std::vector<PairCoefficients> pairs;
    std::vector<BlockCoefficients> blocks;
  };

  bool model_at(double tau, Node& node);
  void rhs(const Node& node, const Eigen::MatrixXd& P, const Eigen::VectorXd& s, Eigen::MatrixXd& FP,
           Eigen::VectorXd& Fs, double& Fc);
  void to_form(const Eigen::MatrixXd& X, Eigen::MatrixXd& W);    // Vᵀ X V (X symmetric)
  void from_form(const Eigen::MatrixXd& W, Eigen::MatrixXd& X);  // V⁻ᵀ W V⁻¹
  void left(const Eigen::MatrixXd& X, Eigen::MatrixXd& out) const;   // blockdiag(N)ᵀ X
  void right(const Eigen::MatrixXd& X, Eigen::MatrixXd& out) const;  // X blockdiag(N)
  void left(const Eigen::VectorXd& x, Eigen::VectorXd& out) const;   // blockdiag(N)ᵀ x
  /// The remainders in the form at a stage: Vᵀ F V − (Dᵀ W + W D), Vᵀ F_s − Dᵀ w.
  void remainders(const Eigen::MatrixXd& FP, const Eigen::VectorXd& Fs, const Eigen::MatrixXd& W,
                  const Eigen::VectorXd& w, Eigen::MatrixXd& N, Eigen::VectorXd& ns);
  void coefficients(double theta, int kmax_pairs, int kmax_blocks, Coefficients& out) const;
  void node_form(const Node& nd, NodeForm& f);
  /// The remainders of a stage from its values W, w in the form (v: ṽ = V⁻¹ v of c').
  void form_remainder(const NodeForm& f, const Eigen::MatrixXd& W, const Eigen::VectorXd& w, const Eigen::VectorXd& v,
                      Eigen::MatrixXd& N, Eigen::VectorXd& ns, double& rc);
  void prepare(Inputs& in, int K) const;
  /// Σ_k scale_k (φ_{k + shift} coefficients) applied to the inputs k = 0..K.
  void combine(const Coefficients& co, const double* scale, int K, const Inputs& in, Eigen::MatrixXd& W) const;
  void combine(const Coefficients& co, const double* scale, int K, int shift, const Inputs& in,
               Eigen::VectorXd& w) const;
  /// W, w and c at θ from the current inputs (c by the exact integral of its linear part).
  void evaluate(double theta, const Coefficients& co, Eigen::MatrixXd* W, Eigen::VectorXd& w, double* c) const;
  double wrms(const Eigen::MatrixXd& dP, const Eigen::VectorXd& ds, double dc, const Eigen::MatrixXd& Pref,
              const Eigen::VectorXd& sref, double cref) const;

  RiccatiData& d_;
  Settings set_;
  int n_, m_;
  ModalLyapunovSolver form_;
  Eigen::VectorXd mids_;  // the block of each index: its D_II = mid I + N
  std::vector<std::pair<int, int>> pair_index_;  // (I, J), I <= J

  // the state and its derivatives at tau_
  double tau_ = 0.0, h_ = 0.0, h_next_ = 0.0;
  Eigen::MatrixXd P_, FP_;
  Eigen::VectorXd s_, Fs_;
  double c_ = 0.0, Fc_ = 0.0;
  Node start_node_, end_node_, nodes_[3];

  // the last step
  Inputs in_, defect_;
  Eigen::VectorXd vform_;  // V⁻¹ v: c' = 2 sᵀ v + r_c, v = g − σ G Gᵀ s_m at the midpoint
  double c0_ = 0.0, rc_[3] = {0.0, 0.0, 0.0}, rcm_[3] = {0.0, 0.0, 0.0};  // r_c at the nodes, monomials
  Coefficients co_[4];  // at the three nodes and the end
  Coefficients co_out_;                        // dense output
  Eigen::MatrixXd Wout_, UG_, GtW_;
  Eigen::VectorXd wout_;
  mutable Eigen::VectorXd integral_;
  std::string reject_reason_;

  NodeForm nf_[3];
  Eigen::MatrixXd work_, scratch_, corr_mid_, Abar_, Qform_, WG_, Wk_[3], Wold_, Wend_, Pend_, FPend_, corr_;
  Eigen::VectorXd wk_[3], wold_, sold_, wend_, send_, Fsend_, corr_w_;
  Eigen::MatrixXd Nk_[3];
  Eigen::VectorXd nk_[3];

  long iterations_ = 0, rhs_evaluations_ = 0, factorizations_ = 0;
};

}  // namespace freeflex::detail
