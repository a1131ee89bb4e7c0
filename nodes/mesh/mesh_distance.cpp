#include "nodes/mesh/mesh_distance.h"

#include <stdexcept>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <mutex>

#include "nodes/geom/kd_tree.h"
#include "nodes/geom/triangle.h"
#include "nodes/mesh/mesh_topology.h"

namespace scallop {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<Kernel::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

// CGAL's exact predicates turn a NaN into a GMP rational, and GMP ends the process (SIGFPE):
// a point that is not finite is refused here instead (a 200 000-point ABC plate cloud's programs
// stopped the whole run that way).
Kernel::Point_3 point(const Eigen::Vector3d& p) {
  if (!p.allFinite()) throw std::invalid_argument("a distance to the mesh was asked at a point that is not finite");
  return Kernel::Point_3(p.x(), p.y(), p.z());
}

// The least a distance to a set of points and faces can be between two points `gap` apart where
// it is d0 and d1: (d0 + d1 - gap) / 2 (1-Lipschitz), and, where that is positive, min(d0, d1) -
// gap^2 / (8 that) (a minimum of convex functions of curvature at most 1 / that).
double least_between(double d0, double d1, double gap) {
  const double lip = 0.5 * (d0 + d1 - gap);
  return std::max(lip, lip > 0 ? std::min(d0, d1) - gap * gap / (8 * lip) : -INFINITY);
}

// Each polygon fanned from its first corner.
Triangles triangles(const Mesh& m) {
  Triangles tris;
  tris.reserve(m.num_faces());
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    for (std::size_t k = 1; k + 1 < m.face_size(f); ++k)
      tris.emplace_back(point(m.vertices[m.face(f)[0]]), point(m.vertices[m.face(f)[k]]),
                        point(m.vertices[m.face(f)[k + 1]]));
  return tris;
}

// The triangles and how far their boxes are grown, for the grown scenes' bounds.
struct GrownTriangles {
  const Triangles* tris;
  double grow;
};

// Embree's device, one for the process (it holds Embree's own thread pool state).
RTCDevice embree_device() {
  static const RTCDevice device = [] {
    RTCDevice d = rtcNewDevice(nullptr);
    if (!d) throw std::runtime_error("Embree could not start: " + std::to_string(int(rtcGetDeviceError(nullptr))));
    return d;
  }();
  return device;
}

}  // namespace

// The nearest point of the faces is found by Embree's bounding volume hierarchy (its point
// query): 3-4 times faster than CGAL's AABB tree on the fandisk (bench/mesh_distance_bench). Its
// boxes and query are floats, so each triangle's box is rounded outward and the query's radius
// kept a little over the best distance found, which is computed in doubles by
// closest_on_triangle: the answer is the exact nearest triangle's, as CGAL's was. CGAL's tree
// stays for rays (the signed distance's crossings, ray_distance), built when first asked.
namespace {
// The side of a point whose nearest is on an edge or a corner (signed_distance): the angle-weighted
// pseudo-normal there (Baerentzen and Aanaes 2005), where every face around is trusted and they
// close around it as a closed surface's do; NaN where not (the rays decide).
struct SideNormals {
  std::vector<Eigen::Vector3d> edge;        // #tris * 3: of the edge opposite corner k of each triangle
  std::vector<std::uint32_t> corner_vertex;  // #tris * 3: the mesh vertex at corner k
  std::vector<Eigen::Vector3d> vertex;      // per mesh vertex
};
}  // namespace

struct MeshDistance::Impl {
  Triangles tris;
  std::vector<std::size_t> face_of;  // #tris: the polygon each triangle was fanned from
  std::vector<char> folded;          // per polygon: over 150 degrees from a neighbour, 10 from its unmoved place, or untrusted
  SideNormals side;                  // where the nearest point is on an edge or a corner
  RTCScene scene = nullptr;          // the triangles' boxes, for the nearest point
  std::once_flag rays_built;
  Tree tree;                         // for rays only
  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    for (auto& [radius, grown_scene] : grown) rtcReleaseScene(grown_scene);
  }
  const Tree& ray_tree() {
    std::call_once(rays_built, [&] {
      tree.insert(tris.begin(), tris.end());
      tree.build();
    });
    return tree;
  }
  // The triangles' boxes grown by a ball's radius, for touch_along: one scene per radius asked.
  std::mutex grown_mutex;
  std::vector<std::pair<double, RTCScene>> grown;
  std::deque<GrownTriangles> grown_boxes;  // what each scene's bounds read
  RTCScene grown_by(double radius);
  // The nearest point of the triangles to p and its triangle's index, searched within `radius`
  // (+infinity, or the distance to a point known to be on them): false when none is that near.
  bool nearest(const Eigen::Vector3d& p, double radius, Eigen::Vector3d& foot, std::size_t& tri) const;
};

