#include "nodes/mesh/segment.h"

#include <algorithm>
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/kruskal_min_spanning_tree.hpp>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/sharp_edges.h"

namespace scallop {
namespace {

constexpr std::uint32_t kNone = UINT32_MAX;
// Two patches are not joined where the union's border would turn by more than this at an end of
// the side they share (a border turns about 11 degrees per quad on a 32-quad cylinder).
constexpr double kMaxJoinedBorderTurnDeg = 30;

// Connectivity of a manifold quad mesh, for walking straight along its edge lines.
struct QuadConnectivity {
  const Mesh& mesh;
  MeshEdges edges;
  std::vector<std::vector<std::uint32_t>> vertex_edges;
  std::vector<bool> boundary_vertex;

  explicit QuadConnectivity(const Mesh& m) : mesh(m), edges(mesh_edges(m)), vertex_edges(m.num_vertices()),
                                             boundary_vertex(m.num_vertices(), false) {
    for (std::uint32_t e = 0; e < edges.size(); ++e)
      for (auto v : edges.edges[e]) {
        vertex_edges[v].push_back(e);
        if (edges.is_boundary(e)) boundary_vertex[v] = true;
      }
  }
  std::uint32_t other(std::uint32_t e, std::uint32_t v) const {
    return edges.edges[e][0] == v ? edges.edges[e][1] : edges.edges[e][0];
  }
  bool share_face(std::uint32_t e, std::uint32_t g) const {
    for (std::size_t i = 0; i < edges.faces_on(e); ++i)
      for (std::size_t j = 0; j < edges.faces_on(g); ++j)
        if (edges.faces(e)[i] == edges.faces(g)[j]) return true;
    return false;
  }
  bool regular(std::uint32_t v) const { return !boundary_vertex[v] && vertex_edges[v].size() == 4; }
  bool extraordinary(std::uint32_t v) const {
    return !boundary_vertex[v] && !vertex_edges[v].empty() && vertex_edges[v].size() != 4;
  }
  // The edge at v straight on from e (the one sharing no face with it); kNone at a vertex that is
  // not a regular interior one, where "straight on" has no meaning.
  std::uint32_t straight_on(std::uint32_t v, std::uint32_t e) const {
    if (!regular(v)) return kNone;
    for (auto g : vertex_edges[v])
      if (g != e && !share_face(g, e)) return g;
    return kNone;
  }
};

struct Line {
  std::vector<std::uint32_t> vertices;  // edges.size() + 1
  std::vector<std::uint32_t> edges;
};

// Walks from v along e, then straight on, until stop(w) holds at the vertex w reached, there is
// no straight on, or the line comes back onto itself.
template <class Stop>
Line trace_line(const QuadConnectivity& q, std::uint32_t v, std::uint32_t e, Stop stop) {
  Line line{{v}, {}};
  std::vector<std::uint32_t> seen{v};
  while (true) {
    line.edges.push_back(e);
    const std::uint32_t w = q.other(e, v);
    line.vertices.push_back(w);
    if (std::find(seen.begin(), seen.end(), w) != seen.end() || stop(w)) break;
    seen.push_back(w);
    const std::uint32_t next = q.straight_on(w, e);
    if (next == kNone) break;
    v = w;
    e = next;
  }
  return line;
}

// The clipping edges: priority (1..7) of each mesh edge, 0 where it is not one.
struct Clipping {
  const QuadConnectivity& q;
  std::vector<std::uint8_t> priority;

