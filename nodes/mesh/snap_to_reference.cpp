#include "nodes/mesh/snap_to_reference.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "nodes/geom/cell_hash_3d.h"
#include "nodes/geom/segment.h"
#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_distance.h"
#include "nodes/mesh/mesh_topology.h"

namespace scallop {
namespace {

using Edge = std::array<std::uint32_t, 2>;

// The given feature edges and the mesh's border edges, each once, as (a < b).
std::vector<Edge> features_and_borders(const MeshEdges& edges, const std::vector<Edge>& given) {
  std::vector<Edge> out;
  for (Edge e : given) out.push_back({std::min(e[0], e[1]), std::max(e[0], e[1])});
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges.is_boundary(e)) out.push_back({std::min(edges.edges[e][0], edges.edges[e][1]), std::max(edges.edges[e][0], edges.edges[e][1])});
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<int> degrees(std::size_t vertices, const std::vector<Edge>& edges) {
  std::vector<int> d(vertices, 0);
  for (Edge e : edges) ++d[e[0]], ++d[e[1]];
  return d;
}

// Pieces of segments, none longer than a cell, filed by the cells their bounding boxes touch:
// a piece within one cell's width of a point is filed in one of the point's 27 neighbouring cells.
class SegmentGrid {
 public:
  explicit SegmentGrid(double cell) : cells_(cell) {}

  void add(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / cells_.cell())));
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d p = a + (b - a) * (double(k) / n), q = a + (b - a) * (double(k + 1) / n);
      const auto lo = cells_.key(p.cwiseMin(q)), hi = cells_.key(p.cwiseMax(q));
      for (auto i = lo[0]; i <= hi[0]; ++i)
        for (auto j = lo[1]; j <= hi[1]; ++j)
          for (auto l = lo[2]; l <= hi[2]; ++l) cells_.add(CellHash3::Key{i, j, l}, pieces_.size());
      pieces_.push_back({p, q});
    }
  }

  // f(a, b) for every piece filed near p (some more than once).
  template <class F>
  void near(const Eigen::Vector3d& p, F&& f) const {
    cells_.near(p, 1, [&](std::size_t s) { f(pieces_[s][0], pieces_[s][1]); });
  }

 private:
  CellHash3 cells_;
  std::vector<std::array<Eigen::Vector3d, 2>> pieces_;
};

enum class Snap : std::uint8_t { Kept, Corner, Feature, Surface };

}  // namespace

SnapReport snap_to_reference(Mesh& remeshed, const Mesh& reference, const std::vector<Edge>& reference_features,
                             double reach) {
  if (reference.num_faces() == 0) throw std::invalid_argument("the reference mesh has no faces");
  if (!(reach > 0)) throw std::invalid_argument("reach must be positive");
  const std::vector<Edge> ref_edges = features_and_borders(mesh_edges(reference), reference_features);
  const std::vector<Edge> own_edges = features_and_borders(mesh_edges(remeshed), remeshed.feature_edges);
  const std::vector<int> ref_degree = degrees(reference.num_vertices(), ref_edges);
  const std::vector<int> own_degree = degrees(remeshed.num_vertices(), own_edges);

  std::vector<Eigen::Vector3d> ref_corners;
  for (std::size_t v = 0; v < reference.num_vertices(); ++v)
    if (ref_degree[v] >= 3) ref_corners.push_back(reference.vertices[v]);
  SegmentGrid grid(reach);
  for (Edge e : ref_edges) grid.add(reference.vertices[e[0]], reference.vertices[e[1]]);
  std::vector<std::vector<Eigen::Vector3d>> own_directions(remeshed.num_vertices());
  for (Edge e : own_edges) {
    const Eigen::Vector3d d = (remeshed.vertices[e[1]] - remeshed.vertices[e[0]]).normalized();
    own_directions[e[0]].push_back(d);
    own_directions[e[1]].push_back(d);
  }
  const MeshDistance surface(reference);
  const double parallel = std::cos(30.0 * M_PI / 180.0);

  const std::vector<Eigen::Vector3d> before = remeshed.vertices;
  std::vector<Snap> kind(before.size(), Snap::Kept);
  std::vector<double> off(before.size(), 0);
  tbb::parallel_for(std::size_t(0), before.size(), [&](std::size_t v) {
    const Eigen::Vector3d& p = before[v];
    off[v] = surface(p);
    double best = reach;
    if (own_degree[v] >= 3)
      for (const Eigen::Vector3d& c : ref_corners)
        if (const double d = (c - p).norm(); d <= best) best = d, remeshed.vertices[v] = c, kind[v] = Snap::Corner;
    if (kind[v] == Snap::Kept && own_degree[v] >= 1) {
      grid.near(p, [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        const Eigen::Vector3d along = (b - a).normalized();
        if (std::none_of(own_directions[v].begin(), own_directions[v].end(),
                         [&](const Eigen::Vector3d& d) { return std::abs(d.dot(along)) >= parallel; }))
          return;
        const Eigen::Vector3d q = closest_on_segment(p, a, b);
        if (const double d = (q - p).norm(); d <= best) best = d, remeshed.vertices[v] = q, kind[v] = Snap::Feature;
      });
    }
    if (kind[v] == Snap::Kept)
      if (const Eigen::Vector3d q = surface.closest_point(p); (q - p).norm() <= reach)
        remeshed.vertices[v] = q, kind[v] = Snap::Surface;
  });

  // Faces that would turn: their vertices go back, until none does.
  const double turn = std::cos(45.0 * M_PI / 180.0);
  const std::vector<Eigen::Vector3d> normal_before = face_geometry(remeshed, before).normal;
  for (bool reverted = true; reverted;) {
    reverted = false;
    const std::vector<Eigen::Vector3d> normal = face_geometry(remeshed).normal;
    for (std::size_t f = 0; f < remeshed.num_faces(); ++f) {
      if (normal_before[f].isZero() || normal[f].dot(normal_before[f]) >= turn) continue;
      for (std::size_t k = 0; k < remeshed.face_size(f); ++k) {
        const std::uint32_t v = remeshed.face(f)[k];
        if (kind[v] == Snap::Kept) continue;
        remeshed.vertices[v] = before[v];
        kind[v] = Snap::Kept;
        reverted = true;
      }
    }
  }

  SnapReport report;
  for (std::size_t v = 0; v < before.size(); ++v) {
    report.corners += kind[v] == Snap::Corner;
    report.feature_vertices += kind[v] == Snap::Feature;
    report.surface_vertices += kind[v] == Snap::Surface;
    report.kept += kind[v] == Snap::Kept;
    report.off_surface_max = std::max(report.off_surface_max, off[v]);
    report.moved_max = std::max(report.moved_max, (remeshed.vertices[v] - before[v]).norm());
  }
  return report;
}

}  // namespace scallop