namespace {

// A float at most x (at least x): the boxes and radii Embree culls with hold every double.
float float_below(double x) { return std::nextafter(static_cast<float>(x), -std::numeric_limits<float>::infinity()); }
float float_above(double x) { return std::nextafter(static_cast<float>(x), std::numeric_limits<float>::infinity()); }

void triangle_box(const RTCBoundsFunctionArguments* args) {
  const Kernel::Triangle_3& t = (*static_cast<const Triangles*>(args->geometryUserPtr))[args->primID];
  const CGAL::Bbox_3 box = t.bbox();
  RTCBounds* out = args->bounds_o;
  out->lower_x = float_below(box.xmin()), out->lower_y = float_below(box.ymin()), out->lower_z = float_below(box.zmin());
  out->upper_x = float_above(box.xmax()), out->upper_y = float_above(box.ymax()), out->upper_z = float_above(box.zmax());
}

// Corner k of a triangle, in Eigen's terms.
Eigen::Vector3d corner(const Kernel::Triangle_3& t, int k) { return {t[k].x(), t[k].y(), t[k].z()}; }

struct NearestQuery {
  const Triangles* tris;
  Eigen::Vector3d p;
  double slack;  // what the float query point and Embree's float tests may be off by
  double d2 = std::numeric_limits<double>::infinity();
  Eigen::Vector3d foot = Eigen::Vector3d::Zero();
  std::size_t tri = std::numeric_limits<std::size_t>::max();
};

bool nearer_triangle(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<NearestQuery*>(args->userPtr);
  const std::size_t t = args->primID;
  const Kernel::Triangle_3& tri = (*q->tris)[t];
  const Eigen::Vector3d c = closest_on_triangle(q->p, corner(tri, 0), corner(tri, 1), corner(tri, 2));
  const double d2 = (c - q->p).squaredNorm();
  if (!(d2 < q->d2)) return false;
  q->d2 = d2, q->foot = c, q->tri = t;
  const float radius = float_above(std::sqrt(d2) + q->slack);
  if (!(radius < args->query->radius)) return false;
  args->query->radius = radius;
  return true;
}

// The nearest pair of a segment and the triangles a point query's sphere about its middle meets.
struct SegmentQuery {
  const Triangles* tris;
  Eigen::Vector3d a, b;
  double half;   // half the segment's length: the sphere is half + the least found
  double slack;  // as NearestQuery's
  double least;  // the least distance found, and where on the segment
  Eigen::Vector3d where;
};

bool nearer_to_segment(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<SegmentQuery*>(args->userPtr);
  const Kernel::Triangle_3& tri = (*q->tris)[args->primID];
  const Eigen::Vector3d t0 = corner(tri, 0), t1 = corner(tri, 1), t2 = corner(tri, 2);
  // The triangle's ball about its centroid first: most triangles in the sphere are farther.
  const Eigen::Vector3d centre = (t0 + t1 + t2) / 3;
  const double reach = std::sqrt(std::max({(t0 - centre).squaredNorm(), (t1 - centre).squaredNorm(), (t2 - centre).squaredNorm()}));
  if (!(segment_distance(centre, q->a, q->b) - reach < q->least)) return false;
  Eigen::Vector3d on_segment, on_triangle;
  const double d = std::sqrt(closest_segment_triangle(q->a, q->b, t0, t1, t2, on_segment, on_triangle));
  if (!(d < q->least)) return false;
  q->least = d, q->where = on_segment;
  const float radius = float_above(q->half + d + q->slack);
  if (!(radius < args->query->radius)) return false;
  args->query->radius = radius;
  return true;
}

void grown_triangle_box(const RTCBoundsFunctionArguments* args) {
  const auto* g = static_cast<const GrownTriangles*>(args->geometryUserPtr);
  const CGAL::Bbox_3 box = (*g->tris)[args->primID].bbox();
  RTCBounds* out = args->bounds_o;
  out->lower_x = float_below(box.xmin() - g->grow), out->lower_y = float_below(box.ymin() - g->grow);
  out->lower_z = float_below(box.zmin() - g->grow);
  out->upper_x = float_above(box.xmax() + g->grow), out->upper_y = float_above(box.ymax() + g->grow);
  out->upper_z = float_above(box.zmax() + g->grow);
}

// A ray's context as Embree hands it to the intersection callback, with the ball it moves.
struct TouchQuery {
  RTCIntersectContext context;  // first: the callback gets a pointer to it
  const Triangles* tris;
  Eigen::Vector3d o, d;  // the ball's centre and direction, in doubles
  double r;
  double slack;  // the float ray's rounding, added to the far end it culls with
  double t;      // the first touch found
};

void touch_triangle(const RTCIntersectFunctionNArguments* args) {
  if (!args->valid[0]) return;
  auto* q = reinterpret_cast<TouchQuery*>(args->context);
  const Kernel::Triangle_3& tri = (*q->tris)[args->primID];
  const double t = ball_touch_triangle(q->o, q->d, q->r, corner(tri, 0), corner(tri, 1), corner(tri, 2));
  if (!(t < q->t)) return;
  q->t = t;
  RTCRayHit* hit = reinterpret_cast<RTCRayHit*>(args->rayhit);  // N = 1: rtcIntersect1
  hit->ray.tfar = std::min(hit->ray.tfar, float_above(t + q->slack));
  hit->hit.geomID = args->geomID, hit->hit.primID = args->primID;
}

}  // namespace