  explicit Clipping(const QuadConnectivity& c) : q(c), priority(c.edges.size(), 0) {}
  bool at(std::uint32_t e) const { return priority[e] != 0; }
  void set(const std::vector<std::uint32_t>& edges, std::uint8_t p) {
    for (auto e : edges)
      if (!priority[e]) priority[e] = p;
  }
  std::size_t count_at(std::uint32_t v) const {
    std::size_t n = 0;
    for (auto e : q.vertex_edges[v]) n += at(e);
    return n;
  }
  // From v along e straight on until a vertex with a clipping edge, at priority p.
  void cut(std::uint32_t v, std::uint32_t e, std::uint8_t p) {
    set(trace_line(q, v, e, [&](std::uint32_t w) { return count_at(w) > 0; }).edges, p);
  }
};

// A connection line's piece between two vertices of the EPs' weighted graph.
struct Piece {
  std::uint32_t a, b;  // graph vertices
  std::vector<std::uint32_t> edges;
  double weight = 0;
  bool nf = false;
};

// Priorities 1 and 3 (and the statistics of the EP graph).
void cut_along_ep_graph(const QuadConnectivity& q, const std::vector<bool>& sharp, const SegmentOptions& o,
                        Clipping& clip, SegmentStats& stats) {
  const std::size_t nv = q.mesh.num_vertices();
  // Connection lines: from every EP along every edge, straight on; kept when they end at an EP.
  std::vector<std::uint32_t> line_of_edge(q.edges.size(), kNone);
  std::vector<Line> lines;
  for (std::uint32_t v = 0; v < nv; ++v) {
    if (!q.extraordinary(v)) continue;
    for (auto e : q.vertex_edges[v]) {
      if (line_of_edge[e] != kNone) continue;
      Line l = trace_line(q, v, e, [](std::uint32_t) { return false; });
      const std::uint32_t end = l.vertices.back();
      if (!q.extraordinary(end) || end == v) continue;
      for (auto g : l.edges) line_of_edge[g] = static_cast<std::uint32_t>(lines.size());
      lines.push_back(std::move(l));
    }
  }
  // Sharp edges on no connection line are "priori" sharp edges, like the mesh's boundary: a line
  // crossing one is dropped.
  std::vector<bool> touches_priori(nv, false);
  for (std::uint32_t e = 0; e < q.edges.size(); ++e)
    if (sharp[e] && line_of_edge[e] == kNone)
      for (auto v : q.edges.edges[e]) touches_priori[v] = true;
  std::vector<bool> kept(lines.size(), true);
  for (std::size_t i = 0; i < lines.size(); ++i)
    for (std::size_t k = 1; k + 1 < lines[i].vertices.size(); ++k)
      if (touches_priori[lines[i].vertices[k]]) kept[i] = false;
  std::vector<bool> in_graph(q.edges.size(), false);
  std::vector<int> passes(nv, 0);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (!kept[i]) {
      ++stats.dropped_connection_lines;
      continue;
    }
    ++stats.connection_lines;
    for (auto e : lines[i].edges) in_graph[e] = true;
    for (std::size_t k = 1; k + 1 < lines[i].vertices.size(); ++k) ++passes[lines[i].vertices[k]];
  }
  // Graph vertices: the EPs and the auxiliary vertices where two kept lines cross.
  std::vector<std::uint32_t> node(nv, kNone);
  std::uint32_t nodes = 0;
  for (std::uint32_t v = 0; v < nv; ++v) {
    if (q.extraordinary(v)) node[v] = nodes++;
    else if (passes[v] >= 2) {
      node[v] = nodes++;
      ++stats.auxiliary_vertices;
    }
  }
  // An NF piece: at one of its EP ends, an edge beside its first edge is in no connection line.
  auto beside_free = [&](std::uint32_t v, std::uint32_t e) {
    for (auto g : q.vertex_edges[v])
      if (g != e && q.share_face(g, e) && !in_graph[g]) return true;
    return false;
  };
  std::vector<Piece> pieces;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (!kept[i]) continue;
    const Line& l = lines[i];
    Piece p{node[l.vertices[0]], kNone, {}, 0, false};
    std::uint32_t start = 0;
    for (std::size_t k = 0; k < l.edges.size(); ++k) {
      const auto e = l.edges[k];
      const auto [a, b] = q.edges.edges[e];
      p.edges.push_back(e);
      p.weight += (sharp[e] ? o.sharp_coefficient : 1.0) * (q.mesh.vertices[a] - q.mesh.vertices[b]).norm();
      const std::uint32_t w = l.vertices[k + 1];
      if (node[w] == kNone) continue;
      p.b = node[w];
      const bool a_ep = q.extraordinary(l.vertices[start]), b_ep = q.extraordinary(w);
      if (!a_ep && !b_ep) p.weight *= o.auxiliary_coefficient;
      else if (a_ep && b_ep && (beside_free(l.vertices[start], p.edges.front()) || beside_free(w, p.edges.back()))) {
        p.nf = true;
        p.weight *= o.nf_coefficient;
      }
      pieces.push_back(std::move(p));
      p = Piece{node[w], kNone, {}, 0, false};
      start = static_cast<std::uint32_t>(k + 1);
    }
  }
  stats.graph_edges = pieces.size();
  // Kruskal's minimum spanning forest: one tree per connected weighted graph.
  using Graph = boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS, boost::no_property,
                                      boost::property<boost::edge_weight_t, double,
                                                      boost::property<boost::edge_index_t, std::size_t>>>;
  Graph g(nodes);
  for (std::size_t i = 0; i < pieces.size(); ++i)
    if (pieces[i].a != pieces[i].b) boost::add_edge(pieces[i].a, pieces[i].b, {pieces[i].weight, i}, g);
  std::vector<boost::graph_traits<Graph>::edge_descriptor> tree;
  boost::kruskal_minimum_spanning_tree(g, std::back_inserter(tree));
  const auto index = boost::get(boost::edge_index, g);
  for (const auto& te : tree) clip.set(pieces[index[te]].edges, 1);
  stats.mst_edges = tree.size();
  // Priority 2 comes between: the caller sets it; NF pieces are priority 3, set after it.
  for (auto& p : pieces)
    if (p.nf) {
      ++stats.nf_edges;
      for (auto e : p.edges)
        if (!clip.at(e)) clip.priority[e] = 3;  // overwritten by 2 where sharp (caller)
    }
}

