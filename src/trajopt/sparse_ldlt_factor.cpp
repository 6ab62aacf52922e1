// The numerical part of the sparse LDLᵀ: multifrontal factorization over the supernodes
// in postorder (fronts assembled from the matrix and the children's contribution blocks,
// kept on a stack), threshold 1x1 / 2x2 pivoting within each front's fully summed
// columns with failed pivots delayed to the parent, and the solve.
//
// Layout of the factor in the caller's arrays (what ldlt_solve reads):
//   iw: [magic, n, supernodes, max front], order (n), then per supernode s a table entry
//       [a offset low, a offset high, iw record offset] and its record
//       [m, p, front positions (m), pivot kinds (p)] (kind 1: 1x1, 2 and 3: the two
//       columns of a 2x2 block);
//   a:  per supernode the front's first p columns (m x p, column major): D on the
//       diagonal (a 2x2 block's off-diagonal at (k+1, k)), L strictly below it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "trajopt/sparse_ldlt.hpp"
#include "trajopt/sparse_ldlt_kernels.hpp"

namespace freeflex::detail {
namespace {

constexpr int kMagic = 0x46464c44;  // "FFLD"
constexpr int kHeader = 4;

/// At least n entries in v (grown, never shrunk): resizing a vector up value-initializes
/// what it adds, which cost the elastic maneuvers a tenth of their solve in memset.
template <class T>
T* room(std::vector<T>& v, std::size_t n) {
  if (v.size() < n) v.resize(std::max(n, 2 * v.size()));
  return v.data();
}

struct Workspace {
  std::vector<int> where, idx, kind, nchild, local, run_end;
  std::vector<double> val, front, temp;
  std::vector<double> stack;    // contribution blocks (r x r, column major), stack_used of it in use
  std::size_t stack_used = 0;
  std::vector<int> stack_idx;   // their positions
  struct Block {
    std::size_t off, idx_off;
    int r, ndel;
  };
  std::vector<Block> blocks;
};

/// Partial LDLᵀ of the front F (m x m, lower triangle, column major) over its first q
/// (fully summed) columns: how many were eliminated (p), the negative eigenvalues among
/// their pivots, and whether a root front met a zero pivot. The kinds of the pivots go to
/// kind, the interchanges to idx.
struct FrontResult {
  int p = 0;
  int negative = 0;
  int blocks_2x2 = 0;
  bool zero_pivot = false;
};

class Front {
 public:
  Front(double* F, int m, int q, std::vector<int>& idx, std::vector<int>& kind, std::vector<double>& temp)
      : F_(F), m_(m), q_(q), idx_(idx), kind_(kind), temp_(temp) {}

  /// Blocked: the 1x1 pivots of a block of up to kBlock columns are taken left-looking
  /// (each column brought up to date only when its turn comes), and the block's pivots
  /// reach the columns after it in one product when it is full. A column that fails the
  /// 1x1 test first brings every fully summed column up to date; the search over them and a
  /// 2x2 pivot then go right-looking.
  FrontResult factor(double u, bool force) {
    FrontResult res;
    int k = 0, kb = 0;  // the pivots [kb, k) have not reached the columns from k on
    while (k < q_) {
      if (k - kb == kBlock) {
        update(kb, k, k, q_);
        kb = k;
      }
      const double g = kb < k ? refresh(kb, k) : -1.0;  // the column's largest off-diagonal entry
      const double d = F(k, k);
      if (d != 0.0 && std::abs(d) >= u * (g >= 0.0 ? g : max_abs(&F(k + 1, k), m_ - k - 1))) {
        res.negative += d < 0.0 ? 1 : 0;
        scale_column(k);
        kind_.push_back(1);
        k += 1;
        continue;
      }
      if (kb < k) update(kb, k, k + 1, q_);  // column k is already up to date
      int j = -1, r = -1;
      if (!find_pivot(k, u, j, r) && (!force || !find_forced_pivot(k, j, r))) {
        res.zero_pivot = force;
        kb = k;
        break;
      }
      if (r < 0) {
        swap(k, j);
        res.negative += F(k, k) < 0.0 ? 1 : 0;
        eliminate_1x1(k);
        kind_.push_back(1);
        k += 1;
      } else {
        swap(k, std::min(j, r));
        swap(k + 1, std::max(j, r));
        const double det = F(k, k) * F(k + 1, k + 1) - F(k + 1, k) * F(k + 1, k);
        res.negative += det < 0.0 ? 1 : (F(k, k) < 0.0 ? 2 : 0);
        eliminate_2x2(k);
        kind_.push_back(2);
        kind_.push_back(3);
        ++res.blocks_2x2;
        k += 2;
      }
      kb = k;
    }
    if (kb < k) update(kb, k, k, q_);  // the delayed columns
    res.p = k;
    update(0, k, q_);
    return res;
  }

