#include "nodes/mesh/setup_base.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "nodes/geom/kmeans.h"
#include "nodes/geom/point_text.h"
#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/keep_faces.h"
#include "nodes/mesh/mesh_topology.h"

namespace scallop {
namespace {

std::string direction_text(const Eigen::Vector3d& d) {
  return "(" + short_number(d.x(), 3) + ", " + short_number(d.y(), 3) + ", " + short_number(d.z(), 3) + ")";
}

// The largest v . d over the vertices that faces use: the part's extreme plane along d.
double extreme_offset(const Mesh& mesh, const Eigen::Vector3d& d) {
  double h = -std::numeric_limits<double>::infinity();
  for (auto v : mesh.face_vertices) h = std::max(h, mesh.vertices[v].dot(d));
  return h;
}

struct FlatPart {
  std::vector<std::uint32_t> faces;  // increasing
  double area = 0;
  std::size_t kept_faces = 0;  // facing d but not in the part
  double kept_area = 0;
};

// The base's flat part along d (see the header): faces facing d within the angle with every
// corner on the extreme plane, their connected group of the largest area (ties: the group
// holding the lowest face index).
FlatPart flat_part(const Mesh& mesh, const FaceGeometry& g, const Eigen::Vector3d& d, double angle, double tol) {
  const std::size_t F = mesh.num_faces();
  const double h = extreme_offset(mesh, d);
  std::vector<bool> facing(F, false), candidate(F, false);
  for (std::size_t f = 0; f < F; ++f) {
    facing[f] = g.area[f] > 0 && angle_deg(g.normal[f], d) <= angle;
    if (!facing[f]) continue;
    bool on = true;
    for (std::size_t c = 0; c < mesh.face_size(f) && on; ++c) on = h - mesh.vertices[mesh.face(f)[c]].dot(d) <= tol;
    candidate[f] = on;
  }
  // Connected groups of the candidates alone: the components of the mesh they make.
  Mesh part;
  part.vertices = mesh.vertices;
  std::vector<std::uint32_t> original;
  for (std::size_t f = 0; f < F; ++f)
    if (candidate[f]) {
      part.add_face_range(std::vector<std::uint32_t>(mesh.face(f), mesh.face(f) + mesh.face_size(f)));
      original.push_back(static_cast<std::uint32_t>(f));
    }
  FlatPart out;
  if (!original.empty()) {
    const std::vector<int> comp = face_components(part, mesh_edges(part));
    std::vector<double> area(*std::max_element(comp.begin(), comp.end()) + 1, 0.0);
    for (std::size_t i = 0; i < original.size(); ++i) area[comp[i]] += g.area[original[i]];
    // Components are numbered in order of their first face: the first of the largest wins ties.
    const int best = static_cast<int>(std::max_element(area.begin(), area.end()) - area.begin());
    for (std::size_t i = 0; i < original.size(); ++i)
      if (comp[i] == best) out.faces.push_back(original[i]);
    out.area = area[best];
  }
  for (std::size_t f = 0, i = 0; f < F; ++f) {
    const bool in = i < out.faces.size() && out.faces[i] == f;
    i += in;
    if (facing[f] && !in) ++out.kept_faces, out.kept_area += g.area[f];
  }
  return out;
}

// The clusters of the face normals, rated (S, Gamma, epsilon) and ordered best objective first
// (ties: the larger area, then K-means' order).
std::vector<BaseCluster> rate_clusters(const FaceGeometry& g, const SetupBaseOptions& o) {
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> areas;
  std::vector<std::size_t> face;
  for (std::size_t f = 0; f < g.area.size(); ++f)
    if (g.area[f] > 0) normals.push_back(g.normal[f]), areas.push_back(g.area[f]), face.push_back(f);
  KMeansOptions km;
  km.k = o.clusters;
  km.seed = static_cast<std::uint32_t>(o.seed);
  const KMeansResult r = kmeans(normals, areas, km);
  // The weighted mean of unit normals is K-means' own centre: m = centre, S = |m|.
  std::vector<BaseCluster> clusters(r.centre.size());
  const double largest = *std::max_element(r.weight.begin(), r.weight.end());
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    BaseCluster& b = clusters[c];
    const double m = r.centre[c].norm();
    b.direction = m > 0 ? Eigen::Vector3d(r.centre[c] / m) : Eigen::Vector3d::Zero();
    b.faces = r.size[c];
    b.area = r.weight[c];
    b.similarity = std::min(1.0, m);
    b.quantity = b.area / largest;
    b.objective = o.mu * b.similarity + o.gamma * b.quantity;
  }
  // Each cluster's flattest direction (see the header).
  const double cos_flat = std::cos(o.flat_angle_deg * std::numbers::pi / 180);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    std::vector<std::size_t> members;
    for (std::size_t i = 0; i < normals.size(); ++i)
      if (r.label[i] == static_cast<int>(c)) members.push_back(i);
    clusters[c].flat_direction = clusters[c].direction;
    if (members.empty()) continue;
    const std::size_t stride = std::max<std::size_t>(1, members.size() / 256);
    double best = -1;
    for (std::size_t t = 0; t < members.size(); t += stride) {
      const Eigen::Vector3d& n = normals[members[t]];
      double around = 0;
      for (auto i : members) around += normals[i].dot(n) >= cos_flat ? areas[i] : 0.0;
      if (around > best) {
        best = around;
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (auto i : members)
          if (normals[i].dot(n) >= cos_flat) sum += areas[i] * normals[i];
        clusters[c].flat_direction = sum.normalized();
      }
    }
  }
  std::stable_sort(clusters.begin(), clusters.end(), [](const BaseCluster& a, const BaseCluster& b) {
    return a.objective != b.objective ? a.objective > b.objective : a.area > b.area;
  });
  return clusters;
}

