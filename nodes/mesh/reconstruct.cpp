#include "nodes/mesh/reconstruct.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/bilateral_smooth_point_set.h>
#include <CGAL/poisson_surface_reconstruction.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "nodes/cloud/knn.h"
#include "nodes/cloud/principal_extents.h"
#include "nodes/mesh/external_process.h"
#include "nodes/mesh/mesh_distance.h"
#include "nodes/mesh/mesh_topology.h"

namespace scallop {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Vector3 = Kernel::Vector_3;

constexpr const char* kAdvancingFront = "scallop-advancing-front";  // helpers/advancing_front_main.cpp
constexpr double kAdvancingFrontTimeout = 24 * 3600;               // s: only a hung front comes near it

Point3 to_cgal(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }
Eigen::Vector3d to_eigen(const Point3& p) { return {p.x(), p.y(), p.z()}; }

// A mesh of the triangles over the vertices they use (others dropped; input order kept, so a mesh
// of the same points numbers them the same way).
Mesh compact_mesh(const std::vector<Eigen::Vector3d>& V, const std::vector<std::array<std::size_t, 3>>& T) {
  std::vector<std::int64_t> new_index(V.size(), -1);
  for (const auto& t : T)
    for (auto v : t) new_index[v] = 0;
  Mesh m;
  for (std::size_t v = 0; v < V.size(); ++v)
    if (new_index[v] >= 0) {
      new_index[v] = static_cast<std::int64_t>(m.vertices.size());
      m.vertices.push_back(V[v]);
    }
  for (const auto& t : T)
    m.add_face({static_cast<std::uint32_t>(new_index[t[0]]), static_cast<std::uint32_t>(new_index[t[1]]),
                static_cast<std::uint32_t>(new_index[t[2]])});
  return m;
}

// Flips every component whose faces, weighted by area, face against the normals of the input
// points nearest them; without normals, closed components are turned to bound a positive
// volume and open ones to face +Z on average.
void orient_components(Mesh& m, const KnnIndex& index, const std::vector<Eigen::Vector3d>& N) {
  const MeshEdges edges = mesh_edges(m);
  const std::vector<int> comp = face_components(m, edges);
  const int count = comp.empty() ? 0 : *std::max_element(comp.begin(), comp.end()) + 1;
  std::vector<double> score(count, 0.0), volume(count, 0.0), up(count, 0.0);
  std::vector<bool> closed(count, true);
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges.is_boundary(e)) closed[comp[edges.faces(e)[0]]] = false;
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    const Eigen::Vector3d a = face_area_vector(m, f);
    const Eigen::Vector3d& p0 = m.vertices[m.face(f)[0]];
    volume[comp[f]] += p0.dot(a);  // 6x the signed volume, summed over a closed surface
    up[comp[f]] += a.z();
    if (!N.empty()) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (std::size_t k = 0; k < 3; ++k) c += m.vertices[m.face(f)[k]];
      score[comp[f]] += a.dot(N[index.nearest(c / 3.0)]);
    }
  }
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    const int c = comp[f];
    const double s = !N.empty() ? score[c] : closed[c] ? volume[c] : up[c];
    if (s < 0) std::swap(m.face_vertices[m.face_start[f] + 1], m.face_vertices[m.face_start[f] + 2]);
  }
}

void check_input(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                 const ReconstructOptions& o) {
  constexpr std::size_t kMinPoints = 10;
  if (P.size() < kMinPoints)
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) +
                                " points; reconstruction needs at least " + std::to_string(kMinPoints));
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!P[i].allFinite())
      throw std::invalid_argument("point " + std::to_string(i) + " has a NaN or infinite coordinate: run cloud.clean first");
  if (!N.empty() && N.size() != P.size())
    throw std::invalid_argument("the cloud has " + std::to_string(N.size()) + " normals for " +
                                std::to_string(P.size()) + " points");
  const bool poisson = o.method == ReconstructMethod::poisson;
  if (N.empty() && poisson)
    throw std::invalid_argument(
        "method poisson needs normals oriented consistently over the whole cloud, and the cloud has none: "
        "add cloud.normals (orientation mst) before mesh.reconstruct, or use method advancing_front");
  if (N.empty() && o.smooth_iterations > 0)
    throw std::invalid_argument(
        "smoothing (smooth_iterations > 0) needs normals, and the cloud has none: add cloud.normals "
        "before mesh.reconstruct, or set smooth_iterations 0");
}

double mean_spacing(const std::vector<Eigen::Vector3d>& P) {
  const Neighborhoods nb = compute_knn(P, 6);
  double sum = 0;
  for (double d2 : nb.sq_dists) sum += std::sqrt(d2);
  return sum / static_cast<double>(nb.sq_dists.size());
}

