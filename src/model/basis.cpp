// The paper's admissible functions: cantilever roots and modes evaluated without
// cancellation, and the basis on both halves of the beam.
#include "freeflex/model/basis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace freeflex {

double cantilever_root(int k) {
  if (k < 1) throw std::invalid_argument("cantilever_root: k must be >= 1");
  // f(l) = cos l + 1/cosh l has the same roots and stays O(1); start from the
  // asymptote (2k-1) pi/2, which is within 0.3 even for k = 1.
  double l = (2.0 * k - 1.0) * M_PI / 2.0;
  for (int it = 0; it < 50; ++it) {
    const double f = std::cos(l) + 1.0 / std::cosh(l);
    const double df = -std::sin(l) - std::tanh(l) / std::cosh(l);
    const double dl = f / df;
    l -= dl;
    if (std::abs(dl) < 1e-15 * l) break;
  }
  return l;
}

CantileverConstants::CantileverConstants(int k) : lambda(cantilever_root(k)) {
  // sigma = (sinh l - sin l)/(cosh l + cos l). Scaling by e^-l keeps every term O(1):
  // D = (cosh l + cos l) e^-l, and 1 - sigma = (e^-l + cos l + sin l)/(cosh l + cos l)
  // has no cancellation, so growth = (1 - sigma) e^l = (e^-l + cos l + sin l) / D.
  const double em = std::exp(-lambda);
  const double D = 0.5 * (1.0 + em * em) + std::cos(lambda) * em;
  sigma = (0.5 * (1.0 - em * em) - std::sin(lambda) * em) / D;
  growth = (em + std::cos(lambda) + std::sin(lambda)) / D;
}

CantileverMode CantileverConstants::at(double z) const {
  // cosh z - sigma sinh z = [(1 - sigma) e^z + (1 + sigma) e^-z] / 2
  const double a = growth * std::exp(z - lambda);  // (1 - sigma) e^z
  const double b = (1.0 + sigma) * std::exp(-z);
  const double ch_sh = 0.5 * (a + b);  // cosh z - sigma sinh z
  const double sh_ch = 0.5 * (a - b);  // sinh z - sigma cosh z
  const double c = std::cos(z), s = std::sin(z);
  return {ch_sh - c + sigma * s, sh_ch + s + sigma * c, ch_sh + c - sigma * s};
}

CantileverMode cantilever_mode(int k, double z) { return CantileverConstants(k).at(z); }

AdmissibleBasis::AdmissibleBasis(int n, double a_left, double a_right)
    : n_(n), a_left_(a_left), a_right_(a_right) {
  if (n < 1 || n > kMaxNoa) {
    std::ostringstream os;
    os << "admissible basis: noa = " << n << ", must be in [1, " << kMaxNoa << "]";
    throw std::invalid_argument(os.str());
  }
  if (!(a_left >= 0.0) || !(a_right >= 0.0) || !std::isfinite(a_left) || !std::isfinite(a_right) ||
      !(a_left + a_right > 0.0))
    throw std::invalid_argument("admissible basis: half-lengths must be finite and >= 0, and not both zero");
  symmetric_ = std::abs(a_left - a_right) <= 1e-12 * (a_left + a_right);
  if (symmetric_) {
    for (int k = 1; k <= (n + 1) / 2; ++k) modes_.emplace_back(k);
    for (int j = 0; j < n; ++j) functions_.push_back({j % 2 == 0 ? Shape::Symmetric : Shape::Antisymmetric, j / 2});
    return;
  }
  // eq. 2.4: merge the two sides' sequences by wavenumber lambda_k / a (ties: the longer side first).
  // o at an end (one side of zero length, a cantilever clamped at o): that side's wavenumber
  // is infinite, so every function is the other side's, its cantilever modes in order.
  const bool left_longer = a_left > a_right;
  int kl = 0, kr = 0;
  while (static_cast<int>(functions_.size()) < n) {
    const int k = std::max(kl, kr);
    while (static_cast<int>(modes_.size()) <= k) modes_.emplace_back(static_cast<int>(modes_.size()) + 1);
    const double inf = std::numeric_limits<double>::infinity();
    const double wl = a_left > 0.0 ? modes_[kl].lambda / a_left : inf;
    const double wr = a_right > 0.0 ? modes_[kr].lambda / a_right : inf;
    if (wl < wr || (wl == wr && left_longer)) functions_.push_back({Shape::Left, kl++});
    else functions_.push_back({Shape::Right, kr++});
  }
}

double AdmissibleBasis::max_wavenumber() const {
  if (symmetric_) return modes_.back().lambda / std::min(a_left_, a_right_);
  double w = 0.0;
  for (const Function& f : functions_)
    w = std::max(w, modes_[f.k].lambda / (f.shape == Shape::Left ? a_left_ : a_right_));
  return w;
}

int AdmissibleBasis::functions_left() const {
  int c = 0;
  for (const Function& f : functions_) c += f.shape != Shape::Right;
  return c;
}

int AdmissibleBasis::functions_right() const {
  int c = 0;
  for (const Function& f : functions_) c += f.shape != Shape::Left;
  return c;
}

BasisValues AdmissibleBasis::evaluate(double x) const {
  BasisValues v{Eigen::RowVectorXd(n_), Eigen::RowVectorXd(n_), Eigen::RowVectorXd(n_)};
  const bool right = x >= 0.0;
  const double a = right ? a_right_ : a_left_;
  const double sgn = right ? 1.0 : -1.0;
  const double xi = std::abs(x);
  for (int j = 0; j < n_; ++j) {
    const Function& f = functions_[j];
    if ((f.shape == Shape::Left && right) || (f.shape == Shape::Right && !right)) {
      v.phi(j) = v.dphi(j) = v.ddphi(j) = 0.0;  // a one-sided function on its other side
      continue;
    }
    const CantileverConstants& mode = modes_[f.k];
    const double beta = mode.lambda / a;
    const CantileverMode p = mode.at(beta * xi);
    // d/dx psi(beta |x|) = sign(x) beta psi'; the antisymmetric ones carry one more sign(x).
    if (f.shape != Shape::Antisymmetric) {
      v.phi(j) = p.value;
      v.dphi(j) = sgn * beta * p.d1;
      v.ddphi(j) = beta * beta * p.d2;
    } else {
      v.phi(j) = sgn * p.value;
      v.dphi(j) = beta * p.d1;
      v.ddphi(j) = sgn * beta * beta * p.d2;
    }
  }
  return v;
}

}  // namespace freeflex