// A rectangle of the quad grid: rows by cols vertices, (rows-1) by (cols-1) faces.
struct GridPatch {
  std::uint32_t rows = 0, cols = 0;
  std::vector<std::uint32_t> grid;   // rows * cols vertices
  std::vector<std::uint32_t> cells;  // (rows-1) * (cols-1) faces, cells[i * (cols-1) + j]
};

// Lays the region's faces out on the integer grid, each face a unit square, crossing only edges
// that are not clipping edges; the region is a rectangle when they tile one without overlap.
std::optional<GridPatch> rectangle_of(const QuadConnectivity& q, const Clipping& clip,
                                      const std::vector<std::uint32_t>& faces, const std::vector<int>& region_of,
                                      std::vector<std::array<Eigen::Vector2i, 4>>& corner) {
  const Mesh& m = q.mesh;
  const int region = region_of[faces[0]];
  std::vector<bool> placed(m.num_faces(), false);
  const std::uint32_t f0 = faces[0];
  corner[f0] = {Eigen::Vector2i(0, 0), Eigen::Vector2i(1, 0), Eigen::Vector2i(1, 1), Eigen::Vector2i(0, 1)};
  placed[f0] = true;
  std::vector<std::uint32_t> queue{f0};
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const std::uint32_t f = queue[head];
    const auto* fc = m.face(f);
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t e = q.edges.face_edge[m.face_start[f] + k];
      if (clip.at(e) || q.edges.faces_on(e) != 2) continue;
      const std::uint32_t g = q.edges.faces(e)[0] == f ? q.edges.faces(e)[1] : q.edges.faces(e)[0];
      if (region_of[g] != region) return std::nullopt;
      const std::uint32_t p = fc[k], pq = fc[(k + 1) % 4];
      const Eigen::Vector2i P = corner[f][k], Q = corner[f][(k + 1) % 4];
      const Eigen::Vector2i n = P - corner[f][(k + 3) % 4];
      const auto* gc = m.face(g);
      int mi = -1;
      for (int j = 0; j < 4; ++j)
        if (gc[j] == pq && gc[(j + 1) % 4] == p) mi = j;
      if (mi < 0) return std::nullopt;  // the faces disagree on orientation
      const std::array<Eigen::Vector2i, 4> want = {Q, P, P + n, Q + n};
      std::array<Eigen::Vector2i, 4> cg;
      for (int j = 0; j < 4; ++j) cg[(mi + j) % 4] = want[j];
      if (placed[g]) {
        if (corner[g] != cg) return std::nullopt;
        continue;
      }
      corner[g] = cg;
      placed[g] = true;
      queue.push_back(g);
    }
  }
  if (queue.size() != faces.size()) return std::nullopt;
  Eigen::Vector2i lo = corner[f0][0], hi = corner[f0][0];
  for (auto f : faces)
    for (const auto& c : corner[f]) {
      lo = lo.cwiseMin(c);
      hi = hi.cwiseMax(c);
    }
  const Eigen::Vector2i size = hi - lo;
  if (std::size_t(size.x()) * std::size_t(size.y()) != faces.size()) return std::nullopt;
  GridPatch p;
  p.cols = static_cast<std::uint32_t>(size.x()) + 1;
  p.rows = static_cast<std::uint32_t>(size.y()) + 1;
  p.grid.assign(std::size_t(p.rows) * p.cols, kNone);
  p.cells.assign(faces.size(), kNone);
  for (auto f : faces) {
    Eigen::Vector2i cell = corner[f][0];
    for (const auto& c : corner[f]) cell = cell.cwiseMin(c);
    cell -= lo;
    auto& slot = p.cells[std::size_t(cell.y()) * (p.cols - 1) + cell.x()];
    if (slot != kNone) return std::nullopt;
    slot = f;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2i c = corner[f][k] - lo;
      auto& v = p.grid[std::size_t(c.y()) * p.cols + c.x()];
      if (v != kNone && v != m.face(f)[k]) return std::nullopt;
      v = m.face(f)[k];
    }
  }
  return p;
}

