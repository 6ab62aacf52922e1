#pragma once
// Direct collocation of a ManeuverProblem as a sparse NLP, solver-independent: values,
// exact sparse first derivatives and the exact sparse Hessian of the Lagrangian.
// The Ipopt adapter (src/trajopt) only forwards to this class.
//
// Mesh: N intervals of length h_k = σ_k T (mesh fractions σ_k > 0, Σ σ_k = 1).
//
// Decision vector w (nz = nx + nu values per point, points in time order; nx = 6 for the
// rigid plant, 6 + 4 + 2n with the elastic part, see trajopt/maneuver_dynamics.hpp):
//   w = [z_0, z_1, ..., z_{P-1}, v_0, ..., v_{N-1}, T],   z_j = [x_j (nx), u_j (nu)]
//   Trapezoidal:      P = N + 1, point j is knot j; no v.
//   Hermite–Simpson:  P = 2N + 1, point 2k is knot k, point 2k+1 the midpoint of interval
//                     k (separated form); no v.
//   HS compressed:    P = N + 1 knots; v_k = u_c (nu) is the midpoint control of interval
//                     k, the midpoint state is x_c = (x_a + x_b)/2 + h_k/8 (f_a − f_b).
//   T (the duration) is the last entry only when problem.free_time.
//
// Constraints g(w), in this order:
//   for each interval k = 0..N-1 (a = its first knot, b = its last, c = its midpoint):
//     Trapezoidal:  x_b − x_a − h_k/2 (f_a + f_b)                        (nx rows)
//     HS:           x_c − (x_a + x_b)/2 − h_k/8 (f_a − f_b)   interpolation (nx rows)
//                   x_b − x_a − h_k/6 (f_a + 4 f_c + f_b)     Simpson       (nx rows)
//     HS compressed: the Simpson rows only, f_c = f(x_c(x_a, x_b, u_a, u_b, T), u_c)
//   all = 0. Then, if problem.du_max, per interval and actuator (skipping infinite bounds):
//     Trapezoidal:  e = u_b − u_a                                      (h u' on the piece)
//     HS:           e0 = −3u_a + 4u_c − u_b,  e1 = u_a − 4u_c + 3u_b   (h u' at both ends)
//     fixed T: one row per e with bounds ±du_max h_k; free T: two linear rows,
//     e − du_max σ_k T <= 0 and e + du_max σ_k T >= 0.
//   Then (HS forms) per interval and actuator with a finite limit, the middle Bernstein
//     coefficient of the quadratic control, 2u_c − (u_a + u_b)/2 in [u_min, u_max]: with
//     u_a, u_b bounded too, the whole quadratic lies within the bounds (docs/theory.md).
//   Then, with the elastic part: per point after the first (compressed: knots), the tip
//     deflections Φ(x_left) q_j and Φ(x_right) q_j in ±tip_deflection_limit_m; then per
//     targeted mode j, ω_j η_j(T) = 0 and η_j'(T) = 0 (η = modal_rows q).
// Variable bounds: x_0 = x_initial and x_{P-1} = x_final (fixed; the elastic part of x_0
// is 0 and of x_{P-1} free), interior rigid states in [x_min, x_max], controls in
// [u_min, u_max] at every point, T in [t_min_s, t_max_s].
//
// Objective, by the transcription's quadrature (Trapezoid / Simpson weights q_j):
//   w_energy T Σ_j q̄_j Σ_k W_k u_jk²  +  w_time T  +  w_smooth Σ_k (1/h_k) Σ_act e_kᵀ M e_k
//   + w_vibration ½ (q'ᵀ M_c q' + qᵀ K q) at the last point
// where the smoothness term is the exact ∫ u'² dt of the piecewise linear / quadratic
// control.
//
// Evaluation is const and thread-safe: f and ∂f at the last w are cached in a Data
// workspace that the caller owns (create_data()), one per thread.
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/trajopt/problem.hpp"
#include "freeflex/trajopt/maneuver_dynamics.hpp"
#include "freeflex/trajopt/trajectory.hpp"