bool MeshDistance::Impl::nearest(const Eigen::Vector3d& p, double radius, Eigen::Vector3d& foot, std::size_t& tri) const {
  NearestQuery q{&tris, p, 1e-6 * (1 + p.cwiseAbs().maxCoeff())};
  RTCPointQuery query;
  query.x = static_cast<float>(p.x()), query.y = static_cast<float>(p.y()), query.z = static_cast<float>(p.z());
  query.time = 0;
  query.radius = std::isfinite(radius) ? float_above(radius + q.slack) : std::numeric_limits<float>::infinity();
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(scene, &query, &context, nearer_triangle, &q);
  if (q.tri == std::numeric_limits<std::size_t>::max()) return false;
  foot = q.foot, tri = q.tri;
  return true;
}

RTCScene MeshDistance::Impl::grown_by(double radius) {
  std::lock_guard<std::mutex> lock(grown_mutex);
  for (const auto& [r, grown_scene] : grown)
    if (r == radius) return grown_scene;
  // The float ray may be off the double one by its rounding: a little more than the radius.
  GrownTriangles* user = &grown_boxes.emplace_back(GrownTriangles{&tris, radius * (1 + 1e-6) + 1e-6});
  RTCScene grown_scene = rtcNewScene(embree_device());
  RTCGeometry boxes = rtcNewGeometry(embree_device(), RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(boxes, static_cast<unsigned>(tris.size()));
  rtcSetGeometryUserData(boxes, user);
  rtcSetGeometryBoundsFunction(boxes, grown_triangle_box, nullptr);
  rtcSetGeometryIntersectFunction(boxes, touch_triangle);
  rtcCommitGeometry(boxes);
  rtcAttachGeometry(grown_scene, boxes);
  rtcReleaseGeometry(boxes);
  rtcCommitScene(grown_scene);
  if (rtcGetDeviceError(embree_device()) != RTC_ERROR_NONE)
    throw std::runtime_error("Embree could not build the search of the mesh's " + std::to_string(tris.size()) +
                             " triangles grown by " + std::to_string(radius) + " mm (out of memory?)");
  grown.emplace_back(radius, grown_scene);
  return grown_scene;
}

// A face of a moved mesh whose normal is within 10 degrees of its unmoved place's tells the side.
constexpr double kTrustedTurnCos = 0.98480775301220802;  // cos 10 degrees

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The pseudo-normals of the triangles (fanned from each polygon's first corner, `triangles`) from
// the polygons' unit normals, trusting the faces not `folded`.
SideNormals side_normals(const Mesh& mesh, const MeshEdges& edges, const std::vector<Eigen::Vector3d>& normal,
                         const std::vector<char>& folded, std::size_t triangle_count) {
  SideNormals out;
  const Eigen::Vector3d none = Eigen::Vector3d::Constant(kNaN);
  const auto trusted = [&](std::size_t f) { return !folded[f] && normal[f].allFinite(); };
  // A mesh edge's: the sum of its two faces' normals, when it has exactly two, both trusted.
  const auto mesh_edge_normal = [&](std::uint32_t a, std::uint32_t b) -> Eigen::Vector3d {
    const auto e = edges.find(a, b);
    if (!e || edges.faces_on(*e) != 2) return none;
    const std::uint32_t f = edges.faces(*e)[0], g = edges.faces(*e)[1];
    return trusted(f) && trusted(g) ? Eigen::Vector3d(normal[f] + normal[g]) : none;
  };
  out.edge.assign(triangle_count * 3, none);
  out.corner_vertex.assign(triangle_count * 3, 0);
  std::size_t t = 0;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const std::size_t n = mesh.face_size(f);
    const std::uint32_t* v = mesh.face(f);
    for (std::size_t k = 1; k + 1 < n; ++k, ++t) {
      const std::uint32_t c[3] = {v[0], v[k], v[k + 1]};
      for (int j = 0; j < 3; ++j) out.corner_vertex[3 * t + j] = c[j];
      // edge opposite corner 0: a side of the polygon; opposite 1 and 2: a side, or a diagonal of
      // the fan inside the face (its own normal)
      out.edge[3 * t] = mesh_edge_normal(c[1], c[2]);
      const Eigen::Vector3d inside = trusted(f) ? Eigen::Vector3d(2 * normal[f]) : none;
      out.edge[3 * t + 1] = k + 2 == n ? mesh_edge_normal(c[2], c[0]) : inside;
      out.edge[3 * t + 2] = k == 1 ? mesh_edge_normal(c[0], c[1]) : inside;
    }
  }
  // A corner's: its faces' normals weighted by their angles there, when the faces around it are
  // trusted and one walk across its edges passes each of them once and comes back.
  const VertexFaces around = vertex_faces(mesh);
  out.vertex.assign(mesh.vertices.size(), none);
  for (std::size_t vi = 0; vi < mesh.vertices.size(); ++vi) {
    const std::size_t count = around.count(vi);
    if (count < 3) continue;
    const auto corner_of = [&](std::uint32_t f) -> int {  // -1: not once
      int at = -1;
      for (std::size_t c = 0; c < mesh.face_size(f); ++c)
        if (mesh.face(f)[c] == vi) {
          if (at >= 0) return -1;
          at = int(c);
        }
      return at;
    };
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    bool ok = true;
    for (std::size_t i = 0; i < count && ok; ++i) {
      const std::uint32_t f = around.faces(vi)[i];
      const int c = corner_of(f);
      ok = c >= 0 && trusted(f);
      if (!ok) break;
      const std::size_t n = mesh.face_size(f);
      const Eigen::Vector3d& p = mesh.vertices[vi];
      const Eigen::Vector3d a = (mesh.vertices[mesh.face(f)[(c + n - 1) % n]] - p).normalized(),
                            b = (mesh.vertices[mesh.face(f)[(c + 1) % n]] - p).normalized();
      sum += std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * normal[f];
    }
    if (!ok) continue;
    // the walk: from a face, across the edge to its corner's next vertex, into the face beyond
    std::uint32_t f = around.faces(vi)[0];
    std::size_t steps = 0;
    do {
      const int c = corner_of(f);
      const auto e = edges.find(std::uint32_t(vi), mesh.face(f)[(std::size_t(c) + 1) % mesh.face_size(f)]);
      if (c < 0 || !e || edges.faces_on(*e) != 2) break;
      f = edges.faces(*e)[0] == f ? edges.faces(*e)[1] : edges.faces(*e)[0];
      ++steps;
    } while (f != around.faces(vi)[0] && steps <= count);
    if (f == around.faces(vi)[0] && steps == count && sum.norm() > 1e-12) out.vertex[vi] = sum;
  }
  return out;
}

}  // namespace

