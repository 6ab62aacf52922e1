#pragma once
// A sparse symmetric indefinite LDLᵀ for Ipopt's KKT systems: approximate-minimum-degree
// ordering, supernodes with relaxed amalgamation, multifrontal factorization with
// threshold 1x1 / 2x2 pivoting inside each front and pivots that fail the threshold
// delayed to the parent front (the method of Duff and Reid's MA27), and the inertia
// (number of negative eigenvalues) that Ipopt's step computation needs.
//
// Why freeflex has its own: Ipopt 3.11 in Debian factors with sequential MUMPS on the
// reference BLAS, whose fixed cost per factorization and slow small dense kernels were
// two thirds of a maneuver solve (docs/benchmarks.md). The factor lives in caller-owned
// arrays (a, iw) so that it can serve Ipopt's MA27 interface, which owns them
// (trajopt/ma27_bridge.cpp).
#include <cstdint>
#include <vector>

namespace freeflex::detail {

/// The symbolic analysis of a symmetric pattern: elimination order and supernodes.
struct LdltSymbolic {
  int n = 0;
  std::vector<int> order;      ///< order[k]: the (0-based) variable eliminated k-th
  std::vector<int> sn_start;   ///< supernode s eliminates positions [sn_start[s], sn_start[s + 1])
  std::vector<int> sn_parent;  ///< parent supernode, -1 at a root; children come before parents
  /// The matrix's entries by columns of the permuted lower triangle: column k (position)
  /// holds positions row[colptr[k] .. colptr[k + 1]) >= k; entry t of the input goes to
  /// slot[t] (duplicates keep their own slots and are summed on assembly); source[slot[t]]
  /// = t.
  std::vector<int> colptr, row, slot, source;
  long long factor_doubles = 0;  ///< factor storage without delayed pivots
  long long factor_ints = 0;
  int max_front = 0;             ///< largest front without delayed pivots
  int supernodes() const { return static_cast<int>(sn_parent.size()); }
};

/// Analyses the pattern of nz entries (rows[k], cols[k]) with indices from `base` (0 or
/// 1); either triangle, duplicates allowed. Throws std::invalid_argument for an index out
/// of range.
LdltSymbolic ldlt_analyse(int n, long long nz, const int* rows, const int* cols, int base);

/// Fills s.colptr, s.row, s.slot for the pattern (the rest of s given: order, supernodes).
void ldlt_map_columns(LdltSymbolic& s, long long nz, const int* rows, const int* cols, int base);

struct LdltFactorStatus {
  enum class Code { Ok, Singular, NeedDoubles, NeedInts } code = Code::Ok;
  long long need = 0;   ///< NeedDoubles / NeedInts: the size required
  int negative = 0;     ///< negative eigenvalues (Ok)
  int rank = 0;         ///< nonzero pivots (Singular: < n)
  int max_front = 0;    ///< largest front, delayed pivots included
  int delayed = 0;      ///< pivots passed on to a parent front
  int blocks_2x2 = 0;   ///< 2x2 pivots
};

/// Factorizes the matrix whose entries are values[k] in the pattern analysed into `s`
/// (duplicates are summed) into a[0, la) and iw[0, liw). A pivot is
/// accepted when it is at least `threshold` (in [0, 1]) times the largest entry of its
/// column (MA27's test, for 2x2 blocks through the block's inverse); a pivot at a root
/// front is taken whatever its size, and one of exactly zero makes the matrix Singular.
LdltFactorStatus ldlt_factor(const LdltSymbolic& s, const double* values, double threshold, double* a, long long la,
                             int* iw, long long liw);

/// Solves A x = rhs in place with the factor that ldlt_factor wrote into a and iw.
void ldlt_solve(const double* a, const int* iw, double* rhs);

}  // namespace freeflex::detail
