// Example: free vibration of the paper's uniform free-free beam through the library API.
//
// Scenario: L = 1 m, m = 1 kg, EI = 1 N m^2, o at the mass centre, NOA = 2..12.
// Expected: three rigid modes at zero frequency; the elastic lambda = sqrt(omega
// sqrt(m L^3 / EI)) fall with every added pair of functions and stay above the exact
// free-free roots 4.7300, 7.8532, 10.9956, 14.1372. Exits 1 if that does not hold.
#include <cstdio>

#include "freeflex/analysis/exact_free_free.hpp"
#include "freeflex/analysis/free_vibration.hpp"
#include "freeflex/model/modal_integrals.hpp"

int main() {
  using namespace freeflex;
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  std::printf("NOA   lambda_1   lambda_2   lambda_3   lambda_4\n");
  Eigen::Vector4d previous = Eigen::Vector4d::Constant(1e9);
  bool ok = true;
  for (int noa = 4; noa <= 12; noa += 2) {
    const FreeVibrationResult r = free_vibration(modal_integrals(beam, make_basis(beam, noa)));
    const Eigen::Vector4d lambda = r.omega.head<4>().cwiseSqrt();  // m = L = EI = 1
    std::printf("%3d %10.6f %10.6f %10.6f %10.6f\n", noa, lambda(0), lambda(1), lambda(2), lambda(3));
    for (int k = 0; k < 4; ++k) ok = ok && lambda(k) <= previous(k) && lambda(k) > free_free_root(k + 1);
    previous = lambda;
  }
  std::printf("exact %8.6f %10.6f %10.6f %10.6f\n", free_free_root(1), free_free_root(2), free_free_root(3),
              free_free_root(4));
  std::printf(ok ? "as expected: monotone from above\n" : "NOT as expected\n");
  return ok ? 0 : 1;
}