namespace freeflex {

class CollocationNlp {
 public:
  /// Workspace of one thread of evaluation: the results of the calls that take it, and
  /// the cache of f and ∂f at the last w they were given.
  struct Data {
    Eigen::VectorXd constraints;  ///< g(w), from constraints()
    Eigen::VectorXd jacobian;     ///< Jacobian values (triplet order), from jacobian_values()
    Eigen::VectorXd hessian;      ///< Hessian values (triplet order), from hessian_values()
    /// Cache and scratch (no meaning outside the NLP's own calls).
    struct Cache {
      Eigen::VectorXd w;  // the w that f (and J when jac_valid) describe
      bool f_valid = false, jac_valid = false;
      Eigen::MatrixXd f;             // nx x P, f at the points
      Eigen::MatrixXd J;             // nx x (nz P)
      Eigen::MatrixXd xc, fc, Jc;    // HS compressed: nx x N, nx x N, nx x (nz N)
      Eigen::MatrixXd lam_eff, nu_eff;  // nx x P
      Eigen::MatrixXd D, Y, B;          // HS compressed: nx x q, nz x q, q x q
      Eigen::MatrixXd Yr, Hsr, Hss, L, R;  // HS compressed: YᵀHY = Lᵀ R (collocation_hessian.cpp)
      ManeuverDynamics::Data dyn;
    } cache;
  };

  /// Variable and constraint bounds; infinite ones are ±infinity.
  struct Bounds {
    Eigen::VectorXd w_lower, w_upper, g_lower, g_upper;
  };

  /// Midpoint states and controls of every interval (HS forms), N x nx and N x nu.
  struct Midpoints {
    Eigen::MatrixXd x, u;
  };

  /// Uniform mesh of `intervals` intervals. Validates the problem (std::invalid_argument).
  CollocationNlp(const FlexibleBody& body, const ManeuverProblem& problem, Transcription transcription, int intervals);
  /// Mesh fractions σ_k (> 0; normalized to sum 1).
  CollocationNlp(const FlexibleBody& body, const ManeuverProblem& problem, Transcription transcription,
                 std::vector<double> mesh_fractions);

  const ManeuverDynamics& dynamics() const { return dyn_; }
  /// nx: 6, or 6 + 4 + 2n with the elastic part.
  int state_size() const { return nx_; }
  /// The targeted modes (indices into dynamics().elastic()->mode_frequencies()).
  const std::vector<int>& modes_at_rest() const { return rest_modes_; }
  const ManeuverProblem& problem() const { return problem_; }
  Transcription transcription() const { return tr_; }
  int intervals() const { return static_cast<int>(sigma_.size()); }
  const std::vector<double>& mesh_fractions() const { return sigma_; }
  int num_points() const { return P_; }
  int point_size() const { return nz_; }
  int num_variables() const { return n_; }
  int num_constraints() const { return m_; }
  int num_defect_constraints() const { return m_defect_; }
  bool free_time() const { return problem_.free_time; }
  /// Index of T in w, or -1 for a fixed duration.
  int time_index() const { return free_time() ? n_ - 1 : -1; }
  /// t_j / T for point j.
  double point_fraction(int j) const { return tau_[j]; }
  /// Index of x_j(0) in w; u_j starts nx further.
  int point_offset(int j) const { return j * nz_; }
  /// True for points that are knots (all but the separated form's odd points).
  bool is_knot(int j) const { return tr_ != Transcription::HermiteSimpson || j % 2 == 0; }
  /// Midpoint controls held apart from the points (HS compressed: N, otherwise 0).
  int num_mid_controls() const { return tr_ == Transcription::HermiteSimpsonCompressed ? intervals() : 0; }
  /// Index of u_c(0) of interval k in w (HS compressed).
  int mid_control_offset(int k) const { return P_ * nz_ + k * nu_; }
  /// t / T at the midpoint of interval k.
  double mid_fraction(int k) const { return tau_mid_[k]; }
  double duration(const Eigen::Ref<const Eigen::VectorXd>& w) const;

  Data create_data() const;
  Bounds bounds() const;

  double objective(const Eigen::Ref<const Eigen::VectorXd>& w) const;
  Eigen::VectorXd objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& w) const;
  /// g(w), into data.constraints.
  const Eigen::VectorXd& constraints(Data& data, const Eigen::Ref<const Eigen::VectorXd>& w) const;

