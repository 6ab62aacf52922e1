// The compiled N_Vector kernels (src/sim/fast_nvector) against SUNDIALS' own serial
// kernels: the same results to the bit, except the weighted norm (summed in another order).
#include <catch2/catch.hpp>

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "sim/fast_nvector.hpp"

namespace {

/// Two families of serial vectors with the same data: SUNDIALS' kernels and ours.
struct Pair {
  SUNContext ctx = nullptr;
  std::vector<N_Vector> lib, ours;
  Pair(int count, int n, unsigned seed) {
    SUNContext_Create(nullptr, &ctx);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-2.0, 2.0);
    for (int k = 0; k < count; ++k) {
      lib.push_back(N_VNew_Serial(n, ctx));
      ours.push_back(N_VNew_Serial(n, ctx));
      freeflex::use_compiled_vector_kernels(ours.back());
      for (int i = 0; i < n; ++i) NV_Ith_S(lib.back(), i) = NV_Ith_S(ours.back(), i) = U(rng) + (U(rng) > 0 ? 0.5 : -0.5);
    }
  }
  ~Pair() {
    for (N_Vector v : lib) N_VDestroy(v);
    for (N_Vector v : ours) N_VDestroy(v);
    SUNContext_Free(&ctx);
  }
  bool same(int k) const {
    const sunindextype n = NV_LENGTH_S(lib[k]);
    return std::memcmp(NV_DATA_S(lib[k]), NV_DATA_S(ours[k]), n * sizeof(double)) == 0;
  }
};

}  // namespace

TEST_CASE("compiled N_Vector kernels reproduce SUNDIALS' serial kernels", "[sim]") {
  for (int n : {1, 3, 18, 37, 190}) {
    INFO("length " << n);
    Pair p(4, n, 7u + static_cast<unsigned>(n));
    // linear sums, including the special cases SUNDIALS rounds differently (a = ±b, aliasing)
    const double coef[][2] = {{0.3, 0.7}, {1.0, -2.5}, {-1.0, 0.25}, {0.6, 0.6}, {0.6, -0.6}, {2.0, 1.0}};
    for (const auto& c : coef) {
      N_VLinearSum(c[0], p.lib[0], c[1], p.lib[1], p.lib[2]);
      N_VLinearSum(c[0], p.ours[0], c[1], p.ours[1], p.ours[2]);
      CHECK(p.same(2));
      N_VLinearSum(c[0], p.lib[0], c[1], p.lib[1], p.lib[1]);  // z = y
      N_VLinearSum(c[0], p.ours[0], c[1], p.ours[1], p.ours[1]);
      CHECK(p.same(1));
    }
    N_VScale(-1.5, p.lib[0], p.lib[3]);
    N_VScale(-1.5, p.ours[0], p.ours[3]);
    CHECK(p.same(3));
    // weights for the norm below (SUNDIALS' own kernels on both sides: no longer compiled here)
    N_VDiv(p.lib[0], p.lib[1], p.lib[3]);
    N_VDiv(p.ours[0], p.ours[1], p.ours[3]);
    N_VAbs(p.lib[3], p.lib[3]);
    N_VAbs(p.ours[3], p.ours[3]);
    REQUIRE(p.same(3));
    // the only kernel that sums in another order: equal to round-off of an n-term sum
    const double w_lib = N_VWrmsNorm(p.lib[0], p.lib[3]), w_ours = N_VWrmsNorm(p.ours[0], p.ours[3]);
    CHECK(std::abs(w_lib - w_ours) <= 4.0 * n * DBL_EPSILON * w_lib);
    // fused operations, against SUNDIALS' serial fused kernels (ours: CVODE's fallback for a
    // linear combination, N_VScale and N_VLinearSum calls, made with the kernels above)
    double c3[] = {0.5, -1.25, 3.0};
    N_Vector xl[] = {p.lib[0], p.lib[1], p.lib[2]}, xo[] = {p.ours[0], p.ours[1], p.ours[2]};
    N_VEnableFusedOps_Serial(p.lib[3], SUNTRUE);
    N_VLinearCombination(3, c3, xl, p.lib[3]);
    N_VLinearCombination(3, c3, xo, p.ours[3]);
    CHECK(p.same(3));
    N_Vector yl[] = {p.lib[1], p.lib[2]}, yo[] = {p.ours[1], p.ours[2]};
    N_VEnableFusedOps_Serial(p.lib[0], SUNTRUE);
    N_VScaleAddMulti(2, c3, p.lib[0], yl, yl);
    N_VScaleAddMulti(2, c3, p.ours[0], yo, yo);
    CHECK(p.same(1));
    CHECK(p.same(2));
  }
}
