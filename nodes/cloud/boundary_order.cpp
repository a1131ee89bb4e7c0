#include "nodes/cloud/boundary_order.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>

#include "nodes/cloud/knn.h"
#include "nodes/geom/best_fit_plane.h"
#include "nodes/geom/tangent_frame.h"

namespace scallop {

double projected_loop_area(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop,
                           const Eigen::Vector3d& c, const Eigen::Vector3d& n) {
  Eigen::Vector3d t1, t2;
  tangent_frame(n, t1, t2);
  double a = 0;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    Eigen::Vector3d p = P[loop[i]] - c, q = P[loop[(i + 1) % loop.size()]] - c;
    a += p.dot(t1) * q.dot(t2) - q.dot(t1) * p.dot(t2);
  }
  return 0.5 * a;
}

namespace {

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  bool unite(int a, int b) {
    a = find(a), b = find(b);
    if (a == b) return false;
    parent[a] = b;
    return true;
  }
};

struct Edge {
  int a, b;
  double len;
};

using TreeAdjacency = std::vector<std::vector<std::pair<int, double>>>;

// Farthest node from `src` in a tree (weighted), with parents for the path back and its distance
// in `length`; only through the nodes `in` marks when it is given.
int farthest(const TreeAdjacency& adj, int src, std::vector<int>& parent, double& length,
             const std::vector<char>* in = nullptr) {
  std::vector<double> dist(adj.size(), -1);
  parent.assign(adj.size(), -1);
  std::vector<int> stack{src};
  dist[src] = 0;
  int best = src;
  while (!stack.empty()) {
    int u = stack.back();
    stack.pop_back();
    if (dist[u] > dist[best]) best = u;
    for (auto [v, w] : adj[u])
      if (dist[v] < 0 && (!in || (*in)[v])) {
        dist[v] = dist[u] + w;
        parent[v] = u;
        stack.push_back(v);
      }
  }
  length = dist[best];
  return best;
}

// The longest path of the tree holding `src` (of the nodes `in` marks, when given), from one
// end to the other (the ends found by two sweeps), and its length.
std::vector<int> longest_path(const TreeAdjacency& adj, int src, double& length,
                              const std::vector<char>* in = nullptr) {
  std::vector<int> parent;
  const int b = farthest(adj, farthest(adj, src, parent, length, in), parent, length, in);
  std::vector<int> path;
  for (int v = b; v != -1; v = parent[v]) path.push_back(v);
  return path;
}