MeshDistance::MeshDistance(const Mesh& mesh, const Mesh* unmoved, std::span<const std::size_t> untrusted)
    : impl_(std::make_shared<Impl>()) {
  if (unmoved && !unmoved->same_faces(mesh))
    throw std::invalid_argument("the unmoved mesh's faces differ from the mesh's");
  for (const std::size_t f : untrusted)
    if (f >= mesh.num_faces())
      throw std::invalid_argument("untrusted face " + std::to_string(f) + " is past the mesh's " +
                                  std::to_string(mesh.num_faces()) + " faces");
  impl_->tris = triangles(mesh);
  impl_->face_of.reserve(impl_->tris.size());
  for (std::size_t f = 0; f < mesh.num_faces(); ++f)
    for (std::size_t k = 1; k + 1 < mesh.face_size(f); ++k) impl_->face_of.push_back(f);
  if (impl_->tris.empty()) return;
  // A face whose normal is turned more than 150 degrees from a neighbour's is folded back onto it
  // (block.off has slivers at 177 degrees): its normal does not tell which side is outside.
  impl_->folded.assign(mesh.num_faces(), 0);
  std::vector<Eigen::Vector3d> normal(mesh.num_faces());
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) normal[f] = face_area_vector(mesh, f).normalized();
  const MeshEdges edges = mesh_edges(mesh);
  for (std::size_t e = 0; e < edges.size(); ++e)
    for (std::size_t i = 0; i < edges.faces_on(e); ++i)
      for (std::size_t j = i + 1; j < edges.faces_on(e); ++j)
        if (normal[edges.faces(e)[i]].dot(normal[edges.faces(e)[j]]) < -0.866)
          impl_->folded[edges.faces(e)[i]] = impl_->folded[edges.faces(e)[j]] = 1;
  // Turned by the moves: the fandisk cloud's outer mesh had a face turned 111 degrees that
  // crossed its neighbours, and a ball centre 2.3 mm outside the part read 2.0 mm inside by it;
  // its noisy cloud's, one turned 82 degrees (4.0 mm). A face turned less than 90 degrees may
  // cross its neighbours too (a search over two moved corners of a cube's face found its normal
  // wrong at turns down to 43 degrees), so every face turned more than 10 goes to the rays.
  if (unmoved)
    for (std::size_t f = 0; f < mesh.num_faces(); ++f)
      if (!(normal[f].dot(face_area_vector(*unmoved, f).normalized()) >= kTrustedTurnCos)) impl_->folded[f] = 1;
  for (const std::size_t f : untrusted) impl_->folded[f] = 1;
  impl_->side = side_normals(mesh, edges, normal, impl_->folded, impl_->tris.size());
  if (impl_->tris.size() > std::numeric_limits<unsigned>::max() - 1)
    throw std::invalid_argument("a mesh of more than 4 billion triangles cannot be searched");
  impl_->scene = rtcNewScene(embree_device());
  RTCGeometry boxes = rtcNewGeometry(embree_device(), RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(boxes, static_cast<unsigned>(impl_->tris.size()));
  rtcSetGeometryUserData(boxes, &impl_->tris);
  rtcSetGeometryBoundsFunction(boxes, triangle_box, nullptr);
  rtcCommitGeometry(boxes);
  rtcAttachGeometry(impl_->scene, boxes);
  rtcReleaseGeometry(boxes);
  rtcCommitScene(impl_->scene);
  if (rtcGetDeviceError(embree_device()) != RTC_ERROR_NONE)
    throw std::runtime_error("Embree could not build the search of the mesh's " + std::to_string(impl_->tris.size()) +
                             " triangles (out of memory?)");
}

