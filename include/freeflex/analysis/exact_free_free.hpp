#pragma once
// Closed-form free-free uniform beam (Blevins): frequencies omega_k = lambda_k^2
// sqrt(EI / (mbar L^4)) with cos(lambda) cosh(lambda) = 1, and mode shapes.

namespace freeflex {

/// k-th elastic root (k >= 1) of cos(lambda) cosh(lambda) = 1: 4.7300407..., 7.8532046...
double free_free_root(int k);

/// k-th elastic mode shape of a uniform free-free beam at xi = s / L in [0, 1]:
/// cosh + cos - sigma (sinh + sin) of lambda_k xi, evaluated without cancellation.
double free_free_shape(int k, double xi);

}  // namespace freeflex