 private:
  static constexpr int kBlock = 16;

  double& F(int i, int j) { return F_[i + static_cast<std::ptrdiff_t>(j) * m_]; }
  /// Entry (i, j) of the symmetric active matrix, either triangle.
  double S(int i, int j) { return i >= j ? F(i, j) : F(j, i); }

  /// Largest |a_ij| over active rows i >= k, i not j and not skip.
  double colmax(int k, int j, int skip) {
    double g = 0.0;
    for (int i = k; i < j; ++i)
      if (i != skip) g = std::max(g, std::abs(F(j, i)));
    if (skip > j) {
      g = std::max(g, max_abs(&F(j + 1, j), skip - j - 1));
      g = std::max(g, max_abs(&F(skip + 1, j), m_ - skip - 1));
    } else {
      g = std::max(g, max_abs(&F(j + 1, j), m_ - j - 1));
    }
    return g;
  }

  /// MA27's threshold test over the fully summed columns in order: a 1x1 pivot j with
  /// |a_jj| >= u max_i |a_ij|, else a 2x2 with the largest fully summed entry of column j
  /// whose inverse keeps the growth below 1/u.
  bool find_pivot(int k, double u, int& j, int& r) {
    for (j = k; j < q_; ++j) {
      const double ajj = std::abs(F(j, j));
      r = -1;
      if (ajj > 0.0 && ajj >= u * colmax(k, j, -1)) return true;
      double best = 0.0;
      for (int i = k; i < q_; ++i)
        if (i != j && std::abs(S(i, j)) > best) best = std::abs(S(i, j)), r = i;
      if (r < 0) continue;
      const double a = S(j, j), b = S(r, j), c = S(r, r), det = a * c - b * b;
      if (det == 0.0) continue;
      const double gj = colmax(k, j, r), gr = colmax(k, r, j), lim = std::abs(det) / std::max(u, 1e-300);
      if (std::abs(c) * gj + std::abs(b) * gr <= lim && std::abs(b) * gj + std::abs(a) * gr <= lim) return true;
    }
    r = -1;
    return false;
  }

  /// At a root every column must go: the 1x1 with the best ratio |a_jj| / max |a_ij|, or
  /// when every diagonal is zero the 2x2 on the largest fully summed entry.
  bool find_forced_pivot(int k, int& j, int& r) {
    double best = 0.0;
    j = -1;
    r = -1;
    for (int c = k; c < q_; ++c) {
      const double g = colmax(k, c, -1), d = std::abs(F(c, c));
      const double ratio = g > 0.0 ? d / g : (d > 0.0 ? HUGE_VAL : 0.0);
      if (ratio > best) best = ratio, j = c;
    }
    if (j >= 0) return true;
    double big = 0.0;
    for (int c = k; c < q_; ++c)
      for (int i = c + 1; i < q_; ++i)
        if (std::abs(F(i, c)) > big) big = std::abs(F(i, c)), j = c, r = i;
    return big > 0.0;
  }

  /// Symmetric interchange of positions a and b in the lower triangle, the rows of the
  /// columns already eliminated included.
  void swap(int a, int b) {
    if (a == b) return;
    if (a > b) std::swap(a, b);
    for (int c = 0; c < a; ++c) std::swap(F(a, c), F(b, c));
    std::swap(F(a, a), F(b, b));
    for (int c = a + 1; c < b; ++c) std::swap(F(c, a), F(b, c));
    for (int i = b + 1; i < m_; ++i) std::swap(F(i, a), F(i, b));
    std::swap(idx_[a], idx_[b]);
  }