  /// Jacobian of g in triplet form (0-based); the structure never changes.
  int jacobian_nonzeros() const { return static_cast<int>(jac_rows_.size()); }
  const std::vector<int>& jacobian_rows() const { return jac_rows_; }
  const std::vector<int>& jacobian_cols() const { return jac_cols_; }
  /// The values of the Jacobian's triplets at w, into data.jacobian.
  const Eigen::VectorXd& jacobian_values(Data& data, const Eigen::Ref<const Eigen::VectorXd>& w) const;

  /// Lower triangle (row >= col) of ∇²(obj_factor J + λᵀ g), triplets, no duplicates.
  int hessian_nonzeros() const { return static_cast<int>(hess_rows_.size()); }
  const std::vector<int>& hessian_rows() const { return hess_rows_; }
  const std::vector<int>& hessian_cols() const { return hess_cols_; }
  /// The values of the Hessian's triplets at (w, obj_factor, λ), into data.hessian.
  const Eigen::VectorXd& hessian_values(Data& data, const Eigen::Ref<const Eigen::VectorXd>& w, double obj_factor,
                                        const Eigen::Ref<const Eigen::VectorXd>& lambda) const;

  /// E_vib at the last point (eq. 6.8) of w; 0 without the elastic part.
  double terminal_vibration_energy(const Eigen::Ref<const Eigen::VectorXd>& w) const;

  /// max |defect| over all collocation rows (interpolation rows included).
  double max_defect(const Eigen::Ref<const Eigen::VectorXd>& w) const;

  /// Midpoint states and controls of every interval (HS forms only).
  Midpoints midpoints(const Eigen::Ref<const Eigen::VectorXd>& w) const;

  /// Multipliers of variable bounds found on `from` (the same problem and transcription on
  /// another mesh), carried to this NLP's variables: each takes the multiplier of the
  /// variable of `from` of the same kind (knot, midpoint, midpoint control) and component
  /// nearest in time (on a tie the later; variables `from` fixes are passed over: they
  /// have none), scaled by the ratio of their points' quadrature weights (a pointwise
  /// bound's multiplier grows with the weight its point carries in the objective); T's
  /// is taken as it is. Empty when the two NLPs' layouts differ.
  Eigen::VectorXd carried_bound_multipliers(const CollocationNlp& from, const Eigen::Ref<const Eigen::VectorXd>& z) const;

  /// The continuous trajectory that w stands for (see trajopt/trajectory.hpp).
  std::shared_ptr<const CollocationTrajectory> trajectory(const Eigen::Ref<const Eigen::VectorXd>& w) const;

 private:
  struct Term {  // one point in one defect block: β x_j − h α f_j
    int point;
    double beta, alpha;
  };
  struct Block {  // 6 defect rows
    int interval, row;
    std::vector<Term> terms;
  };
  struct LinearRow {  // Σ coef w + time_coef T in [lower, upper]
    int row;
    std::vector<std::pair<int, double>> coef;  // (index in w, coefficient)
    bool timed;                                // has a T column (free time only)
    double time_coef;
    double lower, upper;
  };
  struct CtrlPoint {  // a place where controls are decision variables
    int offset;       // index of u(0) in w
    double qbar;      // Σ_k σ_k q_k: the quadrature weight of its energy term, / T
  };

  // Construction (collocation_structure.cpp): the layout, then the rows and sparsity.
  void build();
  void build_layout();
  void build_defect_rows();
  void build_rate_rows();
  void build_linear_rows();  // Bernstein, tip deflection and terminal rows
  void build_jacobian_structure();
  void build_hessian_structure();
  void build_compressed_hessian_structure(const std::function<int(int, int)>& slot);

