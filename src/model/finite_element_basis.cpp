// The finite-element basis: mesh, element matrices, the free-free (or clamped-at-o)
// eigenproblem by shift-inverted subspace iteration, and the kept modes (free-free ones
// with their rigid part removed).
#include "freeflex/model/finite_element_basis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Sparse>

#include "freeflex/model/quadrature.hpp"
#include "model/beam_element.hpp"

namespace freeflex {
namespace {

using SpMat = Eigen::SparseMatrix<double>;

/// Nodes: the key points (ends and o, then segment junctions, then point masses), each
/// interval between them cut into equal elements, the elements handed out one at a time to
/// the interval whose elements are currently longest (ties: the leftmost), so that the
/// longest element is as short as the count allows. A key point closer than a thousandth
/// of the mean element length to one of higher rank is not a node: an element that short
/// would be ~1e9 times stiffer than the others, and the factored shifted stiffness would
/// lose as many digits. A point mass is then lumped on the nearby node (the modal
/// integrals keep it at its own position; the basis error this costs enters the
/// frequencies squared: measured 1e-11 relative at 2.5e-5 L); a junction falls inside an
/// element, whose integrals are split there.
std::vector<double> make_nodes(const Beam& beam, int elements) {
  const double L = beam.length(), tol = 1e-3 * L / elements;
  std::vector<double> ranked{beam.x_left(), beam.x_right(), 0.0};
  const std::vector<double> junctions = beam.breakpoints_x();
  ranked.insert(ranked.end(), junctions.begin() + 1, junctions.end() - 1);
  for (const auto& pm : beam.properties().point_masses) ranked.push_back(beam.x_of(pm.position_m));
  std::vector<double> k;
  for (std::size_t i = 0; i < ranked.size(); ++i) {
    const double x = ranked[i];
    // the ends and o are always nodes; every other key only away from the nodes so far
    const bool near = std::any_of(k.begin(), k.end(), [&](double y) { return std::abs(x - y) < tol; });
    if (i < 3 ? std::find(k.begin(), k.end(), x) == k.end() : !near) k.push_back(x);
  }
  std::sort(k.begin(), k.end());
  const int intervals = static_cast<int>(k.size()) - 1;
  std::vector<int> count(intervals, 1);
  for (int e = intervals; e < elements; ++e) {
    int widest = 0;
    for (int i = 1; i < intervals; ++i)
      if ((k[i + 1] - k[i]) / count[i] > (k[widest + 1] - k[widest]) / count[widest]) widest = i;
    ++count[widest];
  }
  std::vector<double> nodes{k.front()};
  for (int i = 0; i < intervals; ++i) {
    for (int j = 1; j < count[i]; ++j) nodes.push_back(k[i] + (k[i + 1] - k[i]) * j / count[i]);
    nodes.push_back(k[i + 1]);
  }
  return nodes;
}

/// Index of the node nearest to x.
int nearest_node(const std::vector<double>& nodes, double x) {
  const auto it = std::lower_bound(nodes.begin(), nodes.end(), x);
  if (it == nodes.end()) return static_cast<int>(nodes.size()) - 1;
  if (it == nodes.begin()) return 0;
  return (x - *(it - 1) <= *it - x) ? static_cast<int>(it - nodes.begin()) - 1 : static_cast<int>(it - nodes.begin());
}

/// Global DOF of local DOF j of element e: nodes carry (w, w') at 2i, 2i+1; the bubbles of
/// element e follow all nodes, at 2 (N+1) + 2e, +1.
int global_dof(int e, int j, int elements) { return j < 4 ? 2 * e + j : 2 * (elements + 1) + 2 * e + (j - 4); }

/// The element model. Its stiffness is kept in factored form K = Gᵀ D G, G the curvature
/// of every DOF at each element's Gauss points and D the weights EI(x) w: a projection
/// (GY)ᵀ D (GY) then sees curvatures computed from nodal values (losing ~log10(N) digits)
/// instead of the cancellation in K Y of terms EI/h³ (losing ~log10(N^4)).
struct Assembly {
  SpMat K, M, G;
  Eigen::VectorXd D;
  double mass = 0.0;
};

Assembly assemble(const Beam& beam, const std::vector<double>& nodes, int order, int dofs) {
  const int elements = static_cast<int>(nodes.size()) - 1, per = order == 5 ? 6 : 4;
  // 8-point Gauss is exact to degree 15: the mass integrand (quintic x quintic x linear) is 11.
  const GaussRule gm = gauss_legendre(8);
  // 4-point Gauss is exact to degree 7: the stiffness integrand (cubic x cubic x linear).
  const GaussRule gk = gauss_legendre(4);
  const int nk = static_cast<int>(gk.nodes.size());
  const std::vector<double> junctions = beam.breakpoints_x();
  std::vector<Eigen::Triplet<double>> gt, mt;
  gt.reserve(static_cast<std::size_t>(elements) * nk * per);
  mt.reserve(static_cast<std::size_t>(elements) * per * per + 8);
  Assembly r;
  r.D.resize(static_cast<Eigen::Index>(elements + junctions.size()) * nk);
  int rows = 0;
  for (int e = 0; e < elements; ++e) {
    const double a = nodes[e], b = nodes[e + 1], h = b - a;
    // the element's pieces between the junctions inside it (usually none): m and EI are
    // linear on each piece, so each piece's Gauss rule is exact
    std::vector<double> cuts{a};
    for (double x : junctions)
      if (x > a && x < b) cuts.push_back(x);
    cuts.push_back(b);
    Eigen::MatrixXd me = Eigen::MatrixXd::Zero(per, per);
    for (std::size_t piece = 0; piece + 1 < cuts.size(); ++piece) {
      const double pa = cuts[piece], pb = cuts[piece + 1], ph = pb - pa;
      for (int i = 0; i < gm.nodes.size(); ++i) {
        const double x = 0.5 * (pa + pb) + 0.5 * ph * gm.nodes(i), w = 0.5 * ph * gm.weights(i);
        const element::Shape s = element::shape((2.0 * x - a - b) / h, h, per);
        me.noalias() += (w * beam.mass_per_length(x)) * s.N.transpose() * s.N;
      }
      for (int i = 0; i < nk; ++i, ++rows) {
        const double x = 0.5 * (pa + pb) + 0.5 * ph * gk.nodes(i), w = 0.5 * ph * gk.weights(i);
        const element::Shape s = element::shape((2.0 * x - a - b) / h, h, per);
        r.D(rows) = w * beam.bending_stiffness(x);
        for (int c = 0; c < per; ++c) gt.emplace_back(rows, global_dof(e, c, elements), s.N2(c));
      }
    }
    for (int i = 0; i < per; ++i)
      for (int c = 0; c < per; ++c) mt.emplace_back(global_dof(e, i, elements), global_dof(e, c, elements), me(i, c));
  }
  const auto& p = beam.properties();
  for (const auto& pm : p.point_masses) {
    const int i = nearest_node(nodes, beam.x_of(pm.position_m));
    mt.emplace_back(2 * i, 2 * i, pm.mass_kg);
  }
  const int io = nearest_node(nodes, 0.0);
  mt.emplace_back(2 * io, 2 * io, p.hub_mass_kg);
  mt.emplace_back(2 * io + 1, 2 * io + 1, p.hub_rotary_inertia_kgm2);
  r.D.conservativeResize(rows);
  r.G.resize(rows, dofs);
  r.G.setFromTriplets(gt.begin(), gt.end());
  r.M.resize(dofs, dofs);
  r.M.setFromTriplets(mt.begin(), mt.end());
  r.K = SpMat(r.G.transpose() * r.D.asDiagonal() * r.G);
  // total mass: the rigid translation (w = 1 at every node, no slope, no bubbles) in M
  Eigen::VectorXd one = Eigen::VectorXd::Zero(dofs);
  for (int i = 0; i <= elements; ++i) one(2 * i) = 1.0;
  r.mass = one.dot(r.M * one);
  return r;
}

/// Global DOFs on each side of node io, which is held (w = w' = 0): nodes below io with the
/// bubbles of the elements left of it, and nodes above io with the bubbles right of it.
std::pair<std::vector<int>, std::vector<int>> side_dofs(int io, int elements, bool bubbles) {
  std::vector<int> left, right;
  for (int i = 0; i <= elements; ++i) {
    if (i == io) continue;
    auto& side = i < io ? left : right;
    side.push_back(2 * i);
    side.push_back(2 * i + 1);
  }
  if (bubbles)
    for (int e = 0; e < elements; ++e)
      for (int j = 4; j < 6; ++j) (e < io ? left : right).push_back(global_dof(e, j, elements));
  return {left, right};
}

/// A deterministic start vector entry in [-1, 1] (no <random>: its distributions differ
/// between standard libraries).
double start_entry(int i, int j) {
  const double v = std::sin(12.9898 * (i + 1) + 78.233 * (j + 1)) * 43758.5453;
  return 2.0 * (v - std::floor(v)) - 1.0;
}

struct Eigenpairs {
  Eigen::VectorXd lambda;  // ascending, the q lowest
  Eigen::MatrixXd vectors; // M-orthonormal
  int iterations = 0;
};

/// The element model restricted to some of its DOFs (the others held at zero): columns of
/// G and rows and columns of M; rows of G (curvature samples) with nothing left are dropped.
Assembly restrict_to(const Assembly& fe, const std::vector<int>& keep) {
  std::vector<Eigen::Triplet<double>> pt;
  for (std::size_t j = 0; j < keep.size(); ++j) pt.emplace_back(keep[j], static_cast<int>(j), 1.0);
  SpMat P(fe.M.rows(), static_cast<Eigen::Index>(keep.size()));
  P.setFromTriplets(pt.begin(), pt.end());
  const SpMat G = fe.G * P;
  std::vector<char> used(static_cast<std::size_t>(G.rows()), 0);
  for (int c = 0; c < G.outerSize(); ++c)
    for (SpMat::InnerIterator it(G, c); it; ++it) used[static_cast<std::size_t>(it.row())] = 1;
  std::vector<Eigen::Triplet<double>> rt;
  Assembly r;
  r.D.resize(G.rows());
  int rows = 0;
  for (int i = 0; i < G.rows(); ++i)
    if (used[static_cast<std::size_t>(i)]) {
      rt.emplace_back(rows, i, 1.0);
      r.D(rows++) = fe.D(i);
    }
  r.D.conservativeResize(rows);
  SpMat R(rows, G.rows());
  R.setFromTriplets(rt.begin(), rt.end());
  r.G = R * G;
  r.M = SpMat(P.transpose() * fe.M * P);
  r.K = SpMat(r.G.transpose() * r.D.asDiagonal() * r.G);
  r.mass = fe.mass;
  return r;
}

/// The q lowest eigenpairs of K v = lambda M v by subspace iteration on the shifted
/// pencil (K + sigma M)^-1 M with a Rayleigh-Ritz step on the iterate Y every time. The
/// projected stiffness is (GY)ᵀ D (GY), so the Ritz values are true Rayleigh quotients:
/// errors of the solve move them only to second order, and they fall monotonically as the
/// span converges.
/// `rigid`: how many of the q are rigid modes (zero eigenvalues, left out of the convergence
/// test): 2 free-free, 0 clamped.
Eigenpairs lowest_eigenpairs(const Assembly& fe, int q, double sigma, int rigid) {
  const SpMat& M = fe.M;
  const int n = static_cast<int>(M.rows());
  const int p = std::min(n, std::max(2 * q, q + 8));
  const SpMat A = fe.K + sigma * M;
  Eigen::SimplicialLDLT<SpMat> ldlt(A);
  if (ldlt.info() != Eigen::Success)
    throw std::runtime_error("finite-element basis: the shifted stiffness could not be factored");
  Eigen::MatrixXd X(n, p);
  for (int j = 0; j < p; ++j)
    for (int i = 0; i < n; ++i) X(i, j) = start_entry(i, j);
  Eigen::VectorXd previous = Eigen::VectorXd::Constant(q, std::numeric_limits<double>::infinity());
  constexpr int kMaxIterations = 1000;
  double last_change = std::numeric_limits<double>::infinity();
  int stalled = 0;
  for (int it = 1; it <= kMaxIterations; ++it) {
    Eigen::MatrixXd Y = ldlt.solve(M * X);
    // M-orthonormal columns by modified Gram-Schmidt, twice ("twice is enough"): the solve
    // scales mode j by 1/(lambda_j + sigma), so from a random start the columns are nearly
    // parallel and Yᵀ M Y far too ill-conditioned for a Cholesky factor.
    Eigen::MatrixXd MY = M * Y;
    for (int j = 0; j < p; ++j) {
      for (int pass = 0; pass < 2; ++pass)
        for (int i = 0; i < j; ++i) {
          const double c = Y.col(i).dot(MY.col(j));
          Y.col(j) -= c * Y.col(i);
          MY.col(j) -= c * MY.col(i);
        }
      const double norm = std::sqrt(Y.col(j).dot(MY.col(j)));
      if (!(norm > 0.0)) throw std::runtime_error("finite-element basis: the subspace lost its rank");
      Y.col(j) /= norm;
      MY.col(j) /= norm;
    }
    // Rayleigh-Ritz as the SVD of B = D^1/2 G Y (BᵀB = Yᵀ K Y): one-sided Jacobi keeps the
    // small singular values to high relative accuracy, where a symmetric eigensolver of
    // YᵀKY would leave the low eigenvalues eps * lambda_p in absolute error.
    // (zero rows added when G has fewer rows than Y has columns, so that V is p x p)
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(std::max<Eigen::Index>(fe.G.rows(), p), p);
    B.topRows(fe.G.rows()) = fe.D.cwiseSqrt().asDiagonal() * (fe.G * Y);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(B, Eigen::ComputeThinV);
    // singular values come descending: reverse for ascending eigenvalues
    const Eigen::VectorXd sv = svd.singularValues().reverse();
    X = Y * svd.matrixV().rowwise().reverse();
    const Eigen::VectorXd lambda = sv.head(q).cwiseAbs2();
    // Converged when every wanted elastic eigenvalue moved by <= 1e-13 of itself since the
    // previous iteration (measured: the change falls 1e3-fold per iteration on beams, down
    // to a few 1e-15 of noise), or stalled at round-off (<= 1e-11, not halving for 3 steps).
    const double change =
        ((lambda - previous).tail(q - rigid).cwiseAbs().array() / lambda.tail(q - rigid).array()).maxCoeff();
    stalled = change > 0.5 * last_change ? stalled + 1 : 0;
    last_change = change;
    previous = lambda;
    if (change <= 1e-13 || (change <= 1e-11 && stalled >= 3)) return {lambda, X.leftCols(q), it};
  }
  std::ostringstream os;
  os << "finite-element basis: subspace iteration did not converge in " << kMaxIterations << " iterations";
  throw std::runtime_error(os.str());
}

}  // namespace

void FiniteElementOptions::validate() const {
  if (elements < 1 || elements > kMaxElements) {
    std::ostringstream os;
    os << "finite-element basis: elements = " << elements << ", must be in [1, " << kMaxElements << "]";
    throw std::invalid_argument(os.str());
  }
  if (order != 3 && order != 5) {
    std::ostringstream os;
    os << "finite-element basis: element_order = " << order << ", must be 3 or 5";
    throw std::invalid_argument(os.str());
  }
}

FiniteElementBasis::FiniteElementBasis(const Beam& beam, int n, FiniteElementOptions options)
    : options_(options) {
  options_.validate();
  nodes_ = make_nodes(beam, options_.elements);
  const int N = elements();
  per_element_ = options_.order == 5 ? 6 : 4;
  dofs_ = 2 * (N + 1) + (options_.order == 5 ? 2 * N : 0);
  if (n < 1 || n > dofs_ - 2) {
    std::ostringstream os;
    os << "finite-element basis: " << n << " modes requested, must be in [1, " << dofs_ - 2 << "] (the "
       << N << "-element model has " << dofs_ - 2 << " elastic modes)";
    throw std::invalid_argument(os.str());
  }
  const Assembly fe = assemble(beam, nodes_, options_.order, dofs_);
  // Shift: about the first eigenvalue of a uniform free-free beam of the same mass and
  // mean stiffness (500 EI / (m L^3)); any positive shift below the wanted eigenvalues works.
  const double L = beam.length();
  const double sigma = 100.0 * beam.mean_bending_stiffness() / (fe.mass * L * L * L);
  const int io = nearest_node(nodes_, 0.0);
  const double scale = std::sqrt(fe.mass);
  Eigen::MatrixXd V;
  if (options_.modes == FiniteElementOptions::Modes::FreeFree) {
    const Eigenpairs ep = lowest_eigenpairs(fe, n + 2, sigma, 2);
    iterations_ = ep.iterations;
    const double lambda_first = ep.lambda(2);
    if (!(std::abs(ep.lambda(0)) <= 1e-8 * lambda_first && std::abs(ep.lambda(1)) <= 1e-8 * lambda_first))
      throw std::runtime_error("finite-element basis: the element model's two lowest modes are not rigid");
    omega_ = ep.lambda.tail(n).cwiseMax(0.0).cwiseSqrt();

    // eq. 2.6: remove each mode's rigid part at o (w_o, w'_o at node io), scale by sqrt(m).
    V = ep.vectors.rightCols(n) * scale;
    for (int k = 0; k < n; ++k) {
      const double w_o = V(2 * io, k), t_o = V(2 * io + 1, k);
      for (int i = 0; i <= N; ++i) {
        V(2 * i, k) -= w_o + nodes_[i] * t_o;
        V(2 * i + 1, k) -= t_o;
      }
      V(2 * io, k) = V(2 * io + 1, k) = 0.0;  // exactly, whatever nodes_[io] rounds to
    }
  } else {
    // eq. 2.7: held at o, the two sides are independent cantilevers. Each side's lowest
    // modes (as many as n, or all it has), merged by frequency; near-ties (relative 1e-9,
    // e.g. the mirror-image halves of a symmetric beam) take the longer side first, the
    // left on equal lengths, so that the degenerate pairs stay together and in order.
    const auto [left, right] = side_dofs(io, N, per_element_ == 6);
    const std::vector<int>* sides[2] = {&left, &right};
    Eigenpairs ep[2];
    for (int s = 0; s < 2; ++s) {
      const int q = std::min(n, static_cast<int>(sides[s]->size()));
      if (q == 0) continue;  // o at this end of the beam: no side there, no modes
      ep[s] = lowest_eigenpairs(restrict_to(fe, *sides[s]), q, sigma, 0);
      iterations_ = std::max(iterations_, ep[s].iterations);
    }
    const bool left_first_on_tie = beam.x_left() + beam.x_right() <= 0.0;  // |x_left| >= x_right
    omega_.resize(n);
    V = Eigen::MatrixXd::Zero(dofs_, n);
    int next[2] = {0, 0};
    for (int k = 0; k < n; ++k) {
      const bool has_l = next[0] < ep[0].lambda.size(), has_r = next[1] < ep[1].lambda.size();
      int s = has_l ? 0 : 1;
      if (has_l && has_r) {
        const double l = ep[0].lambda(next[0]), r = ep[1].lambda(next[1]);
        s = std::abs(l - r) <= 1e-9 * std::max(l, r) ? (left_first_on_tie ? 0 : 1) : (l < r ? 0 : 1);
      }
      const int j = next[s]++;
      omega_(k) = std::sqrt(std::max(ep[s].lambda(j), 0.0));
      for (std::size_t i = 0; i < sides[s]->size(); ++i) V((*sides[s])[i], k) = scale * ep[s].vectors(i, j);
    }
  }
  for (int k = 0; k < n; ++k) {
    // sign: the end value of larger magnitude is positive
    const double left = V(0, k), right = V(2 * N, k);
    if ((std::abs(right) >= std::abs(left) ? right : left) < 0.0) V.col(k) *= -1.0;
  }
  coef_.resize(static_cast<Eigen::Index>(N) * per_element_, n);
  for (int e = 0; e < N; ++e)
    for (int j = 0; j < per_element_; ++j) coef_.row(e * per_element_ + j) = V.row(global_dof(e, j, N));
}

BasisValues FiniteElementBasis::evaluate(double x) const {
  const int N = elements();
  // element containing x; a node belongs to the element on its right (the last to the last)
  int e = static_cast<int>(std::upper_bound(nodes_.begin(), nodes_.end(), x) - nodes_.begin()) - 1;
  e = std::min(std::max(e, 0), N - 1);
  const double a = nodes_[e], b = nodes_[e + 1], h = b - a;
  const element::Shape s = element::shape((2.0 * x - a - b) / h, h, per_element_);
  const auto C = coef_.middleRows(static_cast<Eigen::Index>(e) * per_element_, per_element_);
  return {s.N * C, s.N1 * C, s.N2 * C};
}

std::vector<double> FiniteElementBasis::cuts() const { return {nodes_.begin() + 1, nodes_.end() - 1}; }

double FiniteElementBasis::max_panel_width() const { return std::numeric_limits<double>::infinity(); }

}  // namespace freeflex