// One further cut (priority 6) that brings a region that is not a rectangle closer to being
// one; false if none is found.
bool cut_towards_rectangle(const QuadConnectivity& q, Clipping& clip, const VertexFaces& vf,
                           const std::vector<std::uint32_t>& faces, const std::vector<int>& region_of) {
  const int region = region_of[faces[0]];
  std::vector<std::uint32_t> verts;
  for (auto f : faces) verts.insert(verts.end(), q.mesh.face(f), q.mesh.face(f) + 4);
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  std::optional<std::pair<std::uint32_t, std::uint32_t>> straight;
  for (auto v : verts) {
    // The region's faces at v and its free (not clipping) edges among them.
    std::size_t region_faces = 0;
    for (std::size_t i = 0; i < vf.count(v); ++i) region_faces += region_of[vf.faces(v)[i]] == region;
    std::vector<std::uint32_t> free_edges, clip_edges;
    for (auto e : q.vertex_edges[v]) {
      bool in_region = false;
      for (std::size_t i = 0; i < q.edges.faces_on(e); ++i) in_region |= region_of[q.edges.faces(e)[i]] == region;
      if (!in_region) continue;
      (clip.at(e) ? clip_edges : free_edges).push_back(e);
    }
    if (free_edges.empty()) continue;
    if (clip_edges.empty()) {
      // Inside the region: only an EP left inside is a defect; cut from it.
      if (q.extraordinary(v)) {
        clip.cut(v, free_edges[0], 6);
        return true;
      }
      continue;
    }
    // A concave corner (three or more of the region's faces between clipping edges): go on
    // straight from one of the clipping edges.
    if (region_faces >= 3) {
      for (auto c : clip_edges)
        for (auto e : free_edges)
          if (!q.share_face(e, c)) {
            clip.cut(v, e, 6);
            return true;
          }
    }
    if (!straight && region_faces == 2 && free_edges.size() == 1) straight = {v, free_edges[0]};
  }
  // No concave corner: a ring or a region touching itself; cut across from a straight border.
  if (straight) {
    clip.cut(straight->first, straight->second, 6);
    return true;
  }
  return false;
}