struct MeshDistance::HeldPoints {
  std::vector<Eigen::Vector3d> points;
  double margin;
  PointsAdaptor<Eigen::Vector3d> adaptor{points};
  KdTree<Eigen::Vector3d, 3> tree{3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)};
  HeldPoints(std::vector<Eigen::Vector3d> p, double m) : points(std::move(p)), margin(m) { tree.buildIndex(); }
};

MeshDistance MeshDistance::with_points(const std::vector<Eigen::Vector3d>& points, double margin) const {
  for (const auto& p : points)
    if (!p.allFinite()) throw std::invalid_argument("a point the part holds is not finite");
  if (!(margin >= 0) || !std::isfinite(margin)) throw std::invalid_argument("the margin about held points must be >= 0");
  MeshDistance d;
  d.impl_ = impl_;
  d.held_ = held_;
  d.placed_ = placed_, d.rotation_ = rotation_, d.translation_ = translation_;
  if (!points.empty()) d.held_.push_back(std::make_shared<const HeldPoints>(points, margin));
  return d;
}

double MeshDistance::to_held_points(const Eigen::Vector3d& p) const {
  double least = std::numeric_limits<double>::infinity();
  for (const auto& set : held_) {
    std::uint32_t i = 0;
    double d2 = 0;
    set->tree.knnSearch(p.data(), 1, &i, &d2);
    least = std::min(least, std::sqrt(d2) - set->margin);
  }
  return least;
}

MeshDistance::~MeshDistance() = default;
MeshDistance::MeshDistance(MeshDistance&&) noexcept = default;
MeshDistance& MeshDistance::operator=(MeshDistance&&) noexcept = default;

MeshDistance MeshDistance::placed(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) const {
  MeshDistance d;
  d.impl_ = impl_;
  d.held_ = held_;
  d.placed_ = true;
  // Placed twice: the motions composed.
  d.rotation_ = rotation * rotation_;
  d.translation_ = rotation * translation_ + translation;
  return d;
}

double MeshDistance::operator()(const Eigen::Vector3d& p) const { return unsigned_in_mesh(to_mesh(p)); }

double MeshDistance::unsigned_in_mesh(const Eigen::Vector3d& p) const {
  return std::min(faces_unsigned(p), to_held_points(p));
}

// The nearest point of the faces (the mesh's frame), searched within `radius` of p; p refused
// when it is not finite.
Eigen::Vector3d MeshDistance::foot_in_mesh(const Eigen::Vector3d& p, double radius, std::size_t& tri) const {
  point(p);
  Eigen::Vector3d foot;
  // A hint's radius holds the nearest point unless rounding lost it: then the whole search.
  if (!impl_->nearest(p, radius, foot, tri)) impl_->nearest(p, std::numeric_limits<double>::infinity(), foot, tri);
  return foot;
}

double MeshDistance::faces_unsigned(const Eigen::Vector3d& p) const {
  if (impl_->tris.empty()) return std::numeric_limits<double>::infinity();
  std::size_t tri;
  return (foot_in_mesh(p, std::numeric_limits<double>::infinity(), tri) - p).norm();
}

double MeshDistance::unsigned_near(const Eigen::Vector3d& p, Eigen::Vector3d& near, bool& has_near) const {
  const double to_points = to_held_points(p);
  if (impl_->tris.empty()) return to_points;
  std::size_t tri;
  near = foot_in_mesh(p, has_near ? (near - p).norm() : std::numeric_limits<double>::infinity(), tri);
  has_near = true;
  return std::min(to_points, (near - p).norm());
}

double MeshDistance::operator()(const Eigen::Vector3d& p, const Eigen::Vector3d& hint) const {
  const Eigen::Vector3d q = to_mesh(p);
  if (impl_->tris.empty()) return to_held_points(q);
  std::size_t tri;
  return std::min((foot_in_mesh(q, (to_mesh(hint) - q).norm(), tri) - q).norm(), to_held_points(q));
}

Eigen::Vector3d MeshDistance::closest_point(const Eigen::Vector3d& p) const {
  if (impl_->tris.empty()) return p;
  std::size_t tri;
  return from_mesh(foot_in_mesh(to_mesh(p), std::numeric_limits<double>::infinity(), tri));
}

std::size_t MeshDistance::closest_face(const Eigen::Vector3d& p) const {
  Eigen::Vector3d at;
  return closest_face(p, at);
}

std::size_t MeshDistance::closest_face(const Eigen::Vector3d& p, Eigen::Vector3d& at) const {
  at = p;
  if (impl_->tris.empty()) return std::numeric_limits<std::size_t>::max();
  std::size_t tri;
  at = from_mesh(foot_in_mesh(to_mesh(p), std::numeric_limits<double>::infinity(), tri));
  return impl_->face_of[tri];
}

