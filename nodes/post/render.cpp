#include "nodes/post/render.h"
#include "nodes/post/render_mesh.h"

#include <png.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace scallop {
namespace {

using RGB = std::array<std::uint8_t, 3>;

// Perceptually ordered ramp (dark violet → blue → teal → green → yellow), t in [0, 1].
RGB ramp(double t) {
  static const double stops[5][3] = {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * 4;
  int i = std::min(3, static_cast<int>(t));
  double f = t - i;
  RGB c;
  for (int k = 0; k < 3; ++k) c[k] = static_cast<std::uint8_t>(std::lround(stops[i][k] * (1 - f) + stops[i + 1][k] * f));
  return c;
}

std::string hex(RGB c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buf;
}

const RGB kWhite{255, 255, 255}, kBlack{0, 0, 0}, kRed{220, 30, 30}, kMagenta{230, 0, 230};
const RGB kPassA{200, 40, 40}, kPassB{240, 120, 0}, kGrey{60, 60, 60};

struct Canvas {
  Picture p;
  Canvas(int w, int h) {
    p.width = w, p.height = h;
    p.rgb.assign(std::size_t(w) * h * 3, 255);
  }
  void set(int x, int y, RGB c) {
    if (x < 0 || y < 0 || x >= p.width || y >= p.height) return;
    std::size_t i = (std::size_t(y) * p.width + x) * 3;
    p.rgb[i] = c[0], p.rgb[i + 1] = c[1], p.rgb[i + 2] = c[2];
  }
  void line(double x0, double y0, double x1, double y1, RGB c) {
    int n = static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))) + 1;
    for (int i = 0; i <= n; ++i) {
      double t = double(i) / n;
      set(static_cast<int>(std::lround(x0 + t * (x1 - x0))), static_cast<int>(std::lround(y0 + t * (y1 - y0))), c);
    }
  }
  // Digits, '.', '-' in a 5×7 font, scaled.
  void text(int x, int y, const std::string& s, int scale, RGB c) {
    static const std::uint8_t digits[10][7] = {
        {14, 17, 19, 21, 25, 17, 14}, {4, 12, 4, 4, 4, 4, 14},   {14, 17, 1, 2, 4, 8, 31},
        {31, 2, 4, 2, 1, 17, 14},     {2, 6, 10, 18, 31, 2, 2},  {31, 16, 30, 1, 1, 17, 14},
        {6, 8, 16, 30, 17, 17, 14},   {31, 1, 2, 4, 8, 8, 8},    {14, 17, 17, 14, 17, 17, 14},
        {14, 17, 17, 15, 1, 2, 12}};
    static const std::uint8_t dot[7] = {0, 0, 0, 0, 0, 12, 12}, minus[7] = {0, 0, 0, 31, 0, 0, 0};
    for (char ch : s) {
      const std::uint8_t* g = ch >= '0' && ch <= '9' ? digits[ch - '0'] : ch == '.' ? dot : ch == '-' ? minus : nullptr;
      if (g)
        for (int r = 0; r < 7; ++r)
          for (int b = 0; b < 5; ++b)
            if (g[r] & (16 >> b))
              for (int dy = 0; dy < scale; ++dy)
                for (int dx = 0; dx < scale; ++dx) set(x + b * scale + dx, y + r * scale + dy, c);
      x += 6 * scale;
    }
  }
};

void png_write_to_string(png_structp png, png_bytep data, png_size_t length) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), length);
}

// 2D projection of the chosen view; depth grows away from the viewer.
struct View {
  bool iso;  // else from the top (the name compared once: a million cloud points are drawn)
  explicit View(const std::string& name) : iso(name == "iso") {}
  Eigen::Vector2d operator()(const Eigen::Vector3d& p) const {
    if (iso) return {(p.x() - p.y()) / std::sqrt(2.0), (p.x() + p.y() + 2 * p.z()) / std::sqrt(6.0)};
    return {p.x(), p.y()};
  }
  double depth(const Eigen::Vector3d& p) const { return iso ? p.x() + p.y() - p.z() : -p.z(); }
};