// Halves p across its longer side until every part is a height field (priority 7).
void split_to_height_fields(const GridPatch& p, const std::vector<Eigen::Vector3d>& face_normal, double min_dot,
                            const QuadConnectivity& q, Clipping& clip, std::vector<SegmentPatch>& out,
                            SegmentStats& stats) {
  std::vector<Eigen::Vector3d> normals;
  for (auto f : p.cells) normals.push_back(face_normal[f]);
  const auto [d, worst] = best_height_field_direction(normals);
  const std::uint32_t w = p.cols - 1, h = p.rows - 1;
  if (worst > min_dot || (w == 1 && h == 1)) {
    SegmentPatch s;
    s.direction = d;
    s.min_normal_dot = worst;
    s.faces = p.cells;
    s.rows = p.rows;
    s.cols = p.cols;
    s.grid = p.grid;
    out.push_back(std::move(s));
    return;
  }
  ++stats.height_field_splits;
  const bool across_cols = w >= h;
  const std::uint32_t cut = across_cols ? w / 2 : h / 2;
  GridPatch a, b;
  auto take = [&](GridPatch& part, std::uint32_t r0, std::uint32_t r1, std::uint32_t c0, std::uint32_t c1) {
    part.rows = r1 - r0 + 1;
    part.cols = c1 - c0 + 1;
    for (std::uint32_t i = r0; i <= r1; ++i)
      for (std::uint32_t j = c0; j <= c1; ++j) part.grid.push_back(p.grid[std::size_t(i) * p.cols + j]);
    for (std::uint32_t i = r0; i < r1; ++i)
      for (std::uint32_t j = c0; j < c1; ++j) part.cells.push_back(p.cells[std::size_t(i) * w + j]);
  };
  std::vector<std::uint32_t> line;
  if (across_cols) {
    take(a, 0, h, 0, cut);
    take(b, 0, h, cut, w);
    for (std::uint32_t i = 0; i < h; ++i)
      line.push_back(*q.edges.find(p.grid[std::size_t(i) * p.cols + cut], p.grid[std::size_t(i + 1) * p.cols + cut]));
  } else {
    take(a, 0, cut, 0, w);
    take(b, cut, h, 0, w);
    for (std::uint32_t j = 0; j < w; ++j)
      line.push_back(*q.edges.find(p.grid[std::size_t(cut) * p.cols + j], p.grid[std::size_t(cut) * p.cols + j + 1]));
  }
  clip.set(line, 7);
  split_to_height_fields(a, face_normal, min_dot, q, clip, out, stats);
  split_to_height_fields(b, face_normal, min_dot, q, clip, out, stats);
}

// A patch turned a quarter counter-clockwise in its (u, v) = (column, row) map, orientation kept:
// (u', v') = (v, cols - 1 - u), so its right side becomes its bottom.
SegmentPatch turned(const SegmentPatch& p) {
  SegmentPatch t = p;
  t.rows = p.cols;
  t.cols = p.rows;
  for (std::uint32_t i = 0; i < t.rows; ++i)
    for (std::uint32_t j = 0; j < t.cols; ++j) t.grid[std::size_t(i) * t.cols + j] = p.at(j, p.cols - 1 - i);
  for (std::uint32_t i = 0; i + 1 < t.rows; ++i)
    for (std::uint32_t j = 0; j + 1 < t.cols; ++j)
      t.faces[std::size_t(i) * (t.cols - 1) + j] = p.faces[std::size_t(j) * (p.cols - 1) + (p.cols - 2 - i)];
  return t;
}

// a and b side by side, when a whole side of a is a whole side of b and side_ok(a, b, its
// vertices) holds (a and b turned so that the side is a's last column and b's first); with the
// shared side's vertices.
template <class SideOk>
std::optional<std::pair<SegmentPatch, std::vector<std::uint32_t>>> joined(const SegmentPatch& a0,
                                                                           const SegmentPatch& b0, SideOk side_ok) {
  SegmentPatch a = a0;
  for (int ra = 0; ra < 4; ++ra, a = turned(a)) {
    SegmentPatch b = b0;
    for (int rb = 0; rb < 4; ++rb, b = turned(b)) {
      if (a.rows != b.rows) continue;
      std::vector<std::uint32_t> side;
      for (std::uint32_t i = 0; i < a.rows && a.at(i, a.cols - 1) == b.at(i, 0); ++i) side.push_back(a.at(i, a.cols - 1));
      if (side.size() != a.rows || !side_ok(a, b, side)) continue;
      SegmentPatch j;
      j.rows = a.rows;
      j.cols = a.cols + b.cols - 1;
      for (std::uint32_t i = 0; i < j.rows; ++i) {
        for (std::uint32_t c = 0; c < a.cols; ++c) j.grid.push_back(a.at(i, c));
        for (std::uint32_t c = 1; c < b.cols; ++c) j.grid.push_back(b.at(i, c));
      }
      for (std::uint32_t i = 0; i + 1 < j.rows; ++i) {
        for (std::uint32_t c = 0; c + 1 < a.cols; ++c) j.faces.push_back(a.faces[std::size_t(i) * (a.cols - 1) + c]);
        for (std::uint32_t c = 0; c + 1 < b.cols; ++c) j.faces.push_back(b.faces[std::size_t(i) * (b.cols - 1) + c]);
      }
      return std::make_pair(std::move(j), std::move(side));
    }
  }
  return std::nullopt;
}