double MeshDistance::ray_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& d) const {
  if (impl_->tris.empty()) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d dm = placed_ ? Eigen::Vector3d(rotation_.transpose() * d) : d;
  const Kernel::Ray_3 ray(point(to_mesh(p)), Kernel::Direction_3(dm.x(), dm.y(), dm.z()));
  const auto hit = impl_->ray_tree().first_intersection(ray);
  if (!hit) return std::numeric_limits<double>::infinity();
  if (const Kernel::Point_3* q = boost::get<Kernel::Point_3>(&hit->first))
    return std::sqrt(CGAL::squared_distance(*q, ray.source()));
  return 0;  // the ray runs along a face from p
}

double MeshDistance::signed_distance(const Eigen::Vector3d& p) const { return signed_in_mesh(to_mesh(p)); }

double MeshDistance::signed_in_mesh(const Eigen::Vector3d& p) const {
  return std::min(faces_signed(p), to_held_points(p));
}

double MeshDistance::faces_signed(const Eigen::Vector3d& p) const {
  if (impl_->tris.empty()) return std::numeric_limits<double>::infinity();
  const Kernel::Point_3 q = point(p);
  std::size_t tri;
  const Eigen::Vector3d foot_at = foot_in_mesh(p, std::numeric_limits<double>::infinity(), tri);
  const Kernel::Point_3 foot(foot_at.x(), foot_at.y(), foot_at.z());
  const double d = (foot_at - p).norm();
  // A point on the mesh (a cloud point that is one of a reconstruction's vertices) has no side to
  // find, and rays from it graze its own faces, which CGAL then decides in exact arithmetic: that
  // was most of mesh.cloud_envelope's time.
  if (d <= 1e-9) return d;
  const Kernel::Triangle_3& t = impl_->tris[tri];
  const bool folded = impl_->folded[impl_->face_of[tri]];
  const Kernel::Vector_3 normal = CGAL::cross_product(t[1] - t[0], t[2] - t[0]);
  // Barycentric coordinates of the foot: all clearly positive = inside the face.
  const double area2 = normal.squared_length();
  if (!(area2 > 0)) return inside_in_mesh(p) ? -d : d;
  double bary[3];
  int on_side = 0;  // how many are not clearly positive: 1 on an edge, 2 at a corner
  for (int k = 0; k < 3; ++k) {
    const Kernel::Vector_3 nk = CGAL::cross_product(t[(k + 2) % 3] - t[(k + 1) % 3], foot - t[(k + 1) % 3]);
    bary[k] = nk * normal / area2;
    on_side += bary[k] <= 1e-9;
  }
  // A folded face is left to the rays: by its normal alone a ball centre 5.7 mm outside block.off
  // read as a 7.7 mm gouge.
  if (on_side == 0) {
    if (!folded) return (q - foot) * normal < 0 ? -d : d;
    return inside_in_mesh(p) ? -d : d;
  }
  // On an edge or at a corner: its pseudo-normal's side where its faces are trusted (the same as
  // the rays' on a closed surface, without them: the rays were a sixth of the block cloud's
  // certificate, mostly beside edges), the rays where not or where it is too near level.
  const int k = int(std::min_element(bary, bary + 3) - bary);
  Eigen::Vector3d side;
  if (on_side == 1) {
    side = impl_->side.edge[3 * tri + k];
  } else {
    const int corner = bary[(k + 1) % 3] > bary[(k + 2) % 3] ? (k + 1) % 3 : (k + 2) % 3;
    side = impl_->side.vertex[impl_->side.corner_vertex[3 * tri + corner]];
  }
  const double s = (p - foot_at).dot(side);
  if (std::abs(s) > 1e-6 * d * side.norm()) return s < 0 ? -d : d;  // (false for NaN)
  return inside_in_mesh(p) ? -d : d;
}

bool MeshDistance::inside_by_rays(const Eigen::Vector3d& p) const {
  return !impl_->tris.empty() && inside_in_mesh(to_mesh(p));
}

bool MeshDistance::inside_in_mesh(const Eigen::Vector3d& p) const {
  const Kernel::Point_3 q = point(p);
  int odd = 0;
  for (const Kernel::Vector_3& dir : {Kernel::Vector_3(0.5773, 0.3131, 0.7544), Kernel::Vector_3(-0.6421, 0.5172, -0.2913),
                                      Kernel::Vector_3(0.1173, -0.8839, 0.3253)})
    odd += impl_->ray_tree().number_of_intersected_primitives(Kernel::Ray_3(q, dir)) % 2;
  return odd >= 2;
}