// Maps model (x, y-up) coordinates to pixels with a margin, keeping the aspect.
struct Frame {
  Eigen::Vector2d lo, hi;
  double scale = 1;
  int width = 0, height = 0, pad = 10;
  Frame(const std::vector<Eigen::Vector2d>& pts, int w) : width(w) {
    lo = Eigen::Vector2d(INFINITY, INFINITY), hi = -lo;
    for (const auto& p : pts) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    Eigen::Vector2d ext = (hi - lo).cwiseMax(1e-9);
    scale = (w - 2 * pad) / ext.x();
    height = std::clamp(static_cast<int>(std::ceil(ext.y() * scale)) + 2 * pad, 16, 8000);
    scale = std::min(scale, (height - 2 * pad) / ext.y());
  }
  Eigen::Vector2d px(const Eigen::Vector2d& p) const {
    return {pad + (p.x() - lo.x()) * scale, height - pad - (p.y() - lo.y()) * scale};
  }
};

struct Scene {
  std::vector<Eigen::Vector2d> cloud_xy;  // projected cloud points, far first
  std::vector<double> cloud_t;            // their shade in [0, 1] (height)
  std::vector<std::vector<Eigen::Vector2d>> passes;
};

Scene make_scene(const Toolpath& path, const PointCloud* cloud, const std::string& view) {
  if (view != "top" && view != "iso" && view != "uv")
    throw std::invalid_argument("unknown view '" + view + "' (top, iso, uv or scallop)");
  Scene s;
  View V{view};
  bool any = false;
  for (const auto& pass : path.passes) {
    std::vector<Eigen::Vector2d> pl;
    if (view == "uv") {
      for (const auto& q : pass.uv) pl.push_back(q);
    } else {
      for (std::size_t i = 0; i < pass.contact.size(); ++i)
        pl.push_back(V(i < pass.normal.size() ? path.tip(pass.contact[i], pass.normal[i]) : pass.contact[i]));
    }
    any |= !pl.empty();
    s.passes.push_back(std::move(pl));
  }
  if (!any)
    throw std::invalid_argument(view == "uv" ? "no pass carries uv coordinates" : "the tool path has no points");
  if (cloud && view != "uv" && cloud->size()) {
    double zl = INFINITY, zh = -INFINITY;
    for (const auto& p : cloud->points) zl = std::min(zl, p.z()), zh = std::max(zh, p.z());
    // farthest first, so nearer points are drawn over them
    std::vector<std::pair<double, std::size_t>> order(cloud->size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = {-V.depth(cloud->points[i]), i};
    std::sort(order.begin(), order.end());
    for (const auto& [key, i] : order) {
      s.cloud_xy.push_back(V(cloud->points[i]));
      s.cloud_t.push_back(zh > zl ? (cloud->points[i].z() - zl) / (zh - zl) : 0.5);
    }
  }
  return s;
}

Frame scene_frame(const Scene& s, int width) {
  std::vector<Eigen::Vector2d> all = s.cloud_xy;
  for (const auto& pl : s.passes) all.insert(all.end(), pl.begin(), pl.end());
  return Frame(all, width);
}

// Light tint of the height ramp, so the paths stand out over the cloud.
RGB tint(double t) {
  RGB c = ramp(t);
  for (auto& v : c) v = static_cast<std::uint8_t>(v / 2 + 110);
  return c;
}

// The colour of a simulated sample.
RGB sample_colour(const SimSample& s, double limit, double gouge_tol) {
  if (s.gouge > gouge_tol) return kBlack;
  if (std::isnan(s.scallop)) return kMagenta;
  if (s.scallop > 1.01 * limit) return kRed;
  return ramp(s.scallop / (1.01 * limit));
}

int severity(const SimSample& s, double limit, double gouge_tol) {
  if (s.gouge > gouge_tol) return 3;
  if (std::isnan(s.scallop)) return 2;
  return s.scallop > 1.01 * limit ? 1 : 0;
}

std::string label(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  return buf;
}

// Cells of a top-view grid over the samples, each with its worst sample.
struct HeatGrid {
  Frame frame;
  double cell;
  int nx, ny;
  std::vector<long> worst;  // index into samples, −1 empty
  HeatGrid(const Simulation& sim, double limit, double gouge_tol, int plot_width)
      : frame(bounds(sim), plot_width) {
    cell = std::max(1.0 / frame.scale, 1.3 * sim.spacing);  // every cell holds a sample
    nx = std::max(1, static_cast<int>(std::ceil((frame.hi.x() - frame.lo.x()) / cell)) + 1);
    ny = std::max(1, static_cast<int>(std::ceil((frame.hi.y() - frame.lo.y()) / cell)) + 1);
    worst.assign(std::size_t(nx) * ny, -1);
    for (std::size_t i = 0; i < sim.samples.size(); ++i) {
      const auto& s = sim.samples[i];
      int cx = std::clamp(static_cast<int>((s.x - frame.lo.x()) / cell), 0, nx - 1);
      int cy = std::clamp(static_cast<int>((s.y - frame.lo.y()) / cell), 0, ny - 1);
      long& w = worst[std::size_t(cy) * nx + cx];
      if (w < 0) {
        w = long(i);
        continue;
      }
      const auto& o = sim.samples[w];
      int a = severity(s, limit, gouge_tol), b = severity(o, limit, gouge_tol);
      double sv = std::isnan(s.scallop) ? 0 : s.scallop, ov = std::isnan(o.scallop) ? 0 : o.scallop;
      if (a > b || (a == b && (a == 3 ? s.gouge > o.gouge : sv > ov))) w = long(i);
    }
  }
  static std::vector<Eigen::Vector2d> bounds(const Simulation& sim) {
    if (sim.samples.empty()) throw std::invalid_argument("the simulation has no samples");
    std::vector<Eigen::Vector2d> b;
    for (const auto& s : sim.samples) b.emplace_back(s.x, s.y);
    return b;
  }
  long at(double x, double y) const {
    int cx = static_cast<int>(std::floor((x - frame.lo.x()) / cell)), cy = static_cast<int>(std::floor((y - frame.lo.y()) / cell));
    if (cx < 0 || cy < 0 || cx >= nx || cy >= ny) return -1;
    return worst[std::size_t(cy) * nx + cx];
  }
};

constexpr int kBar = 110;  // width of the colour-bar strip (px)

// Colour bar at x = bx: 0 at the bottom, 1.01 h at the top (red above), labelled.
void colour_bar(Canvas& c, int bx, double limit, int text_scale) {
  int top = 20, bottom = c.p.height - 20;
  for (int y = top; y <= bottom; ++y) {
    RGB col = ramp(double(bottom - y) / (bottom - top));
    for (int x = bx; x < bx + 20; ++x) c.set(x, y, col);
  }
  for (int y = top - 12; y < top - 2; ++y)
    for (int x = bx; x < bx + 20; ++x) c.set(x, y, kRed);
  const double vals[3] = {0, 0.5 * 1.01 * limit, 1.01 * limit};
  for (int k = 0; k < 3; ++k) {
    int y = bottom - static_cast<int>(std::lround(k * 0.5 * (bottom - top)));
    c.line(bx + 20, y, bx + 24, y, kBlack);
    c.text(bx + 27, y - 7, label(vals[k]), text_scale, kBlack);
  }
}


}  // namespace