// Joins neighbouring patches that share a whole side without a sharp edge on it while the union
// stays a height field with every n . d above min_dot, the best union first; the shared sides
// stop being clipping edges. Returns the number of joins.
std::size_t join_patches(std::vector<SegmentPatch>& patches, const std::vector<Eigen::Vector3d>& face_normal,
                         double min_dot, const QuadConnectivity& q, const std::vector<bool>& sharp, Clipping& clip) {
  std::size_t joins = 0;
  std::vector<bool> alive(patches.size(), true);
  std::vector<int> patch_of(q.mesh.num_faces(), -1);
  for (std::size_t i = 0; i < patches.size(); ++i)
    for (auto f : patches[i].faces) patch_of[f] = static_cast<int>(i);
  // The union's border runs on through the shared side's two ends: where it turns there (an
  // extraordinary point the two patches had as a corner), its B-spline border curve swings past
  // the turn and the surface folds over near it (a 63 degree turn on the domed block's top
  // turned normals upside down, and balls planned there were lifted 3 mm).
  const std::vector<Eigen::Vector3d>& x = q.mesh.vertices;
  auto straight_through = [&](std::uint32_t before, std::uint32_t at, std::uint32_t after) {
    const Eigen::Vector3d in = (x[at] - x[before]).normalized(), out = (x[after] - x[at]).normalized();
    return in.dot(out) >= std::cos(kMaxJoinedBorderTurnDeg * std::numbers::pi / 180);
  };
  auto side_ok = [&](const SegmentPatch& a, const SegmentPatch& b, const std::vector<std::uint32_t>& side) {
    for (std::size_t k = 1; k < side.size(); ++k)
      if (sharp[*q.edges.find(side[k - 1], side[k])]) return false;
    const std::uint32_t last = a.rows - 1;
    return straight_through(a.at(0, a.cols - 2), side.front(), b.at(0, 1)) &&
           straight_through(a.at(last, a.cols - 2), side.back(), b.at(last, 1));
  };
  // Candidate joins, dropped when either patch changes.
  using Join = std::optional<std::pair<SegmentPatch, std::vector<std::uint32_t>>>;
  std::map<std::pair<int, int>, Join> tried;
  auto evaluate = [&](int a, int b) -> const Join& {
    auto [it, added] = tried.try_emplace({a, b});
    if (!added) return it->second;
    if (auto j = joined(patches[a], patches[b], side_ok)) {
      std::vector<Eigen::Vector3d> normals;
      for (auto f : j->first.faces) normals.push_back(face_normal[f]);
      const auto [d, worst] = best_height_field_direction(normals);
      if (worst > min_dot) {
        j->first.direction = d;
        j->first.min_normal_dot = worst;
        it->second = std::move(j);
      }
    }
    return it->second;
  };
  while (true) {
    // Neighbouring pairs across non-sharp clipping edges.
    std::vector<std::pair<int, int>> pairs;
    for (std::uint32_t e = 0; e < q.edges.size(); ++e) {
      if (!clip.at(e) || sharp[e] || q.edges.faces_on(e) != 2) continue;
      int a = patch_of[q.edges.faces(e)[0]], b = patch_of[q.edges.faces(e)[1]];
      if (a == b) continue;
      pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    int best_a = -1, best_b = -1;
    double best = -2;
    for (auto [a, b] : pairs)
      if (const auto& j = evaluate(a, b); j && j->first.min_normal_dot > best) {
        best = j->first.min_normal_dot;
        best_a = a, best_b = b;
      }
    if (best_a < 0) break;
    auto [j, side] = *tried.at({best_a, best_b});
    for (std::size_t k = 1; k < side.size(); ++k) clip.priority[*q.edges.find(side[k - 1], side[k])] = 0;
    patches[best_a] = std::move(j);
    alive[best_b] = false;
    for (auto f : patches[best_a].faces) patch_of[f] = best_a;
    for (auto it = tried.begin(); it != tried.end();)
      it = (it->first.first == best_a || it->first.second == best_a || it->first.first == best_b ||
            it->first.second == best_b)
               ? tried.erase(it)
               : std::next(it);
    ++joins;
  }
  std::vector<SegmentPatch> kept;
  for (std::size_t i = 0; i < patches.size(); ++i)
    if (alive[i]) kept.push_back(std::move(patches[i]));
  patches = std::move(kept);
  return joins;
}

// Faces joined across edges that are not clipping edges: region id per face, and the faces of each.
std::vector<std::vector<std::uint32_t>> regions(const QuadConnectivity& q, const Clipping& clip,
                                                std::vector<int>& region_of) {
  const std::size_t nf = q.mesh.num_faces();
  region_of.assign(nf, -1);
  std::vector<std::vector<std::uint32_t>> out;
  for (std::uint32_t s = 0; s < nf; ++s) {
    if (region_of[s] >= 0) continue;
    const int r = static_cast<int>(out.size());
    out.push_back({s});
    region_of[s] = r;
    for (std::size_t head = 0; head < out[r].size(); ++head) {
      const std::uint32_t f = out[r][head];
      for (int k = 0; k < 4; ++k) {
        const std::uint32_t e = q.edges.face_edge[q.mesh.face_start[f] + k];
        if (clip.at(e)) continue;
        for (std::size_t i = 0; i < q.edges.faces_on(e); ++i) {
          const std::uint32_t g = q.edges.faces(e)[i];
          if (region_of[g] < 0) {
            region_of[g] = r;
            out[r].push_back(g);
          }
        }
      }
    }
  }
  return out;
}

void check_input(const Mesh& mesh, const MeshEdges& edges) {
  for (std::size_t f = 0; f < mesh.num_faces(); ++f)
    if (mesh.face_size(f) != 4)
      throw std::invalid_argument("face " + std::to_string(f) + " has " + std::to_string(mesh.face_size(f)) +
                                  " corners; the segmentation cuts a quad mesh (mesh.quad_remesh makes one)");
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (!edges.is_manifold(e))
      throw std::invalid_argument("edge " + std::to_string(edges.edges[e][0]) + "-" + std::to_string(edges.edges[e][1]) +
                                  " has " + std::to_string(edges.faces_on(e)) +
                                  " faces; the segmentation needs a manifold mesh (mesh.repair)");
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
    if (!mesh.vertices[v].allFinite())
      throw std::invalid_argument("vertex " + std::to_string(v) + " is not finite");
  if (mesh.num_faces() == 0) throw std::invalid_argument("the mesh has no faces");
}

}  // namespace

