// The symbolic part of the sparse LDLᵀ: approximate minimum degree order (Eigen's port of
// AMD), elimination tree in postorder, column counts, fundamental supernodes and their
// relaxed amalgamation (merging a child into its parent when few explicit zeros result,
// which turns many tiny fronts into fewer dense ones).
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "trajopt/sparse_ldlt.hpp"

namespace freeflex::detail {
namespace {

/// The symmetric pattern without its diagonal: adjacency lists, each neighbour once.
struct Graph {
  std::vector<int> ptr, adj;
};

Graph graph(int n, long long nz, const int* rows, const int* cols, int base) {
  Graph g;
  g.ptr.assign(n + 1, 0);
  for (long long k = 0; k < nz; ++k) {
    const int i = rows[k] - base, j = cols[k] - base;
    if (i < 0 || i >= n || j < 0 || j >= n)
      throw std::invalid_argument("sparse LDLT: entry " + std::to_string(k) + " at (" + std::to_string(rows[k]) + ", " +
                                  std::to_string(cols[k]) + ") outside the " + std::to_string(n) + " x " +
                                  std::to_string(n) + " matrix");
    if (i != j) ++g.ptr[i + 1], ++g.ptr[j + 1];
  }
  for (int i = 0; i < n; ++i) g.ptr[i + 1] += g.ptr[i];
  std::vector<int> next(g.ptr.begin(), g.ptr.end() - 1), mark(n, -1);
  g.adj.resize(g.ptr[n]);
  for (long long k = 0; k < nz; ++k) {
    const int i = rows[k] - base, j = cols[k] - base;
    if (i != j) g.adj[next[i]++] = j, g.adj[next[j]++] = i;
  }
  // drop repeated neighbours in place
  int out = 0;
  for (int i = 0; i < n; ++i) {
    const int b = g.ptr[i], e = g.ptr[i + 1];
    g.ptr[i] = out;
    for (int t = b; t < e; ++t)
      if (mark[g.adj[t]] != i) mark[g.adj[t]] = i, g.adj[out++] = g.adj[t];
  }
  g.ptr[n] = out;
  g.adj.resize(out);
  return g;
}

/// Strictly upper pattern of P A Pᵀ by columns (rows < column), pos[i] the position of i.
struct UpperPattern {
  std::vector<int> colptr, rows;
};

UpperPattern upper_pattern(const Graph& g, const std::vector<int>& pos) {
  const int n = static_cast<int>(pos.size());
  UpperPattern u;
  u.colptr.assign(n + 1, 0);
  for (int i = 0; i < n; ++i)
    for (int t = g.ptr[i]; t < g.ptr[i + 1]; ++t)
      if (pos[g.adj[t]] < pos[i]) ++u.colptr[pos[i] + 1];
  for (int k = 0; k < n; ++k) u.colptr[k + 1] += u.colptr[k];
  u.rows.resize(u.colptr[n]);
  std::vector<int> next(u.colptr.begin(), u.colptr.end() - 1);
  for (int i = 0; i < n; ++i)
    for (int t = g.ptr[i]; t < g.ptr[i + 1]; ++t)
      if (pos[g.adj[t]] < pos[i]) u.rows[next[pos[i]]++] = pos[g.adj[t]];
  return u;
}

/// Elimination tree (Liu's algorithm with path compression).
std::vector<int> etree(int n, const UpperPattern& u) {
  std::vector<int> parent(n, -1), ancestor(n, -1);
  for (int k = 0; k < n; ++k)
    for (int p = u.colptr[k]; p < u.colptr[k + 1]; ++p)
      for (int i = u.rows[p]; i != -1 && i < k;) {
        const int next = ancestor[i];
        ancestor[i] = k;
        if (next == -1) parent[i] = k;
        i = next;
      }
  return parent;
}

/// A postorder of the forest: post[k] is the node visited k-th (children before parents,
/// siblings in increasing order).
std::vector<int> postorder(const std::vector<int>& parent) {
  const int n = static_cast<int>(parent.size());
  std::vector<int> head(n, -1), next(n, -1), post, stack;
  post.reserve(n);
  for (int j = n - 1; j >= 0; --j)
    if (parent[j] != -1) next[j] = head[parent[j]], head[parent[j]] = j;
  for (int root = 0; root < n; ++root) {
    if (parent[root] != -1) continue;
    stack.push_back(root);
    while (!stack.empty()) {
      const int p = stack.back();
      if (head[p] == -1) {
        stack.pop_back();
        post.push_back(p);
      } else {
        const int child = head[p];
        head[p] = next[child];
        stack.push_back(child);
      }
    }
  }
  return post;
}

long long entries(long long ncols, long long front) { return ncols * front - ncols * (ncols - 1) / 2; }

}  // namespace

LdltSymbolic ldlt_analyse(int n, long long nz, const int* rows, const int* cols, int base) {
  if (n < 0 || nz < 0) throw std::invalid_argument("sparse LDLT: negative size");
  const Graph g = graph(n, nz, rows, cols, base);
  LdltSymbolic s;
  s.n = n;
  if (n == 0) {
    s.sn_start = {0};
    return s;
  }
  // AMD on the symmetric pattern with every diagonal present (Eigen's AMD orders a node
  // without a structural diagonal last, as if it were dense: the constraint rows of a
  // KKT matrix have none).
  {
    Eigen::SparseMatrix<double, Eigen::ColMajor, int> pattern(n, n);
    pattern.resizeNonZeros(g.ptr[n] + n);
    int* outer = pattern.outerIndexPtr();
    int* inner = pattern.innerIndexPtr();
    for (int i = 0, at = 0; i < n; ++i) {
      outer[i] = at;
      inner[at++] = i;
      for (int t = g.ptr[i]; t < g.ptr[i + 1]; ++t) inner[at++] = g.adj[t];
      std::sort(inner + outer[i], inner + at);
    }
    outer[n] = g.ptr[n] + n;
    std::fill(pattern.valuePtr(), pattern.valuePtr() + g.ptr[n] + n, 1.0);
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
    Eigen::internal::minimum_degree_ordering(pattern, perm);
    s.order.assign(perm.indices().data(), perm.indices().data() + n);  // position -> variable
  }
  std::vector<int> pos(n);
  for (int k = 0; k < n; ++k) pos[s.order[k]] = k;

  // Postorder the elimination tree (the same fill), then work in that order.
  {
    const std::vector<int> post = postorder(etree(n, upper_pattern(g, pos)));
    std::vector<int> order(n);
    for (int k = 0; k < n; ++k) order[k] = s.order[post[k]];
    s.order = std::move(order);
    for (int k = 0; k < n; ++k) pos[s.order[k]] = k;
  }
  const UpperPattern u = upper_pattern(g, pos);
  const std::vector<int> parent = etree(n, u);

  // Column counts of L (diagonal included) from the row subtrees.
  std::vector<int> count(n, 1), mark(n, -1), children(n, 0);
  for (int k = 0; k < n; ++k) {
    mark[k] = k;
    for (int p = u.colptr[k]; p < u.colptr[k + 1]; ++p)
      for (int j = u.rows[p]; mark[j] != k; j = parent[j]) ++count[j], mark[j] = k;
    if (parent[k] != -1) ++children[parent[k]];
  }

  // Fundamental supernodes: j joins j - 1's when j is its only child's parent and the
  // columns nest.
  std::vector<int> start, ncols, front;
  std::vector<long long> zeros;
  for (int j = 0; j < n; ++j) {
    const bool joins = j > 0 && parent[j - 1] == j && children[j] == 1 && count[j - 1] == count[j] + 1;
    if (joins) {
      ++ncols.back();
    } else {
      start.push_back(j);
      ncols.push_back(1);
      front.push_back(count[j]);
      zeros.push_back(0);
    }
  }
  const int nsn = static_cast<int>(start.size());
  std::vector<int> sn_of(n);
  for (int t = 0; t < nsn; ++t)
    for (int j = start[t]; j < start[t] + ncols[t]; ++j) sn_of[j] = t;
  std::vector<int> sn_parent(nsn, -1), rep(nsn);
  for (int t = 0; t < nsn; ++t) {
    const int last = start[t] + ncols[t] - 1;
    sn_parent[t] = parent[last] == -1 ? -1 : sn_of[parent[last]];
    rep[t] = t;
  }
  auto find = [&rep](int t) {
    while (rep[t] != t) t = rep[t] = rep[rep[t]];
    return t;
  };

  // Relaxed amalgamation, children first: merge t into its parent when the merged front
  // holds few explicit zeros (CHOLMOD's default rule: any merge up to 4 columns, up to 80%
  // zeros to 16 columns, 10% to 48, 5% beyond; and a child of at most 4 columns up to 50%,
  // since a front of its own costs more than the zeros). Any child may merge, not only the one just
  // before its parent: its columns then move next to the parent's (t's rows lie in the
  // parent's front, so the fill is the same), which gathers the many one- and two-column
  // leaves of a KKT matrix (slacks, controls) into their parents' fronts.
  std::vector<char> alive(nsn, 1);
  std::vector<std::vector<int>> members(nsn);
  for (int t = 0; t < nsn; ++t) members[t] = {t};
  std::vector<int> merged_cols = ncols;
  for (int t = 0; t < nsn; ++t) {
    if (sn_parent[t] == -1) continue;
    const int p = find(sn_parent[t]);
    const long long nc = merged_cols[t] + merged_cols[p], m = merged_cols[t] + front[p];
    const long long z = entries(nc, m) - entries(merged_cols[t], front[t]) - entries(merged_cols[p], front[p]) +
                        zeros[t] + zeros[p];
    const double frac = static_cast<double>(z) / static_cast<double>(entries(nc, m));
    const bool merge = (merged_cols[t] <= 4 && frac < 0.5) || nc <= 4 || (nc <= 16 && frac < 0.8) || (nc <= 48 && frac < 0.1) || frac < 0.05;
    if (!merge) continue;
    merged_cols[p] = static_cast<int>(nc);
    front[p] = static_cast<int>(m);
    zeros[p] = z;
    alive[t] = 0;
    rep[t] = p;
    members[p].insert(members[p].end(), members[t].begin(), members[t].end());
    members[t].clear();
  }
  // The merged tree in postorder: each node's children, then its members' columns (in
  // their former order).
  std::vector<std::vector<int>> kids(nsn);
  std::vector<int> roots;
  for (int t = 0; t < nsn; ++t) {
    if (!alive[t]) continue;
    if (sn_parent[t] == -1)
      roots.push_back(t);
    else
      kids[find(sn_parent[t])].push_back(t);
  }
  std::vector<int> order, renumber(nsn, -1);
  order.reserve(n);
  std::vector<std::pair<int, std::size_t>> stack;
  for (int root : roots) {
    stack.emplace_back(root, 0);
    while (!stack.empty()) {
      auto& [t, next] = stack.back();
      if (next < kids[t].size()) {
        const int child = kids[t][next++];
        stack.emplace_back(child, 0);
        continue;
      }
      renumber[t] = static_cast<int>(s.sn_start.size());
      s.sn_start.push_back(static_cast<int>(order.size()));
      std::sort(members[t].begin(), members[t].end());
      for (int f : members[t])
        for (int j = start[f]; j < start[f] + ncols[f]; ++j) order.push_back(s.order[j]);
      s.factor_doubles += static_cast<long long>(front[t]) * merged_cols[t];
      s.factor_ints += 3 + 2 + front[t] + merged_cols[t];  // table entry and record (sparse_ldlt_factor.cpp)
      s.max_front = std::max(s.max_front, front[t]);
      stack.pop_back();
    }
  }
  s.sn_parent.assign(s.sn_start.size(), -1);
  for (int t = 0; t < nsn; ++t)
    if (alive[t] && sn_parent[t] != -1) s.sn_parent[renumber[t]] = renumber[find(sn_parent[t])];
  s.sn_start.push_back(n);
  s.order = std::move(order);
  s.factor_ints += 4 + n;  // header and order
  ldlt_map_columns(s, nz, rows, cols, base);
  return s;
}

void ldlt_map_columns(LdltSymbolic& s, long long nz, const int* rows, const int* cols, int base) {
  const int n = s.n;
  std::vector<int> pos(n);
  for (int k = 0; k < n; ++k) pos[s.order[k]] = k;
  s.colptr.assign(n + 1, 0);
  for (long long t = 0; t < nz; ++t) ++s.colptr[std::min(pos[rows[t] - base], pos[cols[t] - base]) + 1];
  for (int k = 0; k < n; ++k) s.colptr[k + 1] += s.colptr[k];
  s.row.resize(static_cast<std::size_t>(nz));
  s.slot.resize(static_cast<std::size_t>(nz));
  s.source.resize(static_cast<std::size_t>(nz));
  std::vector<int> next(s.colptr.begin(), s.colptr.end() - 1);
  for (long long t = 0; t < nz; ++t) {
    const int pi = pos[rows[t] - base], pj = pos[cols[t] - base];
    const int at = next[std::min(pi, pj)]++;
    s.row[at] = std::max(pi, pj);
    s.slot[t] = at;
    s.source[at] = static_cast<int>(t);
  }
}

}  // namespace freeflex::detail