std::string encode_png(const Picture& pic) {
  if (pic.width <= 0 || pic.height <= 0 || pic.rgb.size() != std::size_t(pic.width) * pic.height * 3)
    throw std::invalid_argument("picture size does not match its pixels");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) throw std::runtime_error("libpng: cannot create a writer");
  png_infop info = png_create_info_struct(png);
  std::string out;
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    throw std::runtime_error("libpng: error while encoding");
  }
  png_set_write_fn(png, &out, png_write_to_string, nullptr);
  png_set_IHDR(png, info, pic.width, pic.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  // Fast deflate: these are flat-coloured pictures, compressed nearly as well at level 1 (the
  // bundled example's scallop map's encoding at the default level took 0.1 s).
  png_set_compression_level(png, 1);
  png_write_info(png, info);
  for (int y = 0; y < pic.height; ++y)
    png_write_row(png, const_cast<png_bytep>(pic.rgb.data() + std::size_t(y) * pic.width * 3));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

Picture render_path(const Toolpath& path, const PointCloud* cloud, const std::string& view, int width) {
  if (width < 32) throw std::invalid_argument("width must be at least 32 px");
  Scene s = make_scene(path, cloud, view);
  Frame f = scene_frame(s, width);
  Canvas c(f.width, f.height);
  int dot = s.cloud_xy.size() * 4 < std::size_t(f.width) * f.height / 8 ? 2 : 1;  // sparse clouds: bigger dots
  for (std::size_t i = 0; i < s.cloud_xy.size(); ++i) {
    Eigen::Vector2d q = f.px(s.cloud_xy[i]);
    for (int dy = 0; dy < dot; ++dy)
      for (int dx = 0; dx < dot; ++dx) c.set(int(q.x()) + dx, int(q.y()) + dy, tint(s.cloud_t[i]));
  }
  for (std::size_t k = 0; k < s.passes.size(); ++k) {
    const auto& pl = s.passes[k];
    for (std::size_t i = 0; i + 1 < pl.size(); ++i) {
      Eigen::Vector2d a = f.px(pl[i]), b = f.px(pl[i + 1]);
      c.line(a.x(), a.y(), b.x(), b.y(), k % 2 ? kPassB : kPassA);
    }
    if (pl.size() == 1) c.set(int(f.px(pl[0]).x()), int(f.px(pl[0]).y()), kPassA);
  }
  return c.p;
}

std::string render_path_svg(const Toolpath& path, const PointCloud* cloud, const std::string& view, int width) {
  if (width < 32) throw std::invalid_argument("width must be at least 32 px");
  Scene s = make_scene(path, cloud, view);
  Frame f = scene_frame(s, width);
  std::ostringstream o;
  o.precision(6);
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << f.width << "\" height=\"" << f.height
    << "\" viewBox=\"0 0 " << f.width << " " << f.height << "\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  // At most ~5000 cloud dots keep the file small.
  std::size_t stride = std::max<std::size_t>(1, s.cloud_xy.size() / 5000);
  o << "<g stroke=\"none\">\n";
  for (std::size_t i = 0; i < s.cloud_xy.size(); i += stride) {
    Eigen::Vector2d q = f.px(s.cloud_xy[i]);
    o << "<circle cx=\"" << q.x() << "\" cy=\"" << q.y() << "\" r=\"1.5\" fill=\"" << hex(tint(s.cloud_t[i])) << "\"/>\n";
  }
  o << "</g>\n<g fill=\"none\" stroke-width=\"1\">\n";
  for (std::size_t k = 0; k < s.passes.size(); ++k) {
    o << "<polyline stroke=\"" << hex(k % 2 ? kPassB : kPassA) << "\" points=\"";
    for (const auto& p : s.passes[k]) {
      Eigen::Vector2d q = f.px(p);
      o << q.x() << "," << q.y() << " ";
    }
    o << "\"/>\n";
  }
  o << "</g>\n<text x=\"12\" y=\"20\" font-family=\"sans-serif\" font-size=\"14\">" << view << " view, "
    << s.passes.size() << " passes</text>\n</svg>\n";
  return o.str();
}

Picture render_scallop(const Simulation& sim, int width) {
  if (width < kBar + 32) throw std::invalid_argument("width must be at least " + std::to_string(kBar + 32) + " px");
  const double limit = sim.scallop_limit, gouge_tol = sim.gouge_tolerance;
  if (!(limit > 0)) throw std::invalid_argument("scallop limit must be > 0");
  HeatGrid g(sim, limit, gouge_tol, width - kBar);
  const Frame& f = g.frame;
  Canvas c(width, std::max(f.height, 200));
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x) {
      double mx = f.lo.x() + (x + 0.5 - f.pad) / f.scale, my = f.lo.y() + (f.height - f.pad - (y + 0.5)) / f.scale;
      long i = g.at(mx, my);
      if (i >= 0) c.set(x, y, sample_colour(sim.samples[i], limit, gouge_tol));
    }
  // Outline of the patch.
  for (const auto& q : sim.outline) {
    Eigen::Vector2d p = f.px(q);
    c.set(int(p.x()), int(p.y()), kGrey);
  }
  colour_bar(c, f.width + 10, limit, width > 400 ? 2 : 1);
  return c.p;
}

