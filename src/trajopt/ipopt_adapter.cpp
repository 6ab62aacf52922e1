// Ipopt 3.11 behind the collocation NLP: a TNLP that forwards to CollocationNlp and its
// workspace, the options freeflex sets and the user's, and Ipopt's return status in
// freeflex's terms. Ipopt's headers stay in this file.
#include "trajopt/ma27_bridge.hpp"
#include "trajopt/ipopt_adapter.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <stdexcept>
#include <string>

#include <coin/IpIpoptApplication.hpp>
#include <coin/IpSolveStatistics.hpp>
#include <coin/IpTNLP.hpp>

namespace freeflex::detail {

namespace {

using Ipopt::Index;
using Ipopt::Number;

/// Collects Ipopt's output in a string (the derivative checker's verdict is read from it).
class StringJournal : public Ipopt::Journal {
 public:
  StringJournal(Ipopt::EJournalLevel level, std::string* out) : Ipopt::Journal("freeflex-log", level), out_(out) {}

 protected:
  void PrintImpl(Ipopt::EJournalCategory, Ipopt::EJournalLevel, const char* str) override { out_->append(str); }
  void PrintfImpl(Ipopt::EJournalCategory, Ipopt::EJournalLevel, const char* fmt, va_list ap) override {
    va_list copy;
    va_copy(copy, ap);
    char buf[1024];
    const int len = std::vsnprintf(buf, sizeof buf, fmt, ap);
    if (len >= 0 && static_cast<std::size_t>(len) < sizeof buf) {
      out_->append(buf, static_cast<std::size_t>(len));
    } else if (len >= 0) {
      std::string big(static_cast<std::size_t>(len) + 1, '\0');
      std::vsnprintf(&big[0], big.size(), fmt, copy);
      big.resize(static_cast<std::size_t>(len));
      out_->append(big);
    }
    va_end(copy);
  }
  void FlushBufferImpl() override {}

 private:
  std::string* out_;
};

/// The TNLP. Every callback catches everything: no exception crosses into Ipopt; the
/// first message is kept and reported in the result.
class CollocationTnlp : public Ipopt::TNLP {
 public:
  CollocationTnlp(const CollocationNlp& nlp, Eigen::VectorXd w0, const BoundMultipliers* z0)
      : nlp_(nlp), data_(nlp.create_data()), w0_(std::move(w0)), z0_(z0) {}

  Eigen::VectorXd w_final;
  BoundMultipliers z_final;
  double obj_final = std::numeric_limits<double>::quiet_NaN();
  bool finalized = false;
  std::string error;

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& index_style) override {
    n = nlp_.num_variables();
    m = nlp_.num_constraints();
    nnz_jac_g = nlp_.jacobian_nonzeros();
    nnz_h_lag = nlp_.hessian_nonzeros();
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    return guard([&] {
      const CollocationNlp::Bounds b = nlp_.bounds();
      // Ipopt reads |bound| >= 1e19 as no bound.
      const double big = 1e20;
      Eigen::Map<Eigen::VectorXd>(x_l, n) = b.w_lower.cwiseMax(-big);
      Eigen::Map<Eigen::VectorXd>(x_u, n) = b.w_upper.cwiseMin(big);
      Eigen::Map<Eigen::VectorXd>(g_l, m) = b.g_lower.cwiseMax(-big);
      Eigen::Map<Eigen::VectorXd>(g_u, m) = b.g_upper.cwiseMin(big);
    });
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number* z_L, Number* z_U, Index m,
                          bool init_lambda, Number* lambda) override {
    if (init_x) std::copy(w0_.data(), w0_.data() + n, x);
    // Only asked for with warm_start_init_point = yes: set with z0, or by a user's
    // ipopt_options (then zeros, which Ipopt raises to warm_start_mult_bound_push).
    if (init_z) {
      const bool known = z0_ && z0_->lower.size() == n && z0_->upper.size() == n;
      Eigen::Map<Eigen::VectorXd>(z_L, n) = known ? z0_->lower : Eigen::VectorXd::Zero(n);
      Eigen::Map<Eigen::VectorXd>(z_U, n) = known ? z0_->upper : Eigen::VectorXd::Zero(n);
    }
    if (init_lambda) std::fill(lambda, lambda + m, 0.0);
    return true;
  }

  bool eval_f(Index n, const Number* x, bool, Number& obj_value) override {
    return guard([&] { obj_value = nlp_.objective(Eigen::Map<const Eigen::VectorXd>(x, n)); });
  }

