// What a sweep's sampling leaves uncertain: the Wilson score interval of the fraction
// meeting the requirement against SciPy's (tests/reference/sweep_intervals.csv, written by
// scripts/reference/sweep_intervals.py), and the order-statistic interval of the 95th
// percentile by its coverage over repeated samples of a known distribution.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "freeflex/app/sweep.hpp"
#include "support/reference_csv.hpp"

using namespace freeflex;

TEST_CASE("the sweep's fraction interval equals SciPy's Wilson interval", "[app]") {
  const auto t = freeflex_test::read_reference("sweep_intervals.csv");
  REQUIRE(t.rows.size() == 6);
  for (const auto& row : t.rows) {
    const long k = std::stol(row[0]), n = std::stol(row[1]);
    const auto [low, high] = wilson_interval(k, n);
    INFO(k << " of " << n);
    CHECK(low == Approx(std::stod(row[2])).margin(1e-14));  // closed form: round-off only
    CHECK(high == Approx(std::stod(row[3])).margin(1e-14));
  }
  CHECK(wilson_interval(0, 0) == std::pair<double, double>{0.0, 1.0});
}

TEST_CASE("the sweep's 95th-percentile interval covers the true one about 95% of the time", "[app]") {
  // 400 samples of n = 1000 uniform draws: the true 0.95 quantile is 0.95. Coverage is a
  // binomial count over 400 trials: 380 expected, standard deviation 4.4; [360, 396]
  // is 4.5 of them either way (a wrong rank or z moves it far outside).
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int covered = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<double> x(1000);
    for (double& v : x) v = u(rng);
    std::sort(x.begin(), x.end());
    const auto [low, high] = quantile_interval(x, 0.95);
    covered += low <= 0.95 && 0.95 <= high;
  }
  INFO("covered " << covered << " of 400");
  CHECK(covered >= 360);
  CHECK(covered <= 396);
  // too few samples for the normal approximation of the ranks: none
  const std::vector<double> few(100, 1.0);
  CHECK(std::isnan(quantile_interval(few, 0.95).first));
}
