// [export]: the controller study's data for other tools (README, outputs): the TV-LQR
// gains and feedforward on their grid, the nominal motion and commands, the first-order
// model A(t), B(t), g(t) and the frozen-time poles on a model grid, and every comparison
// case's histories, as NAME.mat and/or NAME_*.csv.
//
// The model grid is cut into the pieces the closed loops integrate over (between the
// nominal motion's and the loads' breakpoints); each piece's samples are evaluated at
// Instant{t, piece midpoint} as the integrators do, so a breakpoint appears twice (the
// end of one piece and the start of the next) and a replay can integrate piece by piece
// from data alone. The gains are the law itself: K(t) and u_ff(t) are linear between
// their grid times (TvlqrResult::gain), so a replay that interpolates them linearly uses
// exactly the law of the closed loops.
#include <algorithm>
#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "app/study_files.hpp"
#include "io/mat_file.hpp"

namespace freeflex::detail {
namespace {

struct ModelGrid {
  std::vector<double> t, mid;
  std::vector<int> piece;       ///< 1-based
  std::vector<double> bounds;   ///< piece boundaries, ascending from 0 to the end
};

ModelGrid model_grid(const std::vector<double>& gain_t, double step, double end, std::vector<double> cuts) {
  std::vector<double> times = gain_t;
  const double tol = 1e-12 * std::max(1.0, end);
  for (long k = 0;; ++k) {
    const double t = static_cast<double>(k) * step;
    if (t > end - tol) break;
    times.push_back(t);
  }
  times.push_back(end);
  ModelGrid g;
  g.bounds = {0.0};
  std::sort(cuts.begin(), cuts.end());
  for (double c : cuts)
    if (c > tol && c < end - tol && c - g.bounds.back() > tol) g.bounds.push_back(c);
  g.bounds.push_back(end);
  times.insert(times.end(), g.bounds.begin(), g.bounds.end());
  std::sort(times.begin(), times.end());
  std::vector<double> merged;
  for (double t : times) {
    if (t < 0.0 || t > end) continue;
    if (!merged.empty() && t - merged.back() <= tol) continue;
    merged.push_back(t);
  }
  // snap onto the piece boundaries, so that every piece starts and ends at a sample
  std::size_t j = 0;
  for (std::size_t p = 0; p + 1 < g.bounds.size(); ++p) {
    const double a = g.bounds[p], b = g.bounds[p + 1], mid = 0.5 * (a + b);
    while (j < merged.size() && merged[j] < a - tol) ++j;
    std::size_t i = j;
    for (; i < merged.size() && merged[i] <= b + tol; ++i) {
      double t = merged[i];
      if (std::abs(t - a) <= tol) t = a;
      if (std::abs(t - b) <= tol) t = b;
      g.t.push_back(t);
      g.mid.push_back(mid);
      g.piece.push_back(static_cast<int>(p) + 1);
    }
    j = i == 0 ? 0 : i - 1;  // the end of this piece starts the next
  }
  return g;
}

/// Eigenvalues sorted by descending real part, then ascending imaginary part.
Eigen::VectorXcd sorted_eigenvalues(const Eigen::MatrixXd& M) {
  Eigen::VectorXcd e = Eigen::EigenSolver<Eigen::MatrixXd>(M, false).eigenvalues();
  std::vector<std::complex<double>> v(e.data(), e.data() + e.size());
  std::sort(v.begin(), v.end(), [](const std::complex<double>& a, const std::complex<double>& b) {
    return a.real() != b.real() ? a.real() > b.real() : a.imag() < b.imag();
  });
  return Eigen::Map<Eigen::VectorXcd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

std::vector<std::string> indexed(const std::string& stem, int n, int m = 0) {
  std::vector<std::string> h;
  for (int i = 1; i <= n; ++i) {
    if (m == 0) h.push_back(stem + "_" + std::to_string(i));
    else
      for (int j = 1; j <= m; ++j) h.push_back(stem + "_" + std::to_string(i) + "_" + std::to_string(j));
  }
  return h;
}

std::vector<std::string> operator+(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace

void write_export(const Design& design, const SuppressionStudyResult& r, RunOutput& out) {
  if (!design.exports || !design.controller) return;
  const ExportRequest& e = *design.exports;
  const ControllerStudy& st = *design.controller;
  const SuppressionResult& chain = r.chain;
  if (!chain.law.ok() || !chain.nominal) {
    out.warn("[export]: nothing exported, the TV-LQR was not designed (" +
             (chain.message.empty() ? std::string("no nominal motion") : chain.message) + ")");
    return;
  }
  const TvlqrResult& law = chain.law;
  const FlexibleBody body = design.body();  // the law's: the design's basis and stiffening
  const Excitation loads = design.excitation();
  const FirstOrderModel fo(body, *chain.nominal, nominal_element_commands(loads, st.actuators, chain.u0), st.actuators);
  const int N = body.dofs(), n = 2 * N, m = fo.input_size();
  const std::vector<ForceElement> elements = design.force_elements();

  // the model grid
  const double end = std::max(st.horizon_s, st.simulate_until_s);
  std::vector<double> cuts = chain.nominal->breakpoints();
  for (double b : loads.breakpoints()) cuts.push_back(b);
  const ModelGrid grid = model_grid(law.t, e.model_step_s > 0.0 ? e.model_step_s : st.grid_step_s, end, cuts);
  const int T = static_cast<int>(grid.t.size());
  Eigen::MatrixXd x0(T, n), u0(T, m), g(T, n), poles_head(T, 3);
  std::vector<double> A(static_cast<std::size_t>(n) * n * T), B(static_cast<std::size_t>(n) * m * T);
  Eigen::MatrixXcd poles_open(T, n), poles_closed(T, n);
  FirstOrderModel::Data data = fo.create_data();
  Eigen::VectorXd u(m);
  for (int i = 0; i < T; ++i) {
    const Instant at{grid.t[static_cast<std::size_t>(i)], grid.mid[static_cast<std::size_t>(i)]};
    const RigidState s = chain.nominal->at(at);
    x0.row(i).setZero();
    x0.row(i).head<3>() = s.pos.transpose();
    x0.row(i).segment<3>(N) = s.vel.transpose();
    u.setZero();
    chain.u0(at, u);
    u0.row(i) = u.transpose();
    if (!e.model && !e.poles) continue;
    const StateSpace& ss = fo.state_space(data, at);
    std::copy(ss.A.data(), ss.A.data() + ss.A.size(), A.begin() + static_cast<std::ptrdiff_t>(i) * n * n);
    std::copy(ss.B.data(), ss.B.data() + ss.B.size(), B.begin() + static_cast<std::ptrdiff_t>(i) * n * m);
    g.row(i) = ss.g.transpose();
    if (e.poles) {
      poles_open.row(i) = sorted_eigenvalues(ss.A).transpose();
      poles_closed.row(i) = sorted_eigenvalues(ss.A - ss.B * law.gain(at.t)).transpose();
    }
  }
  const int G = static_cast<int>(law.t.size());
  std::vector<double> K(static_cast<std::size_t>(m) * n * G);
  for (int i = 0; i < G; ++i)
    std::copy(law.K[static_cast<std::size_t>(i)].data(), law.K[static_cast<std::size_t>(i)].data() + m * n,
              K.begin() + static_cast<std::ptrdiff_t>(i) * m * n);
  Eigen::Map<const Eigen::VectorXd> tg(law.t.data(), G);
  Eigen::VectorXd tm = Eigen::Map<const Eigen::VectorXd>(grid.t.data(), T);
  Eigen::VectorXd mid = Eigen::Map<const Eigen::VectorXd>(grid.mid.data(), T);
  Eigen::VectorXd piece(T);
  for (int i = 0; i < T; ++i) piece(i) = grid.piece[static_cast<std::size_t>(i)];
  Eigen::VectorXd bounds = Eigen::Map<const Eigen::VectorXd>(grid.bounds.data(), static_cast<Eigen::Index>(grid.bounds.size()));

  // the histories: states, their perturbation from the nominal, every element's command
  struct History {
    std::string name;
    Eigen::MatrixXd x1;
  };
  std::vector<History> hist;
  for (const auto& c : r.cases) {
    Eigen::MatrixXd x1(c.t.size(), n);
    for (Eigen::Index i = 0; i < c.t.size(); ++i) {
      const RigidState s = chain.nominal->at(Instant::at(c.t(i)));
      x1.row(i).head(N) = c.z.row(i);
      x1.row(i).tail(N) = c.z_dot.row(i);
      x1.row(i).head<3>() -= s.pos.transpose();
      x1.row(i).segment<3>(N) -= s.vel.transpose();
    }
    hist.push_back({c.name + "_" + c.model, x1});
  }

  const std::vector<std::string> zn = {"Rx_m", "Ry_m", "theta_rad"};
  std::vector<std::string> state_names = zn, rate_names = {"Rx_dot_m_s", "Ry_dot_m_s", "theta_dot_rad_s"};
  for (int j = 1; j <= N - 3; ++j) {
    state_names.push_back("q_" + std::to_string(j));
    rate_names.push_back("q_dot_" + std::to_string(j));
  }
  if (e.csv) {
    const std::string stem = e.name + "_";
    if (e.gains) {
      Eigen::MatrixXd d(G, 1 + m * n + m);
      d.col(0) = tg;
      for (int i = 0; i < G; ++i) {
        const Eigen::MatrixXd& k = law.K[static_cast<std::size_t>(i)];
        for (int a = 0; a < m; ++a)
          for (int b = 0; b < n; ++b) d(i, 1 + a * n + b) = k(a, b);
      }
      d.rightCols(m) = law.feedforward;
      out.csv(stem + "gains.csv", std::vector<std::string>{"t_s"} + indexed("K", m, n) + indexed("u_ff", m), d);
    }
    if (e.nominal) {
      Eigen::MatrixXd d(T, 3 + n + m);
      d << piece, tm, mid, x0, u0;
      std::vector<std::string> h = {"piece", "t_s", "piece_mid_s"};
      for (const auto& s : state_names) h.push_back("x0_" + s);
      for (const auto& s : rate_names) h.push_back("x0_" + s);
      out.csv(stem + "nominal.csv", h + indexed("u0", m), d);
    }
    if (e.model) {
      Eigen::MatrixXd d(T, 3 + n * n + n * m + n);
      d.leftCols(3) << piece, tm, mid;
      for (int i = 0; i < T; ++i) {
        const std::size_t i0 = static_cast<std::size_t>(i);
        for (int a = 0; a < n; ++a) {
          for (int b = 0; b < n; ++b) d(i, 3 + a * n + b) = A[i0 * n * n + static_cast<std::size_t>(b * n + a)];
          for (int b = 0; b < m; ++b) d(i, 3 + n * n + a * m + b) = B[i0 * n * m + static_cast<std::size_t>(b * n + a)];
        }
      }
      d.rightCols(n) = g;
      out.csv(stem + "model.csv",
              std::vector<std::string>{"piece", "t_s", "piece_mid_s"} + indexed("A", n, n) + indexed("B", n, m) +
                  indexed("g", n),
              d);
    }
    if (e.poles) {
      Eigen::MatrixXd d(T, 2 + 4 * n);
      d.col(0) = piece;
      d.col(1) = tm;
      for (int j = 0; j < n; ++j) {
        d.col(2 + 2 * j) = poles_open.col(j).real();
        d.col(3 + 2 * j) = poles_open.col(j).imag();
        d.col(2 + 2 * n + 2 * j) = poles_closed.col(j).real();
        d.col(3 + 2 * n + 2 * j) = poles_closed.col(j).imag();
      }
      std::vector<std::string> h = {"piece", "t_s"};
      for (const char* w : {"open", "closed"})
        for (int j = 1; j <= n; ++j) {
          h.push_back(std::string(w) + "_re_" + std::to_string(j) + "_1_s");
          h.push_back(std::string(w) + "_im_" + std::to_string(j) + "_1_s");
        }
      out.csv(stem + "poles.csv", h, d);
    }
    if (e.histories)
      for (std::size_t k = 0; k < r.cases.size(); ++k) {
        const auto& c = r.cases[k];
        const int ne = static_cast<int>(c.commands.cols());
        Eigen::MatrixXd d(c.t.size(), 1 + 2 * N + n + ne);
        d << c.t, c.z, c.z_dot, hist[k].x1, c.commands;
        std::vector<std::string> h = {"t_s"};
        h = h + state_names + rate_names;
        for (const auto& s : state_names) h.push_back("x1_" + s);
        for (const auto& s : rate_names) h.push_back("x1_" + s);
        for (int j = 0; j < ne; ++j) h.push_back("u_" + elements[static_cast<std::size_t>(j)].name);
        out.csv(stem + "history_" + hist[k].name + ".csv", h, d);
      }
  }
  if (e.mat) {
    out.file(e.name + ".mat", [&](const std::string& path) {
      io_detail::MatFile f(path);
      f.add("title", design.title);
      Eigen::VectorXd act(m), lim = st.limits;
      for (int k = 0; k < m; ++k) act(k) = st.actuators[static_cast<std::size_t>(k)];
      f.add("actuator_elements", Eigen::MatrixXd(act));
      f.add("limits", Eigen::MatrixXd(lim));
      f.add("horizon_s", Eigen::MatrixXd(Eigen::MatrixXd::Constant(1, 1, st.horizon_s)));
      f.add("until_s", Eigen::MatrixXd(Eigen::MatrixXd::Constant(1, 1, st.simulate_until_s)));
      f.add("piece_bounds_s", Eigen::MatrixXd(bounds));
      if (e.gains) {
        f.add("t_gain", Eigen::MatrixXd(tg));
        f.add("K", {static_cast<std::size_t>(m), static_cast<std::size_t>(n), static_cast<std::size_t>(G)}, K);
        f.add("u_ff", law.feedforward);
        f.add("Qf", law.Qf);
      }
      if (e.nominal || e.model || e.poles) {
        f.add("t_model", Eigen::MatrixXd(tm));
        f.add("piece", Eigen::MatrixXd(piece));
        f.add("piece_mid_s", Eigen::MatrixXd(mid));
      }
      if (e.nominal) {
        f.add("x0", x0);
        f.add("u0", u0);
      }
      if (e.model) {
        f.add("A", {static_cast<std::size_t>(n), static_cast<std::size_t>(n), static_cast<std::size_t>(T)}, A);
        f.add("B", {static_cast<std::size_t>(n), static_cast<std::size_t>(m), static_cast<std::size_t>(T)}, B);
        f.add("g", g);
      }
      if (e.poles) {
        f.add("poles_open", poles_open);
        f.add("poles_closed", poles_closed);
      }
      if (e.histories)
        for (std::size_t k = 0; k < r.cases.size(); ++k) {
          const auto& c = r.cases[k];
          const std::string p = hist[k].name + "_";
          f.add(p + "t", Eigen::MatrixXd(c.t));
          f.add(p + "z", c.z);
          f.add(p + "z_dot", c.z_dot);
          f.add(p + "x1", hist[k].x1);
          f.add(p + "u", c.commands);
        }
      f.close();
    });
  }
}

}  // namespace freeflex::detail