Picture render_part_scallop(const Mesh& mesh, const Simulation& sim, int width) {
  if (width < kBar + 128) throw std::invalid_argument("width must be at least " + std::to_string(kBar + 128) + " px");
  const double limit = sim.scallop_limit, gouge_tol = sim.gouge_tolerance;
  if (!(limit > 0)) throw std::invalid_argument("scallop limit must be > 0");
  if (sim.face.empty() || sim.face.size() != sim.samples.size())
    throw std::invalid_argument("the simulation has no face per sample: give post.simulate_part's");
  std::vector<long> worst(mesh.num_faces(), -1);
  for (std::size_t i = 0; i < sim.samples.size(); ++i) {
    if (sim.face[i] >= mesh.num_faces())
      throw std::invalid_argument("the simulation has a sample on face " + std::to_string(sim.face[i]) + " but the mesh has " +
                                  std::to_string(mesh.num_faces()) + " faces: give the mesh it was simulated on");
    long& w = worst[sim.face[i]];
    const SimSample &s = sim.samples[i];
    if (w >= 0) {
      const SimSample& o = sim.samples[w];
      const int a = severity(s, limit, gouge_tol), b = severity(o, limit, gouge_tol);
      const double sv = std::isnan(s.scallop) ? 0 : s.scallop, ov = std::isnan(o.scallop) ? 0 : o.scallop;
      if (!(a > b || (a == b && (a == 3 ? s.gouge > o.gouge : sv > ov)))) continue;
    }
    w = long(i);
  }
  MeshPictureOptions o;
  o.width = (width - kBar) / 2;
  for (long w : worst) {
    const RGB c = w < 0 ? RGB{200, 200, 200} : sample_colour(sim.samples[w], limit, gouge_tol);
    o.face_colours.push_back({c[0] / 255.0, c[1] / 255.0, c[2] / 255.0});
  }
  o.view = "iso";
  const Picture front = render_mesh(mesh, o);
  o.view = "back";
  const Picture back = render_mesh(mesh, o);
  Canvas c(width, std::max({front.height, back.height, 200}));
  for (const auto& [pic, x0] : {std::pair<const Picture&, int>{front, 0}, {back, front.width}})
    for (int y = 0; y < pic.height; ++y)
      for (int x = 0; x < pic.width; ++x) {
        const std::size_t i = (std::size_t(y) * pic.width + x) * 3;
        c.set(x0 + x, y, RGB{pic.rgb[i], pic.rgb[i + 1], pic.rgb[i + 2]});
      }
  colour_bar(c, front.width + back.width + 10, limit, width > 400 ? 2 : 1);
  return c.p;
}