double MeshDistance::least_along(const Eigen::Vector3d& a_placed, const Eigen::Vector3d& b_placed, double step, double floor,
                                 double eps, Eigen::Vector3d& where, std::size_t& evaluations,
                                 bool is_signed) const {
  // In the mesh's own frame, `where` taken back at the end.
  const Eigen::Vector3d a = to_mesh(a_placed), b = to_mesh(b_placed);
  Eigen::Vector3d near;
  bool has_near = false;
  auto distance = [&](const Eigen::Vector3d& p) { return is_signed ? signed_in_mesh(p) : unsigned_near(p, near, has_near); };
  const double L = (b - a).norm();
  const int k = std::max(1, static_cast<int>(std::ceil(L / step)));
  std::vector<double> d(k + 1);
  for (int i = 0; i <= k; ++i) d[i] = distance(a + (b - a) * (double(i) / k));
  evaluations += k + 1;
  const auto least_at = std::min_element(d.begin(), d.end());
  double least = *least_at, bound = least;
  where = a + (b - a) * (double(least_at - d.begin()) / k);
  std::vector<std::array<double, 4>> todo;  // t0, t1, d0, d1
  for (int i = 0; i < k; ++i) todo.push_back({double(i) / k, double(i + 1) / k, d[i], d[i + 1]});
  // Below the floor the least is pinned to eps or to a thousandth of its depth under the floor,
  // whichever is more: a move 8 mm into the part is known to 8 um; to eps, a stretch where the
  // distance is flat and negative (no curvature bound there) would take L / (2 eps) distances.
  // And at most `budget` halvings: a signed distance that flips sign without passing zero (a mesh
  // whose inside is ambiguous: faces inside the part, solids that overlap) defeats the bounds
  // everywhere it flips (37 million distances for 3 713 moves of the ABC plate before its solids
  // were merged). Past the budget each stretch left keeps its bound: still a lower bound.
  std::size_t budget = 4096 + 64 * std::size_t(k);
  while (!todo.empty()) {
    const auto [t0, t1, d0, d1] = todo.back();
    todo.pop_back();
    const double gap = (t1 - t0) * L;
    const double lower = least_between(d0, d1, gap);
    const double precision = std::max(eps, 1e-3 * (floor - least));
    if (lower >= std::min(floor, least - precision) || gap < 1e-6 || budget == 0) {
      if (lower < floor) bound = std::min(bound, lower);
      continue;
    }
    const double tm = 0.5 * (t0 + t1);
    const double dm = distance(a + (b - a) * tm);
    ++evaluations, --budget;
    if (dm < least) least = dm, where = a + (b - a) * tm;
    bound = std::min(bound, least);
    todo.push_back({t0, tm, d0, dm});
    todo.push_back({tm, t1, dm, d1});
  }
  where = from_mesh(where);
  return bound;
}

double MeshDistance::least_on_segment(const Eigen::Vector3d& a_placed, const Eigen::Vector3d& b_placed,
                                      Eigen::Vector3d& where) const {
  const Eigen::Vector3d a = to_mesh(a_placed), b = to_mesh(b_placed);
  point(a), point(b);  // refuses a point that is not finite
  double least = std::numeric_limits<double>::infinity();
  where = a;
  // Pieces no longer than the distance at their middle (at most 64 of them), each searched once.
  std::vector<std::array<double, 2>> todo{{0.0, 1.0}};
  const double L = (b - a).norm();
  while (!todo.empty()) {
    const auto [t0, t1] = todo.back();
    todo.pop_back();
    const Eigen::Vector3d p = a + t0 * (b - a), q = a + t1 * (b - a), m = 0.5 * (p + q);
    const double at_middle = unsigned_in_mesh(m);
    if ((t1 - t0) * L > std::max(at_middle, 1e-3) && (t1 - t0) > 1.0 / 64) {
      todo.push_back({t0, 0.5 * (t0 + t1)});
      todo.push_back({0.5 * (t0 + t1), t1});
      continue;
    }
    least_on_piece(p, q, at_middle, least, where);
  }
  where = from_mesh(where);
  return least;
}

void MeshDistance::least_on_piece(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double distance, double& least,
                                  Eigen::Vector3d& where) const {
  const Eigen::Vector3d m = 0.5 * (a + b);
  const double half = 0.5 * (b - a).norm();
  // Nothing nearer the segment than `bound` lies beyond half + bound of its middle.
  const double bound = std::min(least, distance + half);
  if (!impl_->tris.empty()) {
    SegmentQuery q{&impl_->tris, a, b, half, 1e-6 * (1 + m.cwiseAbs().maxCoeff()), least, where};
    RTCPointQuery query;
    query.x = static_cast<float>(m.x()), query.y = static_cast<float>(m.y()), query.z = static_cast<float>(m.z());
    query.time = 0;
    query.radius = std::isfinite(bound) ? float_above(half + bound + q.slack) : std::numeric_limits<float>::infinity();
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    rtcPointQuery(impl_->scene, &query, &context, nearer_to_segment, &q);
    least = q.least, where = q.where;
  }
  for (const auto& set : held_) {
    const double radius = half + std::min(least, bound) + set->margin;
    if (!std::isfinite(radius)) continue;
    std::vector<std::pair<std::uint32_t, double>> found;
    set->tree.radiusSearch(m.data(), radius * radius * (1 + 1e-12), found, nanoflann::SearchParams(32, 0, false));
    for (const auto& f : found) {
      const Eigen::Vector3d on = closest_on_segment(set->points[f.first], a, b);
      if (const double d = (on - set->points[f.first]).norm() - set->margin; d < least) least = d, where = on;
    }
  }
}