  /// Column k brought up to date with the pivots [kb, k) (all 1x1): F(k:, k) -= L(k:, kb:k)
  /// (L D)(k, kb:k)ᵀ; returns the largest |F(i, k)|, i > k, of the result.
  double refresh(int kb, int k) {
    double* t = room(temp_, k - kb);
    for (int c = kb; c < k; ++c) t[c - kb] = F(k, c) * F(c, c);
    return column_update_max(m_ - k, k - kb, &F(k, kb), m_, t, &F(k, k));
  }

  /// L's column k from pivot k (1x1): the column below the diagonal over the pivot.
  void scale_column(int k) {
    const double inv = 1.0 / F(k, k);
    for (int i = k + 1; i < m_; ++i) F(i, k) *= inv;
  }

  /// Pivot k, right-looking: updates the fully summed columns (k, q), then stores L's
  /// column.
  void eliminate_1x1(int k) {
    const double d = F(k, k);
    const int cols = q_ - k - 1;
    double* t = room(temp_, std::max(cols, 1));
    for (int j = 0; j < cols; ++j) t[j] = F(k + 1 + j, k) / d;
    trapezoid_update(m_ - k - 1, cols, 1, &F(k + 1, k), m_, t, cols, &F(k + 1, k + 1), m_);
    scale_column(k);
  }

  /// 2x2 pivot on k, k + 1, right-looking: the fully summed columns (k + 1, q) updated.
  void eliminate_2x2(int k) {
    const double a = F(k, k), b = F(k + 1, k), c = F(k + 1, k + 1), det = a * c - b * b;
    const int rows = m_ - k - 2;
    double* L1 = room(temp_, 2 * static_cast<std::size_t>(std::max(rows, 1)));
    double* L2 = L1 + rows;
    for (int i = k + 2; i < m_; ++i) {
      const double w1 = F(i, k), w2 = F(i, k + 1);
      L1[i - k - 2] = (c * w1 - b * w2) / det;
      L2[i - k - 2] = (a * w2 - b * w1) / det;
    }
    trapezoid_update(rows, q_ - k - 2, 2, &F(k + 2, k), m_, L1, rows, &F(k + 2, k + 2), m_);
    for (int i = k + 2; i < m_; ++i) F(i, k) = L1[i - k - 2], F(i, k + 1) = L2[i - k - 2];
  }

  /// F(i, j) -= Σ_{c in [c0, c1)} L(i, c) (L D)(j, c) for j in [from, to), i >= j: one
  /// product. With to = m (the default) it is the contribution block's update.
  void update(int c0, int c1, int from, int to = -1) {
    if (to < 0) to = m_;
    const int rows = m_ - from, cols = to - from, p = c1 - c0;
    if (rows <= 0 || cols <= 0 || p <= 0) return;
    double* W = room(temp_, static_cast<std::size_t>(cols) * p);  // (L D)(from:to, c0:c1)
    for (int c = c0; c < c1; ++c) {
      const double* l = &F(from, c);
      double* w = W + static_cast<std::ptrdiff_t>(c - c0) * cols;
      if (kind_[c] == 1) {
        const double d = F(c, c);
        for (int i = 0; i < cols; ++i) w[i] = l[i] * d;
      } else if (kind_[c] == 2) {
        const double a = F(c, c), b = F(c + 1, c), d = F(c + 1, c + 1);
        const double* l2 = l + m_;
        double* w2 = w + cols;
        for (int i = 0; i < cols; ++i) w[i] = l[i] * a + l2[i] * b, w2[i] = l[i] * b + l2[i] * d;
      }
    }
    trapezoid_update(rows, cols, p, &F(from, c0), m_, W, cols, &F(from, from), m_);
  }

