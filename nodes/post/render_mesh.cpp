#include "nodes/post/render_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "nodes/mesh/mesh_topology.h"

namespace scallop {
namespace {

using RGB = std::array<double, 3>;

// A camera: screen x right, screen y up, depth away from the viewer.
struct Camera {
  Eigen::Vector3d right, up, forward;
  explicit Camera(const std::string& view) {
    if (view == "iso") {
      forward = Eigen::Vector3d(1, 1, -1).normalized();
      right = Eigen::Vector3d(1, -1, 0).normalized();
    } else if (view == "back") {
      forward = Eigen::Vector3d(-1, -1, -1).normalized();
      right = Eigen::Vector3d(-1, 1, 0).normalized();
    } else if (view == "top") {
      forward = Eigen::Vector3d(0, 0, -1);
      right = Eigen::Vector3d(1, 0, 0);
    } else if (view == "front") {
      forward = Eigen::Vector3d(0, 1, 0);
      right = Eigen::Vector3d(1, 0, 0);
    } else {
      throw std::invalid_argument("unknown view '" + view + "' (iso, back, top or front)");
    }
    up = right.cross(forward);
  }
  Eigen::Vector3d project(const Eigen::Vector3d& p) const { return {p.dot(right), p.dot(up), p.dot(forward)}; }
};

// Distinct, readable colours for labels (cycled).
RGB label_colour(int label) {
  static const RGB palette[] = {{0.12, 0.47, 0.71}, {1.00, 0.50, 0.05}, {0.17, 0.63, 0.17}, {0.58, 0.40, 0.74},
                                {0.55, 0.34, 0.29}, {0.89, 0.47, 0.76}, {0.74, 0.74, 0.13}, {0.09, 0.75, 0.81},
                                {0.68, 0.78, 0.91}, {1.00, 0.73, 0.47}, {0.60, 0.87, 0.54}, {0.77, 0.69, 0.84}};
  if (label < 0) return {0.75, 0.75, 0.75};
  return palette[label % static_cast<int>(std::size(palette))];
}

struct Raster {
  int w, h;
  std::vector<double> depth;
  std::vector<RGB> colour;
  Raster(int w_, int h_) : w(w_), h(h_), depth(std::size_t(w_) * h_, std::numeric_limits<double>::infinity()),
                           colour(std::size_t(w_) * h_, RGB{1, 1, 1}) {}
  // A triangle in screen space (x, y pixels, z depth), flat colour, depth-tested.
  void triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const RGB& col) {
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) return;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double wa = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
        const double wb = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
        const double wc = 1 - wa - wb;
        if (wa < 0 || wb < 0 || wc < 0) continue;
        const double z = wa * a.z() + wb * b.z() + wc * c.z();
        const std::size_t i = std::size_t(y) * w + x;
        if (z < depth[i]) depth[i] = z, colour[i] = col;
      }
  }
  // A line of `thick` pixels, drawn where it is not behind a face by more than `bias`.
  void line(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const RGB& col, int thick, double bias) {
    const int n = static_cast<int>(std::ceil(std::max(std::abs(b.x() - a.x()), std::abs(b.y() - a.y())))) + 1;
    for (int s = 0; s <= n; ++s) {
      const Eigen::Vector3d p = a + (b - a) * (double(s) / n);
      for (int dy = 0; dy < thick; ++dy)
        for (int dx = 0; dx < thick; ++dx) {
          const int x = static_cast<int>(p.x()) + dx - thick / 2, y = static_cast<int>(p.y()) + dy - thick / 2;
          if (x < 0 || y < 0 || x >= w || y >= h) continue;
          const std::size_t i = std::size_t(y) * w + x;
          if (p.z() <= depth[i] + bias) colour[i] = col;
        }
    }
  }
};

}  // namespace

