#pragma once
// The composite Gauss rule of the modal integrals (beam_quadrature) on any interval of the
// beam: shared by the modal integrals and the geometric stiffening integrals (H(x) from o
// to x). Internal to the library.
#include "freeflex/model/beam.hpp"
#include "freeflex/model/quadrature.hpp"
#include "freeflex/model/shape_basis.hpp"

namespace freeflex::detail {

/// Composite 20-point Gauss-Legendre on [a, b] (inside the beam), cut at the beam's
/// breakpoints and the basis's cuts inside it (and at `extra_cut` when inside), panels no
/// wider than the basis's max_panel_width(). On [x_left, x_right] it is beam_quadrature.
GaussRule beam_rule(const Beam& beam, const ShapeBasis& basis, double a, double b, double extra_cut);

}  // namespace freeflex::detail