// Distance from every point to the mesh's triangles: mean, 99th percentile, max.
void point_distances(const std::vector<Eigen::Vector3d>& P, const Mesh& m, ReconstructResult& r) {
  if (m.num_faces() == 0 || P.empty()) return;
  std::vector<double> d = distances_to_mesh(P, m);
  double sum = 0;
  for (double x : d) sum += x;
  r.distance_mean = sum / static_cast<double>(d.size());
  auto p99 = d.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(d.size() - 1));
  std::nth_element(d.begin(), p99, d.end());
  r.distance_p99 = *p99;
  r.distance_max = *std::max_element(d.begin(), d.end());
}

// CGAL's advancing front over V, run by scallop-advancing-front beside this program (why: its
// file's header).
std::vector<std::array<std::size_t, 3>> advancing_front_triangles(const std::vector<Eigen::Vector3d>& V,
                                                                  double radius_ratio_bound, double beta,
                                                                  const std::function<void(double, const std::string&)>& progress) {
  const std::filesystem::path helper = std::filesystem::read_symlink("/proc/self/exe").parent_path() / kAdvancingFront;
  if (!find_executable(helper.string()))
    throw std::runtime_error(helper.string() + " is missing: it is built with scallop (scripts/build.sh) and must lie "
                             "beside it");
  const PrivateTempDir dir("scallop-advancing-front-");
  const std::filesystem::path in = dir.path() / "points.bin", out = dir.path() / "triangles.bin", log = dir.path() / "log";
  {
    std::ofstream f(in, std::ios::binary);
    const std::uint64_t n = V.size();
    f.write(reinterpret_cast<const char*>(&n), sizeof n);
    for (const auto& p : V) f.write(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double));
    if (!f) throw std::runtime_error("cannot write the points for the advancing front to " + in.string());
  }
  char ratio[32], wedge[32];
  std::snprintf(ratio, sizeof ratio, "%.17g", radius_ratio_bound);
  std::snprintf(wedge, sizeof wedge, "%.17g", beta);
  const ProcessResult run = run_process({helper.string(), in.string(), out.string(), ratio, wedge}, log, dir.path(),
                                        kAdvancingFrontTimeout, [&](double seconds) {
                                          if (progress)
                                            progress(0.5, "advancing-front reconstruction (" +
                                                              std::to_string(static_cast<int>(seconds)) + " s)");
                                        });
  if (run.exit_status != 0) {
    std::string why = run.timed_out ? "ran longer than " + std::to_string(static_cast<int>(kAdvancingFrontTimeout)) + " s"
                      : run.signal ? "was ended by signal " + std::to_string(run.signal)
                                   : "exited with status " + std::to_string(run.exit_status);
    for (const auto& line : last_lines(log, 3)) why += "; " + line;
    throw std::runtime_error("the advancing front (" + helper.filename().string() + ") " + why);
  }
  std::ifstream f(out, std::ios::binary);
  std::uint64_t m = 0;
  f.read(reinterpret_cast<char*>(&m), sizeof m);
  std::vector<std::array<std::size_t, 3>> tris(f ? m : 0);
  for (auto& t : tris) {
    std::uint64_t v[3];
    f.read(reinterpret_cast<char*>(v), sizeof v);
    if (!f || v[0] >= V.size() || v[1] >= V.size() || v[2] >= V.size())
      throw std::runtime_error("the advancing front's triangles could not be read back from " + out.string());
    t = {v[0], v[1], v[2]};
  }
  return tris;
}

Mesh advancing_front(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                     const ReconstructOptions& o, ReconstructResult& r,
                     const std::function<void(double, const std::string&)>& progress) {
  std::vector<std::pair<Point3, Vector3>> pts(P.size());
  for (std::size_t i = 0; i < P.size(); ++i)
    pts[i] = {to_cgal(P[i]), N.empty() ? Vector3(0, 0, 1) : Vector3(N[i].x(), N[i].y(), N[i].z())};
  for (int it = 0; it < o.smooth_iterations; ++it) {
    if (progress) progress(0.5 * it / o.smooth_iterations, "bilateral smoothing pass " + std::to_string(it + 1));
    r.smooth_moved = CGAL::bilateral_smooth_point_set<CGAL::Parallel_if_available_tag>(
        pts, static_cast<unsigned>(o.smooth_neighbors),
        CGAL::parameters::point_map(CGAL::First_of_pair_property_map<std::pair<Point3, Vector3>>())
            .normal_map(CGAL::Second_of_pair_property_map<std::pair<Point3, Vector3>>())
            .sharpness_angle(o.sharpness_angle));
  }
  if (progress) progress(0.5, "advancing-front reconstruction");
  std::vector<Eigen::Vector3d> V(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) V[i] = to_eigen(pts[i].first);
  std::vector<std::array<std::size_t, 3>> tris = advancing_front_triangles(V, o.radius_ratio_bound, o.beta, progress);
  // Each triangle started at its lowest vertex (keeping its orientation) and the list sorted: the
  // mesh does not depend on the order the front found its triangles in.
  for (auto& t : tris) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  std::sort(tris.begin(), tris.end());
  Mesh m = compact_mesh(V, tris);
  r.unused_points = P.size() - m.num_vertices();
  return m;
}