  double T_of(const Eigen::Ref<const Eigen::VectorXd>& w) const;
  int vib_q_index() const;   // q(0) of the last point in w
  int vib_qd_index() const;  // q'(0) of the last point in w
  void check_size(const Eigen::Ref<const Eigen::VectorXd>& w) const;
  void ensure_f(Data::Cache& c, const Eigen::Ref<const Eigen::VectorXd>& w) const;
  void ensure_jac(Data::Cache& c, const Eigen::Ref<const Eigen::VectorXd>& w) const;
  void compressed_midpoints(Data::Cache& c, const Eigen::Ref<const Eigen::VectorXd>& w, bool with_jacobian) const;
  void constraints_into(Data::Cache& c, const Eigen::Ref<const Eigen::VectorXd>& w,
                        Eigen::Ref<Eigen::VectorXd> g) const;
  int first_point(int interval) const { return tr_ == Transcription::HermiteSimpson ? 2 * interval : interval; }
  int points_per_interval() const { return tr_ == Transcription::Trapezoidal ? 2 : 3; }
  /// Control point index (into ctrl_) of the i-th control of interval k (i < points_per_interval).
  int ctrl_of(int k, int i) const;
  double smooth_quadratic(const Eigen::Ref<const Eigen::VectorXd>& w, int interval) const;
  void compressed_jacobian_block(Data::Cache& c, int k, double T) const;  // fills c.D for interval k

  ManeuverDynamics dyn_;
  ManeuverProblem problem_;
  Transcription tr_;
  std::vector<double> sigma_;
  int nx_ = 6, nu_ = 0, nz_ = 0, P_ = 0, n_ = 0, m_ = 0, m_defect_ = 0;
  std::vector<int> rest_modes_;
  std::vector<double> tau_, tau_mid_;  // point and midpoint time fractions
  std::vector<CtrlPoint> ctrl_;
  Eigen::VectorXd W_;               // energy weights
  Eigen::MatrixXd Msmooth_;         // 2x2 or 3x3 smoothness form per interval and actuator
  std::vector<Block> blocks_;       // trapezoidal and separated HS
  std::vector<LinearRow> rates_;  // rate rows, then the other linear rows

  // Jacobian: per (block, term) the pattern kind and first value index.
  std::vector<std::pair<int, int>> pat_[3];  // 0: identity only, 1: f only, 2: both
  std::vector<std::vector<int>> term_start_;  // [block][term]
  std::vector<int> block_time_start_;         // [block], first of 6 T-column entries
  std::vector<int> rate_start_;
  std::vector<std::vector<int>> dense_vars_;  // HS compressed: [interval] = z_a, z_b, u_c, T
  std::vector<int> dense_jac_start_;          // HS compressed: [interval], 6 x q row-major
  std::vector<int> jac_rows_, jac_cols_;

  // Hessian slots.
  std::vector<int> hess_rows_, hess_cols_;
  std::vector<std::vector<int>> f_slots_;       // [point][hessian_pattern entry]
  std::vector<std::vector<int>> fT_slots_;      // [point][column c of z], (T, z_j(c)); −1 if none
  std::vector<std::vector<int>> energy_slots_;  // [control point][actuator]
  std::vector<std::vector<int>> uT_slots_;      // [control point][actuator], (T, u); free time
  std::vector<std::vector<int>> smooth_slots_;  // [interval*nu + actuator][pair]
  std::vector<int> smooth_pair_i_, smooth_pair_j_;  // local control indices, i >= j
  std::vector<int> dense_act_, dense_trow_;
  std::vector<int> h_rows_;                     // HS compressed: z-indices in the dynamics' Hessian pattern
  std::vector<int> h_cover_, h_rest_;           // h_rows_ split: a vertex cover of the pattern, the rest
  std::vector<std::vector<int>> dense_slots_;   // HS compressed: [interval], pairs of dense_act_
  std::vector<std::vector<int>> denseT_slots_;  // HS compressed: [interval], (T, dense_trow_), (T, T)
  int TT_slot_ = -1;
  std::vector<int> vib_slots_;               // lower triangles of the q and q' blocks at the last point
  std::vector<std::pair<int, int>> vib_ij_;  // their (i, j) in the K / M_c block; i < n: q, else q' (− n)
  std::vector<int> fcols_;  // columns of z on which f depends
};

/// A starting point for `nlp` from `guess` (see InitialGuess), controls clipped to their
/// bounds, interior states to theirs, the boundary states set, T clamped into its bounds.
/// Throws std::invalid_argument if guess.control returns the wrong number of entries or
/// guess.solution has a different number of actuators.
Eigen::VectorXd initial_point(const CollocationNlp& nlp, const InitialGuess& guess);

}  // namespace freeflex