std::string render_scallop_png(const Simulation& sim, int width) { return encode_png(render_scallop(sim, width)); }

std::string render_scallop_svg(const Simulation& sim, int width) {
  if (width < kBar + 32) throw std::invalid_argument("width must be at least " + std::to_string(kBar + 32) + " px");
  const double limit = sim.scallop_limit, gouge_tol = sim.gouge_tolerance;
  if (!(limit > 0)) throw std::invalid_argument("scallop limit must be > 0");
  // Coarse cells (at most ~200 across) keep the SVG small; each shows its worst sample.
  HeatGrid g(sim, limit, gouge_tol, std::min(width - kBar, 220));
  const Frame& f = g.frame;
  double k = double(width - kBar) / f.width;
  int height = std::max(static_cast<int>(std::ceil(f.height * k)), 200);
  std::ostringstream o;
  o.precision(6);
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height << "\" viewBox=\"0 0 "
    << width << " " << height << "\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<g stroke=\"none\">\n";
  for (int cy = 0; cy < g.ny; ++cy)
    for (int cx = 0; cx < g.nx; ++cx) {
      long i = g.worst[std::size_t(cy) * g.nx + cx];
      if (i < 0) continue;
      Eigen::Vector2d a = f.px(f.lo + Eigen::Vector2d(cx * g.cell, (cy + 1) * g.cell)) * k;
      double s = g.cell * f.scale * k;
      o << "<rect x=\"" << a.x() << "\" y=\"" << a.y() << "\" width=\"" << s << "\" height=\"" << s << "\" fill=\""
        << hex(sample_colour(sim.samples[i], limit, gouge_tol)) << "\"/>\n";
    }
  o << "</g>\n<defs><linearGradient id=\"bar\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">";
  for (int s = 0; s <= 4; ++s) o << "<stop offset=\"" << s / 4.0 << "\" stop-color=\"" << hex(ramp(s / 4.0)) << "\"/>";
  int bx = width - kBar + 10, top = 20, bottom = height - 20;
  o << "</linearGradient></defs>\n<rect x=\"" << bx << "\" y=\"" << top << "\" width=\"20\" height=\"" << bottom - top
    << "\" fill=\"url(#bar)\"/>\n<rect x=\"" << bx << "\" y=\"" << top - 12 << "\" width=\"20\" height=\"10\" fill=\""
    << hex(kRed) << "\"/>\n";
  for (int s = 0; s < 3; ++s) {
    double y = bottom - s * 0.5 * (bottom - top);
    o << "<text x=\"" << bx + 26 << "\" y=\"" << y + 4 << "\" font-family=\"sans-serif\" font-size=\"11\">"
      << label(s * 0.5 * 1.01 * limit) << " mm</text>\n";
  }
  o << "<text x=\"12\" y=\"16\" font-family=\"sans-serif\" font-size=\"13\">scallop (red &gt; 1.01 h, magenta uncut, "
       "black gouge)</text>\n</svg>\n";
  return o.str();
}

}  // namespace scallop
