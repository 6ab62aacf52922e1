#pragma once
// Vector kernels of the serial N_Vector, compiled here, for the few operations where they
// still beat SUNDIALS' own serial kernels now that freeflex builds SUNDIALS with -O2
// (Debian's library is -O0; docs/benchmarks.md, "An optimized SUNDIALS"):
// - z = a x + b y: CVODE's Adams predictor is a chain of dependent z = x + y calls, which
//   this kernel tests for first, ahead of SUNDIALS' case analysis (8% of the instructions
//   of a full-model run at NOA 6);
// - z = c x, and Z_i = a_i x + Y_i for several i in one call (CVODE otherwise makes one
//   N_VLinearSum call per vector: the serial vector's fused operations are off); 4% together;
// - the weighted RMS norm, summed in four partial sums. This is the only kernel whose
//   rounding differs from SUNDIALS' (its last bit), so removing it would change every
//   result; the others do the same arithmetic as SUNDIALS, element by element and in the
//   same order, so results are unchanged to the bit.
// The other operations (N_VConst, N_VProd, N_VDiv, N_VAbs, N_VInv, N_VAddConst, N_VMaxNorm,
// N_VMin, N_VLinearCombination) were compiled here too until SUNDIALS itself was; against
// the -O2 library they saved at most 0.7% of the instructions (callgrind) and were removed.
#include <sundials/sundials_nvector.h>

namespace freeflex {

/// Replaces those operations of the serial vector `v` (made by N_VNew_Serial) with the
/// kernels above; vectors that CVODES clones from `v` inherit them.
void use_compiled_vector_kernels(N_Vector v);

}  // namespace freeflex