// One closed tour through all nodes of a tree (local ids 0..n-1, positions X).
// max_detour[v]: an off-path node joins the tour only if that lengthens it by at most this much
// (a few points deep in a noisy boundary band do; spurs towards false boundary points inside the
// patch, e.g. at sampling voids, do not, and stay off the loop together with their subtrees).
std::vector<int> tour_of_tree(const TreeAdjacency& adj, const std::vector<Eigen::Vector3d>& X,
                              const std::vector<double>& max_detour) {
  int n = static_cast<int>(adj.size());
  auto d = [&](int a, int b) { return (X[a] - X[b]).norm(); };
  // The longest path, as a circular doubly linked list closed from its last node to its first.
  double length;
  const std::vector<int> path = longest_path(adj, 0, length);
  std::vector<int> next(n, -1), prev(n, -1);
  for (std::size_t i = 0; i < path.size(); ++i) {
    next[path[i]] = path[(i + 1) % path.size()];
    prev[path[(i + 1) % path.size()]] = path[i];
  }
  // Off-path nodes, breadth first from the path, each next to its tree parent on the cheaper side.
  std::vector<char> seen(n, 0);
  for (int v : path) seen[v] = 1;
  int count = static_cast<int>(path.size());
  std::vector<int> left_out;  // the first node of each subtree left out
  auto insert_from = [&](std::deque<int> queue) {
    while (!queue.empty()) {
      int p = queue.front();
      queue.pop_front();
      for (auto [x, w] : adj[p]) {
        if (seen[x]) continue;
        seen[x] = 1;
        int nx = next[p], pv = prev[p];
        double after = d(p, x) + d(x, nx) - d(p, nx);
        double before = d(pv, x) + d(x, p) - d(pv, p);
        if (std::min(after, before) > max_detour[x]) {  // a spur: leave it (and its subtree) out
          left_out.push_back(x);
          continue;
        }
        ++count;
        if (after <= before) {
          next[p] = x, prev[x] = p, next[x] = nx, prev[nx] = x;
        } else {
          next[pv] = x, prev[x] = pv, next[x] = p, prev[p] = x;
        }
        queue.push_back(x);
      }
    }
  };
  insert_from(std::deque<int>(path.begin(), path.end()));
  // A subtree left out may be a stretch of the loop itself, not a spur: where the loop's points
  // leave two gaps, its tree is cut open twice and a stretch hangs off the longest path by one
  // end (on a scanned bunny, 117 points along its back hung at the ear's base, and the loop
  // took a 62 mm shortcut across the part). Such a stretch, at least three long links (two
  // radii) long, goes into the tour along its own longest path where that costs least, when
  // joining its two ends there adds at most one long link.
  std::vector<char> in_piece(n, 0);
  for (std::size_t k = 0; k < left_out.size(); ++k) {
    std::vector<int> piece{left_out[k]};  // the subtree: off the tour, through unseen nodes
    in_piece[left_out[k]] = 1;
    for (std::size_t i = 0; i < piece.size(); ++i)
      for (auto [y, w] : adj[piece[i]])
        if (!in_piece[y] && !seen[y]) in_piece[y] = 1, piece.push_back(y);
    // (three long links take four points at least: a spur of a few is passed over at once)
    double length = 0;
    std::vector<int> stretch;
    if (piece.size() >= 4) stretch = longest_path(adj, left_out[k], length, &in_piece);
    for (int v : piece) in_piece[v] = 0;
    if (stretch.empty()) continue;
    const int e1 = stretch.back(), e2 = stretch.front();
    const double reach = 2 * std::max(max_detour[e1], max_detour[e2]);
    if (length < 3 * reach) continue;
    double best = INFINITY;
    int at = -1;
    bool reversed = false;
    for (int u = 0; u < n; ++u) {
      if (next[u] < 0) continue;
      const int v = next[u];
      const double forward = d(u, e2) + d(e1, v) - d(u, v), backward = d(u, e1) + d(e2, v) - d(u, v);
      if (std::min(forward, backward) < best) best = std::min(forward, backward), at = u, reversed = backward < forward;
    }
    if (at < 0 || best > reach) continue;
    // the stretch e2 ... e1, spliced in between at and next[at]
    if (reversed) std::reverse(stretch.begin(), stretch.end());
    int p = at;
    const int end = next[at];
    for (int v : stretch) next[p] = v, prev[v] = p, p = v, seen[v] = 1, ++count;
    next[p] = end, prev[end] = p;
    // the rest of the subtree as before, from the stretch (its nodes are still unseen)
    for (int v : piece)
      if (next[v] < 0) seen[v] = 0;
    insert_from(std::deque<int>(stretch.begin(), stretch.end()));
  }
  std::vector<int> t;
  t.reserve(count);
  int v = path[0];
  do {
    t.push_back(v);
    v = next[v];
  } while (v != path[0] && static_cast<int>(t.size()) <= count);
  n = static_cast<int>(t.size());

  // Windowed 2-opt: reverse t[i+1..j] when that shortens the tour (local crossings, zig-zags).
  const int window = std::min(16, n - 2);
  for (int pass = 0; pass < 20; ++pass) {
    bool improved = false;
    for (int i = 0; i < n; ++i)
      for (int s = 2; s <= window; ++s) {
        int j = (i + s) % n;
        int i1 = (i + 1) % n, j1 = (j + 1) % n;
        double gain = d(t[i], t[i1]) + d(t[j], t[j1]) - d(t[i], t[j]) - d(t[i1], t[j1]);
        if (gain > 1e-12) {
          for (int lo = i1, hi = j, c = 0; c < s / 2; ++c) {  // s elements in i+1..j
            std::swap(t[lo], t[hi]);
            lo = (lo + 1) % n;
            hi = (hi + n - 1) % n;
          }
          improved = true;
        }
      }
    if (!improved) break;
  }
  return t;
}