  bool eval_grad_f(Index n, const Number* x, bool, Number* grad_f) override {
    return guard([&] {
      Eigen::Map<Eigen::VectorXd>(grad_f, n) = nlp_.objective_gradient(Eigen::Map<const Eigen::VectorXd>(x, n));
    });
  }

  bool eval_g(Index n, const Number* x, bool, Index m, Number* g) override {
    return guard([&] {
      Eigen::Map<Eigen::VectorXd>(g, m) = nlp_.constraints(data_, Eigen::Map<const Eigen::VectorXd>(x, n));
    });
  }

  bool eval_jac_g(Index n, const Number* x, bool, Index, Index nele_jac, Index* iRow, Index* jCol,
                  Number* values) override {
    return guard([&] {
      if (!values) {
        std::copy(nlp_.jacobian_rows().begin(), nlp_.jacobian_rows().end(), iRow);
        std::copy(nlp_.jacobian_cols().begin(), nlp_.jacobian_cols().end(), jCol);
        return;
      }
      Eigen::Map<Eigen::VectorXd>(values, nele_jac) =
          nlp_.jacobian_values(data_, Eigen::Map<const Eigen::VectorXd>(x, n));
    });
  }

  bool eval_h(Index n, const Number* x, bool, Number obj_factor, Index m, const Number* lambda, bool,
              Index nele_hess, Index* iRow, Index* jCol, Number* values) override {
    return guard([&] {
      if (!values) {
        std::copy(nlp_.hessian_rows().begin(), nlp_.hessian_rows().end(), iRow);
        std::copy(nlp_.hessian_cols().begin(), nlp_.hessian_cols().end(), jCol);
        return;
      }
      Eigen::Map<Eigen::VectorXd>(values, nele_hess) = nlp_.hessian_values(
          data_, Eigen::Map<const Eigen::VectorXd>(x, n), obj_factor, Eigen::Map<const Eigen::VectorXd>(lambda, m));
    });
  }

  void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number* z_L, const Number* z_U, Index,
                         const Number*, const Number*, Number obj_value, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    try {
      if (x) w_final = Eigen::Map<const Eigen::VectorXd>(x, n);
      if (z_L && z_U) {
        z_final.lower = Eigen::Map<const Eigen::VectorXd>(z_L, n);
        z_final.upper = Eigen::Map<const Eigen::VectorXd>(z_U, n);
      }
      obj_final = obj_value;
      finalized = true;
    } catch (const std::exception& e) {
      if (error.empty()) error = e.what();
    } catch (...) {
      if (error.empty()) error = "unknown exception in finalize_solution";
    }
  }

 private:
  template <class F>
  bool guard(F&& f) {
    try {
      f();
      return true;
    } catch (const std::exception& e) {
      if (error.empty()) error = e.what();
    } catch (...) {
      if (error.empty()) error = "unknown exception in an Ipopt callback";
    }
    return false;
  }

  const CollocationNlp& nlp_;
  CollocationNlp::Data data_;  // the NLP's cache of f and ∂f at Ipopt's last point
  Eigen::VectorXd w0_;
  const BoundMultipliers* z0_;  // the bound multipliers to start from, or none
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

/// Sets one user option by its registered type; throws std::invalid_argument naming it.
void set_user_option(Ipopt::IpoptApplication& app, const std::string& name, const std::string& raw) {
  const std::string value = trim(raw);
  Ipopt::SmartPtr<const Ipopt::RegisteredOption> reg = app.RegOptions()->GetOption(name);
  const std::string where = "trajopt options: ipopt option '" + name + "' = '" + raw + "'";
  if (Ipopt::IsNull(reg)) throw std::invalid_argument(where + ": unknown to Ipopt");
  bool ok = false;
  char* end = nullptr;
  switch (reg->Type()) {
    case Ipopt::OT_Integer: {
      const long v = std::strtol(value.c_str(), &end, 10);
      if (value.empty() || *end != '\0') throw std::invalid_argument(where + ", expected an integer");
      ok = reg->IsValidIntegerSetting(static_cast<Index>(v)) &&
           app.Options()->SetIntegerValue(name, static_cast<Index>(v));
      break;
    }
    case Ipopt::OT_Number: {
      const double v = std::strtod(value.c_str(), &end);
      if (value.empty() || *end != '\0') throw std::invalid_argument(where + ", expected a number");
      ok = reg->IsValidNumberSetting(v) && app.Options()->SetNumericValue(name, v);
      break;
    }
    default:
      ok = reg->IsValidStringSetting(value) && app.Options()->SetStringValue(name, value);
  }
  if (!ok) throw std::invalid_argument(where + ": value rejected by Ipopt (out of range or not a valid choice)");
}

const char* ipopt_status_name(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded: return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small: return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates: return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop: return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found: return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed: return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded: return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom: return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition: return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option: return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected: return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception: return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown: return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory: return "Insufficient_Memory";
    default: return "Internal_Error";
  }
}

