// The convergence table of docs/theory.md section 4b (issue 15, acceptance 1): relative
// errors of the first five elastic frequencies of the stepped beam, bare and with hub and
// tip mass, on the finite-element basis against tests/reference/stepped_beam_frequencies.csv
// (transfer matrices, scripts/reference/stepped_beam_frequencies.py), for cubic and
// quintic elements on meshes that nest, with the observed order log2(e(N) / e(2N)); and
// the paper's basis against NOA for comparison. Not a test (the tests check the figures
// that matter: tests/model/test_finite_element_basis.cpp).
//   cmake -S . -B build-bench -DFREEFLEX_BUILD_BENCHMARKS=ON && cmake --build build-bench
//   build-bench/bench/fe_convergence
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "freeflex/analysis/free_vibration.hpp"
#include "freeflex/model/modal_integrals.hpp"
#include "support/reference_csv.hpp"  // the tests' reader of tests/reference and their beams

using namespace freeflex;

namespace {

std::vector<double> errors(const Beam& beam, const BasisOptions& b, int n, const Eigen::VectorXd& exact) {
  const Eigen::VectorXd w = free_vibration(modal_integrals(beam, *make_basis(beam, n, b))).omega;
  std::vector<double> e;
  for (int k = 0; k < 5; ++k) e.push_back(w(k) / exact(k) - 1.0);
  return e;
}

}  // namespace

int main() {
  for (const bool payloads : {false, true}) {
    const std::string name = payloads ? "stepped_hub_tip" : "stepped_bare";
    const Beam beam(freeflex_test::stepped_beam(payloads));
    const Eigen::VectorXd exact = freeflex_test::reference_column("stepped_beam_frequencies.csv", name);
    std::printf("\n%s\n| basis | N | e1 | e2 | e3 | e4 | e5 | order (e5) |\n| --- | --- | --- | --- | --- | --- | --- | --- |\n",
                name.c_str());
    for (const int order : {3, 5}) {
      std::vector<double> prev;
      int prev_elements = 0;
      // 200 cubic elements: the budget (its order column is left empty: not a doubling)
      for (const int elements : order == 3 ? std::vector<int>{20, 40, 80, 160, 200, 320} : std::vector<int>{10, 20, 40, 80}) {
        BasisOptions b;
        b.kind = BasisOptions::Kind::FiniteElement;
        b.finite_element = {elements, order};
        const std::vector<double> e = errors(beam, b, 6, exact);
        std::printf("| %s | %d |", order == 3 ? "cubic" : "quintic", elements);
        for (double x : e) std::printf(" %.1e |", x);
        if (elements == 200) {
          std::printf(" |\n");
          continue;  // the next row doubles 160
        }
        if (prev.empty() || elements != 2 * prev_elements || std::abs(e[4]) < 1e-13) std::printf(" |\n");
        else std::printf(" %.2f |\n", std::log2(prev[4] / e[4]));
        prev = e;
        prev_elements = elements;
      }
    }
    for (const int noa : {6, 12, 24, 48, 96}) {
      const std::vector<double> e = errors(beam, BasisOptions{}, noa, exact);
      std::printf("| paper | NOA %d |", noa);
      for (double x : e) std::printf(" %.1e |", x);
      std::printf(" |\n");
    }
  }
  return 0;
}