// Pieces of the boundary joined by links no longer than a neighbourhood radius, each point's
// piece (`id`) and what that piece is (`kind`): a closed loop when it has at least
// min_loop_points points whose longest path (in the spanning tree of those links) runs at least
// three long links (two radii) around and ends within one of where it starts; an open one when it
// runs that far but does not close (a loop whose boundary points leave gaps wider than a radius);
// none (a few stray points). A hole 2 mm from the outline of a 50 000-point plane (spacing 0.44
// mm, radius 0.78) was joined to the outline by a long link of 1.3-1.6 mm.
enum : char { kNoLoop, kOpenLoop, kClosedLoop };
struct Pieces {
  std::vector<int> id;
  std::vector<char> kind;
};
Pieces pieces_by_short_links(const std::vector<Eigen::Vector3d>& X, const std::vector<double>& radius,
                             const std::vector<Edge>& edges, int min_loop_points) {
  const int nb = static_cast<int>(X.size());
  UnionFind uf(nb);
  TreeAdjacency adj(nb);
  for (const Edge& e : edges)
    if (e.len <= std::max(radius[e.a], radius[e.b]) && uf.unite(e.a, e.b)) {
      adj[e.a].push_back({e.b, e.len});
      adj[e.b].push_back({e.a, e.len});
    }
  Pieces out{std::vector<int>(nb), std::vector<char>(nb, kNoLoop)};
  std::vector<std::vector<int>> members(nb);
  for (int i = 0; i < nb; ++i) members[out.id[i] = uf.find(i)].push_back(i);
  for (const auto& piece : members) {
    if (static_cast<int>(piece.size()) < std::max(min_loop_points, 3)) continue;
    double reach = 0;
    for (int i : piece) reach = std::max(reach, 2 * radius[i]);
    double around;
    const std::vector<int> path = longest_path(adj, piece[0], around);
    if (around < 3 * reach) continue;
    const char kind = (X[path.front()] - X[path.back()]).norm() <= reach ? kClosedLoop : kOpenLoop;
    for (int i : piece) out.kind[i] = kind;
  }
  return out;
}

// A stretch of a loop cut off from the rest by gaps wider than two radii at both its ends is a
// tree of its own, whose tour runs along it and back: it encloses nearly nothing and was dropped
// as a sampling void, and the loop cut across the part between the gaps. Such a piece (under its
// min_area, its tree's longest path ending at least three long links from where it starts, where
// a void's closes within one) is spliced, along that path, into the loop where joining its two
// ends costs least, when that adds at most one long link and the loop then encloses more; its
// own loop is then left empty.
// B: the boundary points' indices into P, radius: their neighbourhood radii; stretches: per loop,
// its tree's longest path (indices into P) or nothing; loops, areas and min_area as
// order_boundary_loops builds them (each loop counter-clockwise).
void splice_cut_off_stretches(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& B,
                              const std::vector<double>& radius, const std::vector<std::vector<int>>& stretches,
                              std::vector<std::vector<int>>& loops, std::vector<double>& areas,
                              const std::vector<double>& min_area, const Eigen::Vector3d& c0, const Eigen::Vector3d& n0) {
  if (std::all_of(stretches.begin(), stretches.end(), [](const auto& s) { return s.size() < 2; })) return;
  std::vector<double> radius_of(P.size(), 0);
  for (std::size_t i = 0; i < B.size(); ++i) radius_of[B[i]] = radius[i];
  auto d = [&](int a, int b) { return (P[a] - P[b]).norm(); };
  for (std::size_t k = 0; k < loops.size(); ++k) {
    std::vector<int> stretch = stretches[k];
    if (stretch.size() < 2) continue;
    const int first = stretch.front(), last = stretch.back();
    const double reach = 2 * std::max(radius_of[first], radius_of[last]);
    if (d(first, last) < 3 * reach) continue;
    double best = INFINITY;
    std::size_t into = 0, after = 0;
    bool reversed = false;
    for (std::size_t m = 0; m < loops.size(); ++m) {
      if (m == k || loops[m].empty() || areas[m] < min_area[m]) continue;
      const std::vector<int>& L = loops[m];
      for (std::size_t j = 0; j < L.size(); ++j) {
        const int u = L[j], v = L[(j + 1) % L.size()];
        const double forward = d(u, first) + d(last, v) - d(u, v), backward = d(u, last) + d(first, v) - d(u, v);
        if (std::min(forward, backward) < best) best = std::min(forward, backward), into = m, after = j, reversed = backward < forward;
      }
    }
    if (best > reach) continue;
    if (reversed) std::reverse(stretch.begin(), stretch.end());
    std::vector<int> joined = loops[into];
    joined.insert(joined.begin() + after + 1, stretch.begin(), stretch.end());
    const double area = projected_loop_area(P, joined, c0, n0);
    if (!(area > areas[into])) continue;  // it was cut across: joined, the loop encloses more
    loops[into].swap(joined);
    areas[into] = area;
    loops[k].clear();
    areas[k] = 0;
  }
}

}  // namespace