TrajoptStatus map_status(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded: return TrajoptStatus::Solved;
    case Ipopt::Solved_To_Acceptable_Level: return TrajoptStatus::SolvedAcceptable;
    case Ipopt::Infeasible_Problem_Detected: return TrajoptStatus::Infeasible;
    case Ipopt::Maximum_Iterations_Exceeded:
    case Ipopt::Maximum_CpuTime_Exceeded: return TrajoptStatus::MaxIterations;
    default: return TrajoptStatus::Failed;
  }
}

std::string describe(Ipopt::ApplicationReturnStatus s, const std::string& error) {
  std::string msg = std::string("Ipopt ") + ipopt_status_name(s) + ": ";
  switch (map_status(s)) {
    case TrajoptStatus::Solved: msg += "optimal solution found"; break;
    case TrajoptStatus::SolvedAcceptable: msg += "solved to the acceptable tolerances only"; break;
    case TrajoptStatus::Infeasible:
      msg += "converged to a point of local infeasibility, the maneuver looks unreachable; not a solution";
      break;
    case TrajoptStatus::MaxIterations: msg += "iteration or time limit reached; not a solution"; break;
    case TrajoptStatus::Failed:
      msg += s == Ipopt::Invalid_Option
                 ? "an Ipopt option ([maneuver.ipopt]) names something this Ipopt build lacks; not a solution"
                 : "the solver stopped; not a solution";
      break;
  }
  if (!error.empty()) msg += " (evaluation error: " + error + ")";
  return msg;
}

}  // namespace