double MeshDistance::touch_along(const Eigen::Vector3d& c_placed, const Eigen::Vector3d& d_placed, double r,
                                 double max) const {
  if (!(r > 0) || !std::isfinite(r)) throw std::invalid_argument("a ball's radius must be > 0");
  if (!(max >= 0)) throw std::invalid_argument("how far a ball moves must be >= 0");
  const Eigen::Vector3d o = to_mesh(c_placed);
  const Eigen::Vector3d d = placed_ ? Eigen::Vector3d(rotation_.transpose() * d_placed) : d_placed;
  point(o), point(d);  // refuses a point that is not finite
  if (!(unsigned_in_mesh(o) > r)) return 0;
  double t = max;
  if (!impl_->tris.empty()) {
    TouchQuery q;
    rtcInitIntersectContext(&q.context);
    q.tris = &impl_->tris, q.o = o, q.d = d, q.r = r, q.t = std::numeric_limits<double>::infinity();
    q.slack = 1e-6 * (1 + o.cwiseAbs().maxCoeff() + (std::isfinite(max) ? max : 0.0));
    RTCRayHit hit;
    hit.ray.org_x = static_cast<float>(o.x()), hit.ray.org_y = static_cast<float>(o.y()), hit.ray.org_z = static_cast<float>(o.z());
    hit.ray.dir_x = static_cast<float>(d.x()), hit.ray.dir_y = static_cast<float>(d.y()), hit.ray.dir_z = static_cast<float>(d.z());
    hit.ray.tnear = 0;
    hit.ray.tfar = std::isfinite(max) ? float_above(max + q.slack) : std::numeric_limits<float>::infinity();
    hit.ray.time = 0, hit.ray.mask = 0xFFFFFFFF, hit.ray.id = 0, hit.ray.flags = 0;
    hit.hit.geomID = RTC_INVALID_GEOMETRY_ID, hit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->grown_by(r), &q.context, &hit);
    t = std::min(t, q.t);
  }
  // The held points: balls of r plus their margin about each, searched along the way in pieces
  // no longer than 2 r.
  for (const auto& set : held_) {
    const double reach = r + set->margin;
    const int pieces = std::isfinite(t) ? std::max(1, static_cast<int>(std::ceil(t / (2 * r)))) : 0;
    std::vector<std::pair<std::uint32_t, double>> found;
    for (int k = 0; k < pieces; ++k) {
      const double from = t * k / pieces, to = t * (k + 1) / pieces;
      if (from >= t) break;
      const Eigen::Vector3d m = o + (0.5 * (from + to)) * d;
      const double radius = 0.5 * (to - from) + reach;
      set->tree.radiusSearch(m.data(), radius * radius * (1 + 1e-12), found, nanoflann::SearchParams(32, 0, false));
      for (const auto& f : found) t = std::min(t, ball_touch_point(o, d, reach, set->points[f.first]));
    }
  }
  return t;
}

bool MeshDistance::clear_along(const Eigen::Vector3d& a_placed, const Eigen::Vector3d& b_placed, double step,
                               double floor, std::size_t* evaluations) const {
  const Eigen::Vector3d a = to_mesh(a_placed), b = to_mesh(b_placed);
  point(a), point(b);  // refuses a point that is not finite
  const double L = (b - a).norm();
  Eigen::Vector3d near;
  bool has_near = false;
  std::size_t asked = 0;
  auto distance = [&](double t) {
    ++asked;
    return unsigned_near(a + (b - a) * (L > 0 ? t / L : 0.0), near, has_near);
  };
  std::size_t budget = 4096 + 64 * std::size_t(std::ceil(L / step));
  auto answer = [&](bool clear) {
    if (evaluations) *evaluations += asked;
    return clear;
  };
  double t0 = 0, d0 = distance(0);
  if (!(d0 >= floor)) return answer(false);
  std::vector<std::array<double, 4>> todo;  // s0, s1, d0, d1 (arc length)
  while (t0 < L) {
    const double t1 = std::min(L, t0 + std::max(step, d0 - floor));
    const double d1 = distance(t1);
    if (!(d1 >= floor)) return answer(false);
    todo.push_back({t0, t1, d0, d1});
    while (!todo.empty()) {
      const auto [s0, s1, e0, e1] = todo.back();
      todo.pop_back();
      const double gap = s1 - s0;
      const double lower = least_between(e0, e1, gap);
      if (lower >= floor) continue;
      if (gap < 1e-6 || budget == 0) return answer(false);
      --budget;
      const double sm = 0.5 * (s0 + s1), dm = distance(sm);
      if (!(dm >= floor)) return answer(false);
      todo.push_back({s0, sm, e0, dm});
      todo.push_back({sm, s1, dm, e1});
    }
    t0 = t1, d0 = d1;
  }
  return answer(true);
}

std::vector<double> distances_to_mesh(const std::vector<Eigen::Vector3d>& points, const Mesh& m) {
  const MeshDistance distance(m);
  std::vector<double> d(points.size());
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) { d[i] = distance(points[i]); });
  return d;
}

}  // namespace scallop