Mesh poisson(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
             const ReconstructOptions& o, ReconstructResult& r, const KnnIndex& index,
             const std::function<void(double, const std::string&)>& progress) {
  if (progress) progress(0.1, "Poisson reconstruction");
  std::vector<std::pair<Point3, Vector3>> pts(P.size());
  for (std::size_t i = 0; i < P.size(); ++i) pts[i] = {to_cgal(P[i]), Vector3(N[i].x(), N[i].y(), N[i].z())};
  CGAL::Surface_mesh<Point3> sm;
  // The surface mesher seeds itself from CGAL's default random generator, which is seeded from
  // the clock: a fixed seed makes the same cloud give the same mesh (and cache entry).
  CGAL::get_default_random() = CGAL::Random(0);
  const bool ok = CGAL::poisson_surface_reconstruction_delaunay(
      pts.begin(), pts.end(), CGAL::First_of_pair_property_map<std::pair<Point3, Vector3>>(),
      CGAL::Second_of_pair_property_map<std::pair<Point3, Vector3>>(), sm, r.spacing,
      // Triangles up to 2 spacings across (CGAL's example uses 30: far coarser than the cloud).
      /*sm_angle=*/20.0, /*sm_radius=*/2.0, /*sm_distance=*/o.poisson_approximation);
  if (!ok || sm.number_of_faces() == 0)
    throw std::invalid_argument("Poisson reconstruction found no surface (the implicit function could not be "
                                "solved or has no zero level); check that the normals point outward");
  if (progress) progress(0.8, "trimming faces far from the points");
  std::vector<Eigen::Vector3d> V;
  std::vector<std::int64_t> vindex(sm.number_of_vertices() + sm.number_of_removed_vertices(), -1);
  for (auto v : sm.vertices()) {
    vindex[v.idx()] = static_cast<std::int64_t>(V.size());
    V.push_back(to_eigen(sm.point(v)));
  }
  std::vector<std::array<std::size_t, 3>> tris;
  const double limit = o.trim_spacings * r.spacing;
  for (auto f : sm.faces()) {
    std::vector<std::size_t> corners;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) corners.push_back(static_cast<std::size_t>(vindex[v.idx()]));
    if (corners.size() != 3) continue;  // the mesher makes triangles
    const std::array<std::size_t, 3> t{corners[0], corners[1], corners[2]};
    const Eigen::Vector3d c = (V[t[0]] + V[t[1]] + V[t[2]]) / 3.0;
    if ((P[index.nearest(c)] - c).norm() > limit) {
      ++r.trimmed_faces;
      continue;
    }
    tris.push_back(t);
  }
  return compact_mesh(V, tris);
}

}  // namespace

double normal_disagreement(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N, int k) {
  if (N.size() != P.size() || P.size() < 2) return 0.0;
  const Neighborhoods nb = compute_knn(P, std::min<int>(k, static_cast<int>(P.size()) - 1));
  std::size_t against = 0, pairs = 0;
  for (std::size_t i = 0; i < nb.size(); ++i)
    for (int j = 0; j < nb.k; ++j, ++pairs)
      if (N[i].dot(N[nb.index(i, j)]) < 0) ++against;
  return pairs == 0 ? 0.0 : static_cast<double>(against) / static_cast<double>(pairs);
}

ReconstructResult reconstruct_surface(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                                      const ReconstructOptions& o,
                                      const std::function<void(double, const std::string&)>& progress) {
  check_input(P, N, o);
  ReconstructResult r;
  r.spacing = mean_spacing(P);
  const PrincipalExtents extents = principal_extents(P);
  const std::string line = one_dimensional_problem(extents, r.spacing);
  if (!line.empty()) throw std::invalid_argument(line);
  if (extents.thickness <= 1e-9 * extents.length)
    throw std::invalid_argument(
        "the points lie exactly in one plane; a 3-D reconstruction has no volume to work in: "
        "mesh a planar cloud with the iso-parametric graphs, or give it its scanner's noise");
  if (o.method == ReconstructMethod::poisson) {
    // Poisson needs inside and outside: normals that flip between neighbours give a surface
    // full of holes and bubbles, so they are refused, with the fix.
    const double against = normal_disagreement(P, N);
    if (against > 0.02) {
      char buf[320];
      std::snprintf(buf, sizeof buf,
                    "the normals are not oriented consistently: %.1f%% of neighbouring normals point against "
                    "each other (at most 2%% expected); Poisson needs them all outward: compute them with "
                    "cloud.normals orientation mst",
                    100.0 * against);
      throw std::invalid_argument(buf);
    }
  }
  const KnnIndex index(P);
  r.mesh = o.method == ReconstructMethod::poisson ? poisson(P, N, o, r, index, progress)
                                                  : advancing_front(P, N, o, r, progress);
  if (r.mesh.num_faces() == 0)
    throw std::invalid_argument("the reconstruction made no faces: the points may be too sparse for their "
                                "shape; raise radius_ratio_bound or give a denser cloud");
  if (progress) progress(0.9, "orienting and measuring");
  orient_components(r.mesh, index, N);
  point_distances(P, r.mesh, r);
  return r;
}

}  // namespace scallop