NlpSolve solve_nlp_ipopt(const CollocationNlp& nlp, const Eigen::VectorXd& w0, const TrajoptOptions& o, bool check_derivatives,
                   bool warm, const BoundMultipliers* z0) {
  // Quiet runs have no console journal rather than print_level 0, which would also
  // silence the journals that want the log (output_file, keep_log).
  // Every IpoptApplication made the usual way registers all of Ipopt's options anew (1.1 M
  // instructions, 1% of a small maneuver's whole run, twice with the coarse start): each
  // thread registers them once and gives every solve its own options list and journalist
  // (what the usual constructor makes; Ipopt's SmartPtr counts are not atomic, so the
  // registry is not shared between threads).
  thread_local Ipopt::SmartPtr<Ipopt::RegisteredOptions> registered;
  if (Ipopt::IsNull(registered)) {
    Ipopt::SmartPtr<Ipopt::RegisteredOptions> fresh = new Ipopt::RegisteredOptions();
    Ipopt::IpoptApplication::RegisterAllIpoptOptions(fresh);  // kept only once complete
    registered = fresh;
  }
  Ipopt::SmartPtr<Ipopt::Journalist> journalist = new Ipopt::Journalist();
  if (o.verbose) {
    Ipopt::SmartPtr<Ipopt::Journal> console = journalist->AddFileJournal("console", "stdout", Ipopt::J_ITERSUMMARY);
    console->SetPrintLevel(Ipopt::J_DBG, Ipopt::J_NONE);
  }
  Ipopt::SmartPtr<Ipopt::OptionsList> options = new Ipopt::OptionsList(registered, journalist);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = new Ipopt::IpoptApplication(registered, options, journalist);
  Ipopt::OptionsList& opts = *app->Options();
  opts.SetStringValue("sb", "yes");  // no banner
  opts.SetIntegerValue("print_level", 5);
  opts.SetNumericValue("tol", o.tol);
  opts.SetIntegerValue("max_iter", o.max_iter);
  opts.SetStringValue("hessian_approximation", "exact");
  opts.SetStringValue("nlp_scaling_method", "gradient-based");
  opts.SetStringValue("derivative_test", check_derivatives ? o.derivative_test : "none");
  opts.SetStringValue("derivative_test_print_all", "no");
  // MUMPS' own row/column scaling misjudges the KKT matrix as singular when boundary
  // conditions repeat what the dynamics already fix (e.g. R at rest at both ends when no
  // actuator can push o): Ipopt then fails in its first step. Without it the
  // regularization copes, and each factorization is ~15% cheaper. Ipopt's
  // gradient-based NLP scaling stays on.
  opts.SetIntegerValue("mumps_scaling", 0);
  // Ipopt's default asks MUMPS for 10x its workspace estimate, and every factorization
  // then pays for touching it (cost superlinear in N beyond ~400 intervals). Ipopt
  // raises the value itself if MUMPS runs short.
  opts.SetIntegerValue("mumps_mem_percent", 20);
  // Approximate minimum fill keeps the factorization linear in N on these block-banded
  // KKT systems; MUMPS' automatic choice switches to an ordering that is ~30% slower
  // above ~10k unknowns (N ~ 800).
  opts.SetIntegerValue("mumps_pivot_order", 2);
  if (o.linear_solver == LinearSolver::Ldlt) {
    // freeflex's LDLᵀ behind Ipopt's MA27 interface (trajopt/ma27_bridge.cpp)
    detail::register_sparse_ldlt();
    opts.SetStringValue("linear_solver", "ma27");
    opts.SetStringValue("linear_system_scaling", "none");
    // the analysis's storage estimate is exact but for delayed pivots: Ipopt's defaults
    // (5 times, and 10 times more when short) would reserve far more than is used
    opts.SetNumericValue("ma27_la_init_factor", 1.5);
    opts.SetNumericValue("ma27_liw_init_factor", 1.5);
    opts.SetNumericValue("ma27_meminc_factor", 2.0);
  } else {
    opts.SetStringValue("linear_solver", "mumps");
  }
  if (warm) opts.SetNumericValue("mu_init", 1e-6);  // start close to the central path of a near-optimal point
  // A solve carried on from another mesh starts from its bound multipliers too, through
  // Ipopt's warm-start initializer (which also raises them to at least 1e-3 and pushes the
  // point 1e-3 from its bounds; Ipopt's own start sets the multipliers to 1): one
  // iteration fewer on the shipped rigid maneuvers continued from their coarse start, 3-12
  // on the minimum-time slew with its end commands at zero (docs/benchmarks.md).
  if (warm && z0) opts.SetStringValue("warm_start_init_point", "yes");
  // The constraint multipliers start at zero instead of Ipopt's least-squares estimate,
  // which costs a factorization of a matrix of its own before the first iteration; with
  // zeros the maneuvers of bench_trajopt took the same iterations with the default LDLᵀ
  // (docs/benchmarks.md, "The whole `freeflex run` of the slew").
  opts.SetNumericValue("constr_mult_init_max", 0.0);
  for (const auto& kv : o.ipopt_options) set_user_option(*app, kv.first, kv.second);

  NlpSolve run;
  Ipopt::ApplicationReturnStatus status = Ipopt::Internal_Error;
  std::string error;
  const Ipopt::ApplicationReturnStatus init = app->Initialize("");  // "": no ipopt.opt from the working directory
  if (init != Ipopt::Solve_Succeeded) {
    run.status = map_status(init);
    run.message = describe(init, "Ipopt initialization failed");
    return run;
  }
  const bool derivative_check = check_derivatives && o.derivative_test != "none";
  if (o.keep_log || derivative_check) {
    // derivative_errors() reads the checker's verdict from this log, at print level 5 or more
    const int level = derivative_check ? std::max(o.log_level, int{Ipopt::J_ITERSUMMARY})
                                       : std::clamp(o.log_level, 0, int{Ipopt::J_ALL});
    Ipopt::SmartPtr<Ipopt::Journal> j = new StringJournal(static_cast<Ipopt::EJournalLevel>(level), &run.log);
    app->Jnlst()->AddJournal(j);
  }
  Ipopt::SmartPtr<CollocationTnlp> tnlp = new CollocationTnlp(nlp, w0, warm ? z0 : nullptr);
  try {
    status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(Ipopt::GetRawPtr(tnlp)));
  } catch (const std::exception& e) {  // Ipopt catches its own; this is a last resort
    status = Ipopt::NonIpopt_Exception_Thrown;
    error = e.what();
  }
  if (Ipopt::IsValid(app->Statistics())) run.iterations = app->Statistics()->IterationCount();
  if (tnlp->finalized) {
    run.w = tnlp->w_final;
    run.z = std::move(tnlp->z_final);
    run.objective = tnlp->obj_final;
  }
  if (error.empty()) error = tnlp->error;
  run.status = map_status(status);
  run.message = describe(status, error);
  return run;
}

}  // namespace freeflex::detail