std::pair<Eigen::Vector3d, double> best_height_field_direction(const std::vector<Eigen::Vector3d>& normals) {
  std::vector<Eigen::Vector3d> n;
  for (const auto& v : normals)
    if (v.squaredNorm() > 0) n.push_back(v.normalized());
  if (n.empty()) return {Eigen::Vector3d::UnitZ(), 1.0};
  auto worst = [&](const Eigen::Vector3d& d) {
    double m = 2;
    for (const auto& v : n) m = std::min(m, v.dot(d));
    return m;
  };
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& v : n) c += v;
  Eigen::Vector3d best = c.norm() > 1e-12 ? c.normalized() : n[0];
  double best_min = worst(best);
  // Badoiu-Clarkson: the centre of the smallest ball holding the normals (points on the unit
  // sphere) is the axis of the smallest cap holding them.
  c = best;
  for (int k = 1; k <= 400; ++k) {
    std::size_t far = 0;
    double far_d = -1;
    for (std::size_t i = 0; i < n.size(); ++i)
      if (double d = (n[i] - c).squaredNorm(); d > far_d) {
        far_d = d;
        far = i;
      }
    c += (n[far] - c) / (k + 1.0);
    if (c.norm() < 1e-12) continue;
    const Eigen::Vector3d d = c.normalized();
    if (const double m = worst(d); m > best_min) {
      best_min = m;
      best = d;
    }
  }
  return {best, best_min};
}