Picture render_mesh(const Mesh& mesh, const MeshPictureOptions& o) {
  if (mesh.num_faces() == 0) throw std::invalid_argument("the mesh has no faces");
  const Camera cam(o.view);
  std::vector<Eigen::Vector3d> q(mesh.num_vertices());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (std::size_t v = 0; v < q.size(); ++v) {
    q[v] = cam.project(mesh.vertices[v]);
    lo = lo.cwiseMin(q[v]), hi = hi.cwiseMax(q[v]);
  }
  for (const auto& line : o.overlays)  // arrows may reach past the mesh: keep them in the frame
    for (const auto& p : line.points) lo = lo.cwiseMin(cam.project(p)), hi = hi.cwiseMax(cam.project(p));
  const int pad = 10, width = std::max(64, o.width);
  const Eigen::Vector3d ext = (hi - lo).cwiseMax(1e-9);
  double scale = (width - 2 * pad) / ext.x();
  const int height = std::clamp(static_cast<int>(std::ceil(ext.y() * scale)) + 2 * pad, 16, 8000);
  scale = std::min(scale, (height - 2 * pad) / ext.y());
  for (auto& p : q) p = Eigen::Vector3d(pad + (p.x() - lo.x()) * scale, height - pad - (p.y() - lo.y()) * scale, p.z());

  Raster r(width, height);
  const bool labels = o.by_label && mesh.has_labels();
  const Eigen::Vector3d light = (-cam.forward + 0.35 * cam.up - 0.25 * cam.right).normalized();
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    // Newell normal of the polygon, lit by a headlight a little from the upper left.
    const Eigen::Vector3d n = face_area_vector(mesh, f);
    const std::size_t m = mesh.face_size(f);
    const double lambert = n.norm() > 0 ? std::abs(n.normalized().dot(light)) : 0.0;
    const RGB base = o.face_colours.size() == mesh.num_faces() ? o.face_colours[f]
                     : labels                                  ? label_colour(mesh.face_label[f])
                                                               : RGB{0.62, 0.70, 0.80};
    const double shade = 0.25 + 0.75 * lambert;
    const RGB col{base[0] * shade, base[1] * shade, base[2] * shade};
    for (std::size_t c = 1; c + 1 < m; ++c)  // a fan: polygons are convex enough for a picture
      r.triangle(q[mesh.face(f)[0]], q[mesh.face(f)[c]], q[mesh.face(f)[c + 1]], col);
  }
  const double bias = 0.01 * ext.z() + 1e-9;
  if (o.wireframe)
    for (std::size_t f = 0; f < mesh.num_faces(); ++f)
      for (std::size_t c = 0; c < mesh.face_size(f); ++c)
        r.line(q[mesh.face(f)[c]], q[mesh.face(f)[(c + 1) % mesh.face_size(f)]], {0.2, 0.2, 0.25}, 1, bias);
  for (const auto& e : mesh.feature_edges) r.line(q[e[0]], q[e[1]], {0.85, 0.05, 0.05}, 2, bias);
  auto screen = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d c = cam.project(p);
    return Eigen::Vector3d(pad + (c.x() - lo.x()) * scale, height - pad - (c.y() - lo.y()) * scale, c.z());
  };
  for (const auto& o_line : o.overlays) {
    if (o_line.points.empty()) continue;
    if (o_line.whole_if_start_seen) {
      const Eigen::Vector3d s = screen(o_line.points[0]);
      const int x = static_cast<int>(s.x()), y = static_cast<int>(s.y());
      if (x < 0 || y < 0 || x >= width || y >= height || s.z() > r.depth[std::size_t(y) * width + x] + bias) continue;
    }
    const double line_bias = o_line.whole_if_start_seen ? std::numeric_limits<double>::infinity() : bias;
    for (std::size_t k = 1; k < o_line.points.size(); ++k)
      r.line(screen(o_line.points[k - 1]), screen(o_line.points[k]), o_line.colour, o_line.thick, line_bias);
  }

  Picture pic;
  pic.width = width, pic.height = height;
  pic.rgb.resize(std::size_t(width) * height * 3);
  for (std::size_t i = 0; i < r.colour.size(); ++i)
    for (int k = 0; k < 3; ++k)
      pic.rgb[3 * i + k] = static_cast<std::uint8_t>(std::lround(255 * std::clamp(r.colour[i][k], 0.0, 1.0)));
  return pic;
}

std::string svg_of_png(const Picture& picture, const std::string& png) {
  static const char* const digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string b64;
  b64.reserve((png.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < png.size(); i += 3) {
    const std::uint32_t n = (std::uint32_t(std::uint8_t(png[i])) << 16) |
                            (i + 1 < png.size() ? std::uint32_t(std::uint8_t(png[i + 1])) << 8 : 0) |
                            (i + 2 < png.size() ? std::uint32_t(std::uint8_t(png[i + 2])) : 0);
    b64 += digits[(n >> 18) & 63];
    b64 += digits[(n >> 12) & 63];
    b64 += i + 1 < png.size() ? digits[(n >> 6) & 63] : '=';
    b64 += i + 2 < png.size() ? digits[n & 63] : '=';
  }
  const std::string w = std::to_string(picture.width), h = std::to_string(picture.height);
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + w + "\" height=\"" + h + "\" viewBox=\"0 0 " + w +
         " " + h + "\">\n<image width=\"" + w + "\" height=\"" + h + "\" href=\"data:image/png;base64," + b64 +
         "\"/>\n</svg>\n";
}

}  // namespace scallop
