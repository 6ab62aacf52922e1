#pragma once
// Vector kernels of the serial N_Vector, compiled here. Debian's SUNDIALS 6.4 library is
// built without optimization (its N_VLinearSum_Serial, N_VWrmsNorm_Serial, ... are -O0
// code, about 10 cycles per element), and on freeflex's small states (18 to 190
// entries) CVODES' own vector work (Nordsieck prediction and rescaling, error weights,
// norms) is a third to a half of a solve. These kernels do the same arithmetic, element
// by element and in the same order as SUNDIALS, so results are unchanged to the bit;
// fused operations reproduce SUNDIALS' fallback sequences. Only the weighted norm sums
// in another order (four partial sums), which moves its last bit.
#include <sundials/sundials_nvector.h>

namespace freeflex {

/// Replaces the operations of the serial vector `v` (made by N_VNew_Serial) with the
/// compiled kernels; vectors that CVODES clones from `v` inherit them.
void use_compiled_vector_kernels(N_Vector v);

}  // namespace freeflex