Segments segment_shf(const Mesh& mesh, const SegmentOptions& o, SegmentStats* stats_out,
                     std::vector<std::uint8_t>* clipping_priority,
                     const std::function<void(double, const std::string&)>& progress) {
  auto say = [&](double f, const std::string& what) {
    if (progress) progress(f, what);
  };
  const QuadConnectivity q(mesh);
  check_input(mesh, q.edges);
  SegmentStats stats;
  for (std::uint32_t v = 0; v < mesh.num_vertices(); ++v) stats.extraordinary_points += q.extraordinary(v);
  const SharpEdges sharp_found = sharp_edges(mesh, q.edges, o.sharp_angle_deg);
  std::vector<bool> sharp(q.edges.size(), false);
  for (const auto& [a, b] : sharp_found.edges) sharp[*q.edges.find(a, b)] = true;
  stats.sharp_edges = sharp_found.edges.size();

  say(0.1, "the extraordinary points' graph");
  Clipping clip(q);
  cut_along_ep_graph(q, sharp, o, clip, stats);
  for (std::uint32_t e = 0; e < q.edges.size(); ++e)
    if (sharp[e] || q.edges.is_boundary(e))
      if (clip.priority[e] != 1) clip.priority[e] = 2;
  say(0.3, "extending sharp features and the extraordinary points' lines");
  for (std::uint32_t v = 0; v < mesh.num_vertices(); ++v) {
    if (!q.regular(v) || clip.count_at(v) != 1) continue;
    for (auto e : q.vertex_edges[v])
      if (clip.at(e)) {
        if (const auto on = q.straight_on(v, e); on != kNone && !clip.at(on)) clip.cut(v, on, 4);
        break;
      }
  }
  for (std::uint32_t v = 0; v < mesh.num_vertices(); ++v)
    if (q.extraordinary(v))
      for (auto e : q.vertex_edges[v])
        if (!clip.at(e)) clip.cut(v, e, 5);

  say(0.5, "cutting the regions into rectangles");
  const VertexFaces vf = vertex_faces(mesh);
  std::vector<int> region_of;
  std::vector<std::array<Eigen::Vector2i, 4>> corner(mesh.num_faces());
  std::vector<GridPatch> rects;
  for (std::size_t round = 0;; ++round) {
    if (round > q.edges.size()) throw std::runtime_error("the regions could not be cut into rectangles");
    const auto rs = regions(q, clip, region_of);
    rects.clear();
    bool all = true;
    for (const auto& faces : rs) {
      if (auto r = rectangle_of(q, clip, faces, region_of, corner)) {
        rects.push_back(std::move(*r));
        continue;
      }
      all = false;
      if (!cut_towards_rectangle(q, clip, vf, faces, region_of))
        throw std::runtime_error("a region of " + std::to_string(faces.size()) + " faces around face " +
                                 std::to_string(faces[0]) + " cannot be cut into rectangles of the quad grid");
    }
    if (all) break;
  }

  say(0.8, "halving what is not a height field");
  const FaceGeometry geometry = face_geometry(mesh);
  Segments out;
  for (const auto& r : rects) split_to_height_fields(r, geometry.normal, o.min_normal_dot, q, clip, out.patches, stats);
  if (o.join) {
    say(0.9, "joining neighbouring patches");
    stats.joins = join_patches(out.patches, geometry.normal, std::max(o.join_min_normal_dot, o.min_normal_dot), q,
                               sharp, clip);
  }
  // Patches in a stable order: by their smallest face.
  std::sort(out.patches.begin(), out.patches.end(), [](const SegmentPatch& a, const SegmentPatch& b) {
    return *std::min_element(a.faces.begin(), a.faces.end()) < *std::min_element(b.faces.begin(), b.faces.end());
  });
  out.mesh = mesh;
  out.mesh.feature_edges = sharp_found.edges;
  out.mesh.face_label.assign(mesh.num_faces(), -1);
  for (std::size_t i = 0; i < out.patches.size(); ++i)
    for (auto f : out.patches[i].faces) out.mesh.face_label[f] = static_cast<std::int32_t>(i);
  if (clipping_priority) clipping_priority->clear();
  for (std::uint32_t e = 0; e < q.edges.size(); ++e) {
    if (!clip.at(e)) continue;
    ++stats.clipping_by_priority[clip.priority[e]];
    out.clipping_edges.push_back(q.edges.edges[e]);
    if (clipping_priority) clipping_priority->push_back(clip.priority[e]);
  }
  if (stats_out) *stats_out = stats;
  say(1.0, "done");
  return out;
}

}  // namespace scallop
