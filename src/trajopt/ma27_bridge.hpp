#pragma once
// Makes Ipopt's `linear_solver ma27` factor with freeflex's sparse LDLᵀ (sparse_ldlt.hpp).

namespace freeflex::detail {

/// Hands freeflex's LDLᵀ to Ipopt's linear-solver loader (once per process).
void register_sparse_ldlt();

/// The four routines with MA27's calling convention (every argument by pointer, indices
/// from 1), for tests that call them as Ipopt does.
struct Ma27Routines {
  void (*ad)(int* n, int* nz, const int* irn, const int* icn, int* iw, int* liw, int* ikeep, int* iw1, int* nsteps,
             int* iflag, int* icntl, double* cntl, int* info, double* ops);
  void (*bd)(int* n, int* nz, const int* irn, const int* icn, double* a, int* la, int* iw, int* liw, int* ikeep,
             int* nsteps, int* maxfrt, int* iw1, int* icntl, double* cntl, int* info);
  void (*cd)(int* n, double* a, int* la, int* iw, int* liw, double* w, int* maxfrt, double* rhs, int* iw1, int* nsteps,
             int* icntl, double* cntl);
  void (*id)(int* icntl, double* cntl);
};
Ma27Routines ma27_routines();

}  // namespace freeflex::detail