std::size_t open_edges(const Mesh& mesh) {
  const MeshEdges e = mesh_edges(mesh);
  std::size_t n = 0;
  for (std::size_t i = 0; i < e.size(); ++i) n += e.is_boundary(i);
  return n;
}

void check(const Mesh& mesh, const SetupBaseOptions& o) {
  if (mesh.num_faces() == 0) throw std::invalid_argument("the mesh has no faces");
  if (o.clusters < 1) throw std::invalid_argument("clusters must be at least 1");
  if (!(o.mu >= 0 && o.gamma >= 0 && o.mu + o.gamma > 0))
    throw std::invalid_argument("mu and gamma must be non-negative, not both 0");
  if (!(o.flat_angle_deg >= 0 && o.flat_angle_deg < 90)) throw std::invalid_argument("flat_angle must lie in [0, 90) degrees");
  if (!(o.plane_tolerance >= 0)) throw std::invalid_argument("plane_tolerance must be non-negative");
  if (!(o.min_area >= 0 && o.min_area <= 1)) throw std::invalid_argument("min_area must lie in [0, 1]");
  if (!o.direction.allFinite()) throw std::invalid_argument("the direction must be finite");
}

}  // namespace

SetupBaseResult setup_base(const Mesh& mesh, const SetupBaseOptions& o) {
  check(mesh, o);
  const FaceGeometry g = face_geometry(mesh);
  const double total = std::accumulate(g.area.begin(), g.area.end(), 0.0);
  if (!(total > 0)) throw std::invalid_argument("the mesh's faces have no area");
  Eigen::AlignedBox3d box;
  for (auto v : mesh.face_vertices) box.extend(mesh.vertices[v]);
  const double tol = o.plane_tolerance * box.diagonal().norm();

  SetupBaseResult r;
  r.area = total;
  FlatPart base;
  if (o.direction.squaredNorm() > 0) {
    r.direction = o.direction.normalized();
    base = flat_part(mesh, g, r.direction, o.flat_angle_deg, tol);
    r.how = "given by the parameter direction";
  } else {
    r.clusters = rate_clusters(g, o);
    FlatPart largest;
    for (std::size_t c = 0; c < r.clusters.size(); ++c) {
      BaseCluster& b = r.clusters[c];
      if (b.direction.squaredNorm() == 0) continue;  // normals that cancel out: no direction
      FlatPart p = flat_part(mesh, g, b.flat_direction, o.flat_angle_deg, tol);
      b.flat_area = p.area;
      if (p.area > largest.area) largest = p;
      if (r.chosen < 0 && p.area >= o.min_area * total) r.chosen = static_cast<int>(c), base = std::move(p);
    }
    if (r.chosen < 0 && open_edges(mesh) > 0) {
      // A scan of one side: it rests on what it does not show, so there is no base to remove.
      r.direction = Eigen::Vector3d::Zero();
      r.how = "an open mesh (" + std::to_string(open_edges(mesh)) +
              " boundary edges) without a flat base: taken whole, nothing removed";
      r.mesh = mesh;
      return r;
    }
    if (r.chosen < 0) {
      Eigen::Vector3d facing = Eigen::Vector3d::Zero();
      for (auto f : largest.faces) facing += g.area[f] * g.normal[f];
      throw std::runtime_error(
          "no flat face large enough for a setup base: " +
          (largest.faces.empty() ? std::string("no cluster of the face normals has a face on the part's extreme plane")
                                 : "the largest flat part on the part's extreme plane, facing " +
                                       direction_text(Eigen::Vector3d(facing.normalized())) + ", holds " +
                                       short_number(100 * largest.area / total, 3) + " % of the area") +
          ", less than min_area " + short_number(100 * o.min_area, 3) +
          " %; give the base's outward normal with the parameter direction");
    }
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (auto f : base.faces) sum += g.area[f] * g.normal[f];
    r.direction = sum.normalized();
    r.how = r.chosen == 0 ? "the cluster of the best objective"
                          : "the cluster of objective rank " + std::to_string(r.chosen + 1) +
                                ": the better ones have no flat part of min_area on the part's extreme plane";
  }
  r.base_faces = std::move(base.faces);
  r.base_area = base.area;
  r.facing_kept_faces = base.kept_faces;
  r.facing_kept_area = base.kept_area;
  r.plane_offset = extreme_offset(mesh, r.direction);
  if (r.base_faces.size() == mesh.num_faces())
    throw std::runtime_error("the base facing " + direction_text(r.direction) + " is the whole mesh: nothing is left to machine");

  std::vector<bool> keep(mesh.num_faces(), true);
  for (auto f : r.base_faces) keep[f] = false;
  r.mesh = keep_faces(mesh, keep);
  std::vector<bool> used(mesh.num_vertices(), false);
  for (auto v : mesh.face_vertices) used[v] = true;
  r.vertices_removed = static_cast<std::size_t>(std::count(used.begin(), used.end(), true)) - r.mesh.num_vertices();
  return r;
}

Eigen::Vector3d base_direction_of(const nlohmann::json& report) {
  const auto it = report.find("base_direction");
  if (it == report.end() || !it->is_array() || it->size() != 3 || !(*it)[0].is_number() || !(*it)[1].is_number() ||
      !(*it)[2].is_number())
    throw std::invalid_argument("the input 'base' has no base_direction [x, y, z]: give mesh.setup_base's report");
  return {(*it)[0].get<double>(), (*it)[1].get<double>(), (*it)[2].get<double>()};
}

}  // namespace scallop
