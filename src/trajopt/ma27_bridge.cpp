// freeflex's sparse LDLᵀ behind Ipopt's MA27 interface. Debian's Ipopt 3.11 is built with
// its linear-solver loader, which calls MA27 through function pointers that a program
// may set itself (LSL_setMA27); with `linear_solver ma27` Ipopt then factors its KKT
// systems with these routines. Nothing of HSL's MA27 is used: only its calling
// convention, in which the caller owns every array (the analysis lives in IKEEP, the
// factor in A and IW).
#include "trajopt/ma27_bridge.hpp"

#include <coin/HSLLoader.h>

#include <algorithm>
#include <climits>
#include <atomic>
#include <mutex>
#include <vector>

#include "trajopt/sparse_ldlt.hpp"

namespace freeflex::detail {
namespace {

int clamp_int(long long v) { return static_cast<int>(std::min<long long>(v, INT_MAX)); }

/// The analyses of this thread's latest patterns, with their column maps: MA27's IKEEP
/// holds only 3 n integers, so the rest of an analysis is kept here under an id written
/// into IKEEP's last slot (free whenever there are fewer supernodes than variables). An
/// analysis that is not found is rebuilt from IKEEP and the pattern.
struct Analysis {
  int id;
  LdltSymbolic s;
};
thread_local std::vector<Analysis> analyses;
std::atomic<int> next_id{1};
constexpr std::size_t kKept = 4;

int new_id() {
  int id = next_id.fetch_add(1);
  if (id <= 0) {  // wrapped after 2^31 analyses
    next_id = 2;
    id = 1;
  }
  return id;
}

void keep(int id, LdltSymbolic&& s) {
  if (analyses.size() >= kKept) analyses.erase(analyses.begin());
  analyses.push_back({id, std::move(s)});
}

/// The analysis as kept in IKEEP (3 n integers): order, then the supernodes' ends, then
/// their parents; NSTEPS holds the number of supernodes.
LdltSymbolic from_ikeep(int n, const ipfint* ikeep, int nsn) {
  LdltSymbolic s;
  s.n = n;
  s.order.assign(ikeep, ikeep + n);
  s.sn_start.resize(nsn + 1);
  s.sn_start[0] = 0;
  std::copy(ikeep + n, ikeep + n + nsn, s.sn_start.begin() + 1);
  s.sn_parent.assign(ikeep + 2 * n, ikeep + 2 * n + nsn);
  return s;
}

extern "C" void ff_ma27id(ipfint* icntl, double* cntl) {
  std::fill(icntl, icntl + 30, 0);
  std::fill(cntl, cntl + 5, 0.0);
  cntl[0] = 0.1;  // pivot threshold (Ipopt overwrites it with ma27_pivtol)
}

extern "C" void ff_ma27ad(ipfint* N, ipfint* NZ, const ipfint* IRN, const ipfint* ICN, ipfint*, ipfint*, ipfint* IKEEP,
                          ipfint*, ipfint* NSTEPS, ipfint*, ipfint*, double*, ipfint* INFO, double* OPS) {
  std::fill(INFO, INFO + 20, 0);
  try {
    LdltSymbolic s = ldlt_analyse(*N, *NZ, IRN, ICN, 1);
    const int n = s.n, nsn = s.supernodes();
    std::copy(s.order.begin(), s.order.end(), IKEEP);
    std::copy(s.sn_start.begin() + 1, s.sn_start.end(), IKEEP + n);
    std::copy(s.sn_parent.begin(), s.sn_parent.end(), IKEEP + 2 * n);
    *NSTEPS = nsn;
    // MA27's storage is counted in ints: a factor that Ipopt could not size (with its
    // margins) is refused here, as a fatal error Ipopt reports, not an overflow
    if (std::max(s.factor_doubles, s.factor_ints) > INT_MAX / 4) {
      INFO[0] = -5;
      return;
    }
    INFO[4] = clamp_int(s.factor_doubles + 1);  // NRLNEC
    INFO[5] = clamp_int(s.factor_ints + 1);     // NIRNEC
    *OPS = static_cast<double>(s.factor_doubles) * s.max_front;
    if (nsn < n) {
      const int id = new_id();
      IKEEP[3 * n - 1] = id;
      keep(id, std::move(s));
    }
  } catch (...) {
    INFO[0] = -1;  // MA27's "N out of range": Ipopt reports a fatal error
  }
}

extern "C" void ff_ma27bd(ipfint* N, ipfint* NZ, const ipfint* IRN, const ipfint* ICN, double* A, ipfint* LA, ipfint* IW,
                          ipfint* LIW, ipfint* IKEEP, ipfint* NSTEPS, ipfint* MAXFRT, ipfint*, ipfint*, double* CNTL,
                          ipfint* INFO) {
  std::fill(INFO, INFO + 20, 0);
  try {
    const int n = *N, nsn = *NSTEPS;
    const LdltSymbolic* s = nullptr;
    const int id = nsn < n ? IKEEP[3 * n - 1] : 0;
    for (const Analysis& kept : analyses)
      if (id != 0 && kept.id == id) s = &kept.s;
    LdltSymbolic rebuilt;
    if (s == nullptr) {
      rebuilt = from_ikeep(n, IKEEP, nsn);
      ldlt_map_columns(rebuilt, *NZ, IRN, ICN, 1);
      s = &rebuilt;
    }
    const LdltFactorStatus st = ldlt_factor(*s, A, std::clamp(CNTL[0], 0.0, 1.0), A, *LA, IW, *LIW);
    *MAXFRT = std::max(st.max_front, 1);
    switch (st.code) {
      case LdltFactorStatus::Code::Ok:
        INFO[14] = st.negative;
        break;
      case LdltFactorStatus::Code::Singular:
        INFO[0] = 3;
        INFO[1] = st.rank;
        break;
      case LdltFactorStatus::Code::NeedDoubles:
        INFO[0] = -4;
        INFO[1] = clamp_int(st.need);
        break;
      case LdltFactorStatus::Code::NeedInts:
        INFO[0] = -3;
        INFO[1] = clamp_int(st.need);
        break;
    }
  } catch (...) {
    INFO[0] = -5;  // Ipopt reads it as a singular matrix and perturbs it
  }
}

extern "C" void ff_ma27cd(ipfint*, double* A, ipfint*, ipfint* IW, ipfint*, double*, ipfint*, double* RHS, ipfint*,
                          ipfint*, ipfint*, double*) {
  ldlt_solve(A, IW, RHS);
}

}  // namespace

Ma27Routines ma27_routines() { return {ff_ma27ad, ff_ma27bd, ff_ma27cd, ff_ma27id}; }

void register_sparse_ldlt() {
  static std::once_flag once;
  std::call_once(once, [] { LSL_setMA27(ff_ma27ad, ff_ma27bd, ff_ma27cd, ff_ma27id); });
}

}  // namespace freeflex::detail