std::vector<std::vector<int>> order_boundary_loops(const std::vector<Eigen::Vector3d>& P,
                                                   const std::vector<Eigen::Vector3d>& N,
                                                   const Neighborhoods& nbrs,
                                                   const std::vector<std::uint8_t>& is_boundary,
                                                   int min_loop_points) {
  const std::size_t np = P.size();
  if (is_boundary.size() != np)
    throw std::invalid_argument("the boundary flags are for " + std::to_string(is_boundary.size()) +
                                " points but the cloud has " + std::to_string(np));
  if (nbrs.size() != np || nbrs.k < 1)
    throw std::invalid_argument("the neighbourhoods are for " + std::to_string(nbrs.size()) +
                                " points but the cloud has " + std::to_string(np));
  if (!N.empty() && N.size() != np)
    throw std::invalid_argument("the cloud has " + std::to_string(N.size()) + " normals for " +
                                std::to_string(np) + " points");
  std::vector<int> B;
  for (std::size_t i = 0; i < np; ++i)
    if (is_boundary[i]) B.push_back(static_cast<int>(i));
  if (B.empty())
    throw std::invalid_argument(
        "no boundary points found: the cloud looks closed (a 3-axis finishing path needs an open patch)");
  const int nb = static_cast<int>(B.size());

  // Link graph among boundary points.
  std::vector<Eigen::Vector3d> X(nb);
  std::vector<double> radius(nb);
  for (int i = 0; i < nb; ++i) {
    X[i] = P[B[i]];
    radius[i] = std::sqrt(nbrs.sq_dist(B[i], nbrs.k - 1));
  }
  std::vector<Edge> edges;
  if (nb > 1) {
    KnnIndex index(X);
    std::vector<int> idx;
    std::vector<double> sq;
    const int m = std::min(8, nb - 1);
    for (int i = 0; i < nb; ++i) {
      index.query(X[i], m, idx, sq, i);
      for (std::size_t j = 0; j < idx.size(); ++j) {
        double len = std::sqrt(sq[j]);
        if (len <= 2 * std::max(radius[i], radius[idx[j]])) edges.push_back({i, idx[j], len});
      }
    }
  }
  // Minimum spanning forest (Kruskal).
  std::sort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) {
    return a.len != b.len ? a.len < b.len : std::tie(a.a, a.b) < std::tie(b.a, b.b);
  });
  const Pieces pieces = pieces_by_short_links(X, radius, edges, min_loop_points);
  UnionFind uf(nb);
  std::vector<Edge> tree;
  for (const Edge& e : edges) {
    // A long link from a loop that closes without long links to another loop's piece is a
    // shortcut across the part (a hole near the outline), not a gap in one loop's points.
    const char ka = pieces.kind[e.a], kb = pieces.kind[e.b];
    if (e.len > std::max(radius[e.a], radius[e.b]) && pieces.id[e.a] != pieces.id[e.b] &&
        std::max(ka, kb) == kClosedLoop && std::min(ka, kb) != kNoLoop)
      continue;
    if (uf.unite(e.a, e.b)) tree.push_back(e);
  }

  // Components, with local ids.
  std::vector<int> comp_of(nb, -1), local(nb, -1);
  std::vector<std::vector<int>> comps;
  for (int i = 0; i < nb; ++i) {
    int r = uf.find(i);
    if (comp_of[r] < 0) {
      comp_of[r] = static_cast<int>(comps.size());
      comps.emplace_back();
    }
    local[i] = static_cast<int>(comps[comp_of[r]].size());
    comps[comp_of[r]].push_back(i);
  }
  std::vector<TreeAdjacency> adj(comps.size());
  for (std::size_t c = 0; c < comps.size(); ++c) adj[c].resize(comps[c].size());
  for (const Edge& e : tree) {
    int c = comp_of[uf.find(e.a)];
    adj[c][local[e.a]].push_back({local[e.b], e.len});
    adj[c][local[e.b]].push_back({local[e.a], e.len});
  }

  Eigen::Vector3d c0, n0;
  best_fit_plane(P, N, c0, n0);
  std::vector<std::vector<int>> loops;
  std::vector<double> areas, min_area;
  std::vector<std::vector<int>> stretches;  // per loop: its tree's longest path, where it encloses nearly nothing
  for (std::size_t c = 0; c < comps.size(); ++c) {
    if (static_cast<int>(comps[c].size()) < std::max(min_loop_points, 3)) continue;
    std::vector<Eigen::Vector3d> Xc(comps[c].size());
    std::vector<double> rc(comps[c].size());
    for (std::size_t j = 0; j < comps[c].size(); ++j) Xc[j] = X[comps[c][j]], rc[j] = radius[comps[c][j]];
    std::vector<int> t = tour_of_tree(adj[c], Xc, rc);
    if (static_cast<int>(t.size()) < std::max(min_loop_points, 3)) continue;
    std::vector<int> loop(t.size());
    for (std::size_t j = 0; j < t.size(); ++j) loop[j] = B[comps[c][t[j]]];
    double a = projected_loop_area(P, loop, c0, n0);
    if (a < 0) {
      std::reverse(loop.begin(), loop.end());
      a = -a;
    }
    double mean_radius = 0;
    for (double r : rc) mean_radius += r;
    mean_radius /= static_cast<double>(rc.size());
    loops.push_back(std::move(loop));
    areas.push_back(a);
    min_area.push_back(std::numbers::pi * 4 * mean_radius * mean_radius);
    // a piece enclosing nearly nothing may be a stretch of a loop, cut off by gaps at both ends
    std::vector<int> path;
    if (a < min_area.back()) {
      double length;
      for (int v : longest_path(adj[c], 0, length)) path.push_back(B[comps[c][v]]);
    }
    stretches.push_back(std::move(path));
  }
  splice_cut_off_stretches(P, B, radius, stretches, loops, areas, min_area, c0, n0);
  if (loops.empty())
    throw std::invalid_argument("no boundary loop found: the " + std::to_string(nb) +
                                " boundary points form only pieces of fewer than min_loop_points = " +
                                std::to_string(min_loop_points) + " points");
  // Outer loop first (largest enclosed area), then holes by decreasing area, reversed (clockwise).
  std::vector<std::size_t> order(loops.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return areas[a] > areas[b]; });
  std::vector<std::vector<int>> out;
  for (std::size_t j = 0; j < order.size(); ++j) {
    // A "hole" narrower than two neighbourhood radii is a sampling void, not a feature of the part.
    if (loops[order[j]].empty() || (j > 0 && areas[order[j]] < min_area[order[j]])) continue;
    out.push_back(std::move(loops[order[j]]));
    if (j > 0) std::reverse(out.back().begin(), out.back().end());
  }
  return out;
}

}  // namespace scallop
