// The paper's admissible functions: cantilever roots and modes evaluated without
// cancellation, and the basis on both halves of the beam.
#include "freeflex/model/basis.hpp"

#include <cmath>
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
  const int cantilevers = one_sided() ? n : (n + 1) / 2;
  for (int k = 1; k <= cantilevers; ++k) modes_.emplace_back(k);
}

double AdmissibleBasis::max_wavenumber() const {
  if (one_sided()) return modes_.back().lambda / std::max(a_left_, a_right_);
  return modes_.back().lambda / std::min(a_left_, a_right_);
}

BasisValues AdmissibleBasis::evaluate(double x) const {
  BasisValues v{Eigen::RowVectorXd(n_), Eigen::RowVectorXd(n_), Eigen::RowVectorXd(n_)};
  const bool right = x >= 0.0;
  const double a = right ? a_right_ : a_left_;
  const double sgn = right ? 1.0 : -1.0;
  const double xi = std::abs(x);
  if (one_sided()) {
    // o at an end: function j is the (j+1)-th cantilever mode of the one half there is;
    // the other side has no beam (zero there, as at o).
    if (a == 0.0) {
      v.phi.setZero();
      v.dphi.setZero();
      v.ddphi.setZero();
      return v;
    }
    for (int j = 0; j < n_; ++j) {
      const CantileverConstants& mode = modes_[j];
      const double beta = mode.lambda / a;
      const CantileverMode p = mode.at(beta * xi);
      v.phi(j) = p.value;
      v.dphi(j) = sgn * beta * p.d1;
      v.ddphi(j) = beta * beta * p.d2;
    }
    return v;
  }
  for (int j = 0; j < n_; ++j) {
    const CantileverConstants& mode = modes_[j / 2];
    const double beta = mode.lambda / a;
    const CantileverMode p = mode.at(beta * xi);
    // d/dx psi(beta |x|) = sign(x) beta psi'; the antisymmetric ones carry one more sign(x).
    if (j % 2 == 0) {
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
