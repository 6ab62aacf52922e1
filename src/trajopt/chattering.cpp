// Chattering of an optimized control (trajopt/chattering.hpp): sign alternations of the
// control's differences over the solution's points, and the remedies to suggest.
#include "freeflex/trajopt/chattering.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "freeflex/trajopt/solve.hpp"

namespace freeflex {

void validate(const ChatteringOptions& o) {
  if (o.min_run < 2)
    throw std::invalid_argument("chattering options: min_run = " + std::to_string(o.min_run) + ", expected >= 2");
  if (!(o.threshold > 0.0) || !std::isfinite(o.threshold))
    throw std::invalid_argument("chattering options: threshold = " + std::to_string(o.threshold) +
                                ", expected a finite value > 0");
}

ChatteringReport detect_chattering(const TrajoptResult& r, const ManeuverProblem& p, const ChatteringOptions& o) {
  validate(o);
  const int nu = static_cast<int>(r.u.cols());
  if (nu != static_cast<int>(p.actuators.size()) || r.t.size() < 2)
    throw std::invalid_argument("detect_chattering: the result holds no solution of this problem");
  // The points in time order: knots, and midpoints between them.
  std::vector<std::pair<double, Eigen::VectorXd>> pts;
  for (int k = 0; k < r.t.size(); ++k) {
    pts.emplace_back(r.t(k), r.u.row(k).transpose());
    if (k < r.t_mid.size()) pts.emplace_back(r.t_mid(k), r.u_mid.row(k).transpose());
  }
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  ChatteringReport rep;
  rep.longest_run.assign(nu, 0);
  rep.run_begin_s.assign(nu, 0.0);
  rep.run_end_s.assign(nu, 0.0);
  rep.suggested_rate_limit.resize(nu);
  std::ostringstream msg;
  const int P = static_cast<int>(pts.size());
  for (int a = 0; a < nu; ++a) {
    double range = p.u_max(a) - p.u_min(a);
    if (!std::isfinite(range)) {
      range = 0.0;
      for (const auto& pt : pts) range = std::max(range, 2.0 * std::abs(pt.second(a)));
    }
    const double tol = o.threshold * range;
    int run = 0, best = 0, best_end = 0;
    for (int i = 1; i + 1 < P; ++i) {
      const double d0 = pts[i].second(a) - pts[i - 1].second(a), d1 = pts[i + 1].second(a) - pts[i].second(a);
      const bool alt = std::abs(d0) > tol && std::abs(d1) > tol && d0 * d1 < 0.0;
      run = alt ? run + 1 : 0;
      if (run > best) best = run, best_end = i;
    }
    rep.longest_run[a] = best;
    if (best > 0) {
      rep.run_begin_s[a] = pts[best_end - best].first;
      rep.run_end_s[a] = pts[best_end + 1].first;
    }
    rep.suggested_rate_limit(a) = range > 0.0 ? 20.0 * range / r.duration_s : ManeuverProblem::inf;
    if (best >= o.min_run) {
      rep.flagged = true;
      rep.actuators.push_back(a);
      msg << (rep.actuators.size() > 1 ? "; " : "") << "actuator " << a << " alternates at " << best
          << " consecutive points over t = " << rep.run_begin_s[a] << " .. " << rep.run_end_s[a] << " s";
    }
  }
  if (!rep.flagged) {
    const int worst = nu ? *std::max_element(rep.longest_run.begin(), rep.longest_run.end()) : 0;
    rep.message = "no chattering (longest alternation run " + std::to_string(worst) + ", flagged at " +
                  std::to_string(o.min_run) + ")";
    return rep;
  }
  rep.message = "chattering, a singular arc the transcription resolves badly: " + msg.str();
  // w_smooth ∫u'² for one full-range change per T/10 on every actuator: ∫u'² = 10·range²·10/T;
  // at 2% of the objective (or of T when the objective is 0): 0.1% left the slew chattering.
  double sum = 0.0;
  for (int a = 0; a < nu; ++a) {
    const double range = std::isfinite(rep.suggested_rate_limit(a)) ? rep.suggested_rate_limit(a) * r.duration_s / 20.0 : 1.0;
    sum += 100.0 * range * range / r.duration_s;
  }
  const double scale = std::abs(r.objective) > 0.0 ? std::abs(r.objective) : r.duration_s;
  rep.suggested_smooth_weight = 0.02 * scale / sum;
  std::ostringstream rem;
  rem << "add a smoothness weight (objective = \"weighted\", smooth_weight = " << rep.suggested_smooth_weight
      << "); rate limits (rate_limits = [";
  for (int a = 0; a < nu; ++a) rem << (a ? ", " : "") << rep.suggested_rate_limit(a);
  rem << "] per second) bound the chatter's amplitude but need not remove it";
  rep.remedy = rem.str();
  return rep;
}

}  // namespace freeflex