  double* F_;
  int m_, q_;
  std::vector<int>& idx_;
  std::vector<int>& kind_;
  std::vector<double>& temp_;
};

void put_offset(int* iw, long long v) {
  iw[0] = static_cast<int>(v & 0x7fffffff);
  iw[1] = static_cast<int>(v >> 31);
}
long long get_offset(const int* iw) { return static_cast<long long>(iw[0]) | (static_cast<long long>(iw[1]) << 31); }

}  // namespace

LdltFactorStatus ldlt_factor(const LdltSymbolic& s, const double* values, double u, double* a, long long la, int* iw,
                             long long liw) {
  thread_local Workspace w;
  const int n = s.n, nsn = s.supernodes();
  LdltFactorStatus st;

  // The values by columns (copied before anything is written: they may share storage
  // with the factor).
  const std::size_t nz = s.slot.size();
  w.val.resize(nz);
  for (std::size_t at = 0; at < nz; ++at) w.val[at] = values[s.source[at]];
  w.where.assign(n, -1);
  w.nchild.assign(nsn, 0);
  for (int t = 0; t < nsn; ++t)
    if (s.sn_parent[t] >= 0) ++w.nchild[s.sn_parent[t]];
  w.blocks.clear();
  w.stack_used = 0;
  w.stack_idx.clear();

  const long long table = kHeader + n;
  long long iw_at = table + 3LL * nsn, a_at = 0;
  const bool room_header = liw >= iw_at;
  if (room_header) {
    iw[0] = kMagic;
    iw[1] = n;
    iw[2] = nsn;
    std::copy(s.order.begin(), s.order.end(), iw + kHeader);
  }

  for (int sn = 0; sn < nsn; ++sn) {
    const int c0 = s.sn_start[sn], c1 = s.sn_start[sn + 1];
    const std::size_t first_child = w.blocks.size() - w.nchild[sn];
    // Front positions in increasing order: the children's delayed pivots (all before c0),
    // the own columns, then the rows below (after c1). Every contribution block lists its
    // positions in increasing order too, so each lands in the front's lower triangle.
    w.idx.clear();
    for (std::size_t b = first_child; b < w.blocks.size(); ++b)
      for (int t = 0; t < w.blocks[b].ndel; ++t) w.idx.push_back(w.stack_idx[w.blocks[b].idx_off + t]);
    std::sort(w.idx.begin(), w.idx.end());
    for (int c = c0; c < c1; ++c) w.idx.push_back(c);
    const int q = static_cast<int>(w.idx.size());
    for (int v : w.idx) w.where[v] = 0;
    for (std::size_t b = first_child; b < w.blocks.size(); ++b)
      for (int t = w.blocks[b].ndel; t < w.blocks[b].r; ++t) {
        const int v = w.stack_idx[w.blocks[b].idx_off + t];
        if (w.where[v] < 0) w.where[v] = 0, w.idx.push_back(v);
      }
    for (int t = s.colptr[c0]; t < s.colptr[c1]; ++t) {
      const int v = s.row[t];
      if (w.where[v] < 0) w.where[v] = 0, w.idx.push_back(v);
    }
    std::sort(w.idx.begin() + q, w.idx.end());
    const int m = static_cast<int>(w.idx.size());
    for (int l = 0; l < m; ++l) w.where[w.idx[l]] = l;
    st.max_front = std::max(st.max_front, m);

    // Assembly into the lower triangle.
    double* F = room(w.front, static_cast<std::size_t>(m) * m);
    for (int j = 0; j < m; ++j) std::fill(F + j + static_cast<std::ptrdiff_t>(j) * m, F + static_cast<std::ptrdiff_t>(j + 1) * m, 0.0);
    for (int c = c0; c < c1; ++c) {
      const std::ptrdiff_t lc = w.where[c];
      for (int t = s.colptr[c]; t < s.colptr[c + 1]; ++t) F[w.where[s.row[t]] + lc * m] += w.val[t];
    }
    for (std::size_t b = first_child; b < w.blocks.size(); ++b) {
      const auto& blk = w.blocks[b];
      const double* cb = w.stack.data() + blk.off;
      const int* ci = w.stack_idx.data() + blk.idx_off;
      w.local.resize(blk.r);
      w.run_end.resize(blk.r);
      for (int x = 0; x < blk.r; ++x) w.local[x] = w.where[ci[x]];
      // runs of rows that land on consecutive front rows: added as contiguous slices
      for (int x = blk.r - 1; x >= 0; --x)
        w.run_end[x] = x + 1 < blk.r && w.local[x + 1] == w.local[x] + 1 ? w.run_end[x + 1] : x + 1;
      for (int y = 0; y < blk.r; ++y) {
        double* col = F + static_cast<std::ptrdiff_t>(w.local[y]) * m;
        const double* from = cb + static_cast<std::ptrdiff_t>(y) * blk.r;
        for (int x = y; x < blk.r;) {
          const int e = w.run_end[x];
          double* to = col + w.local[x];
          for (int t = 0; t < e - x; ++t) to[t] += from[x + t];
          x = e;
        }
      }
    }
    if (first_child < w.blocks.size()) {
      w.stack_used = w.blocks[first_child].off;
      w.stack_idx.resize(w.blocks[first_child].idx_off);
      w.blocks.resize(first_child);
    }

    // Partial factorization.
    w.kind.clear();
    const FrontResult fr = Front(F, m, q, w.idx, w.kind, w.temp).factor(u, s.sn_parent[sn] < 0);
    for (int v : w.idx) w.where[v] = -1;
    if (fr.zero_pivot) {
      st.code = LdltFactorStatus::Code::Singular;
      st.rank = n - (q - fr.p);
      return st;
    }
    const int p = fr.p;
    st.negative += fr.negative;
    st.blocks_2x2 += fr.blocks_2x2;
    st.delayed += q - p;

    // The factor's columns and the record.
    const long long rec = 2 + static_cast<long long>(m) + p;
    if (a_at + static_cast<long long>(m) * p <= la && iw_at + rec <= liw && room_header) {
      put_offset(iw + table + 3LL * sn, a_at);
      iw[table + 3LL * sn + 2] = static_cast<int>(iw_at);
      std::memcpy(a + a_at, F, sizeof(double) * static_cast<std::size_t>(m) * p);
      int* r = iw + iw_at;
      r[0] = m;
      r[1] = p;
      std::copy(w.idx.begin(), w.idx.end(), r + 2);
      std::copy(w.kind.begin(), w.kind.end(), r + 2 + m);
    }
    a_at += static_cast<long long>(m) * p;
    iw_at += rec;

    // The contribution block goes on the stack.
    const int r = m - p;
    if (r > 0) {
      Workspace::Block blk{w.stack_used, w.stack_idx.size(), r, q - p};
      // the delayed pivots back in increasing order (pivoting may have swapped them)
      w.local.resize(r);
      for (int x = 0; x < r; ++x) w.local[x] = p + x;
      std::sort(w.local.begin(), w.local.begin() + (q - p), [idx = w.idx.data()](int a, int b) { return idx[a] < idx[b]; });
      w.stack_used = blk.off + static_cast<std::size_t>(r) * r;
      double* cb = room(w.stack, w.stack_used) + blk.off;
      const int ndel = q - p;
      for (int y = 0; y < r; ++y) {
        double* to = cb + static_cast<std::ptrdiff_t>(y) * r;
        const int ly = w.local[y];
        int x = y;
        for (; x < ndel; ++x) {
          const int lx = w.local[x];
          to[x] = lx >= ly ? F[lx + static_cast<std::ptrdiff_t>(ly) * m] : F[ly + static_cast<std::ptrdiff_t>(lx) * m];
        }
        // past the delayed pivots the order is the front's own
        std::copy(F + (p + x) + static_cast<std::ptrdiff_t>(ly) * m, F + m + static_cast<std::ptrdiff_t>(ly) * m, to + x);
      }
      for (int x = 0; x < r; ++x) w.stack_idx.push_back(w.idx[w.local[x]]);
      w.blocks.push_back(blk);
    }
  }
  if (room_header) iw[3] = st.max_front;
  if (iw_at > liw) {
    st.code = LdltFactorStatus::Code::NeedInts;
    st.need = iw_at;
  } else if (a_at > la) {
    st.code = LdltFactorStatus::Code::NeedDoubles;
    st.need = a_at;
  }
  st.rank = n;
  return st;
}

void ldlt_solve(const double* a, const int* iw, double* rhs) {
  thread_local std::vector<double> y, wv;
  const int n = iw[1], nsn = iw[2], maxf = iw[3];
  const int* order = iw + kHeader;
  const int* table = order + n;
  y.resize(n);
  wv.resize(maxf);
  for (int k = 0; k < n; ++k) y[k] = rhs[order[k]];
  double* w = wv.data();
  // L z = b, supernode by supernode.
  for (int sn = 0; sn < nsn; ++sn) {
    const double* L = a + get_offset(table + 3 * sn);
    const int* r = iw + table[3 * sn + 2];
    const int m = r[0], p = r[1];
    const int* idx = r + 2;
    const int* kind = r + 2 + m;
    for (int c = 0; c < p; ++c) w[c] = y[idx[c]];
    for (int c = 0; c < p; ++c) {
      const double* col = L + static_cast<std::ptrdiff_t>(c) * m;
      if (kind[c] == 1) {
        for (int i = c + 1; i < p; ++i) w[i] -= col[i] * w[c];
      } else if (kind[c] == 2) {
        const double* col2 = col + m;
        for (int i = c + 2; i < p; ++i) w[i] -= col[i] * w[c] + col2[i] * w[c + 1];
      }
    }
    for (int c = 0; c < p; ++c) y[idx[c]] = w[c];
    // the rows below: y(idx[p:m]) -= L(p:m, 0:p) w, one dense product (a 2x2 block's two
    // columns are L's columns like any other)
    double* t = w + p;
    std::fill(t, t + (m - p), 0.0);
    column_update_max(m - p, p, L + p, m, w, t);
    for (int i = p; i < m; ++i) y[idx[i]] += t[i - p];
  }
  // D, then Lᵀ x = z in reverse.
  for (int sn = nsn - 1; sn >= 0; --sn) {
    const double* L = a + get_offset(table + 3 * sn);
    const int* r = iw + table[3 * sn + 2];
    const int m = r[0], p = r[1];
    const int* idx = r + 2;
    const int* kind = r + 2 + m;
    for (int c = 0; c < p; ++c) {
      const double* col = L + static_cast<std::ptrdiff_t>(c) * m;
      if (kind[c] == 1) {
        w[c] = y[idx[c]] / col[c];
      } else if (kind[c] == 2) {
        const double d11 = col[c], d21 = col[c + 1], d22 = col[m + c + 1], det = d11 * d22 - d21 * d21;
        const double b1 = y[idx[c]], b2 = y[idx[c + 1]];
        w[c] = (d22 * b1 - d21 * b2) / det;
        w[c + 1] = (d11 * b2 - d21 * b1) / det;
      }
    }
    // w -= L(p:m, 0:p)ᵀ y(idx[p:m]), the rows below gathered once
    double* g = w + p;
    for (int i = p; i < m; ++i) g[i - p] = y[idx[i]];
    transposed_update(m - p, p, L + p, m, g, w);
    for (int c = p - 1; c >= 0; --c) {
      const double* col = L + static_cast<std::ptrdiff_t>(c) * m;
      if (kind[c] == 1) {
        double acc = 0.0;
        for (int i = c + 1; i < p; ++i) acc += col[i] * w[i];
        w[c] -= acc;
      } else if (kind[c] == 3) {
        const double* col1 = col - m;  // the block's first column
        double acc1 = 0.0, acc2 = 0.0;
        for (int i = c + 1; i < p; ++i) acc1 += col1[i] * w[i], acc2 += col[i] * w[i];
        w[c - 1] -= acc1;
        w[c] -= acc2;
        --c;
      }
    }
    for (int c = 0; c < p; ++c) y[idx[c]] = w[c];
  }
  for (int k = 0; k < n; ++k) rhs[order[k]] = y[k];
}

}  // namespace freeflex::detail
