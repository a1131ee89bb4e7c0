#include "nodes/post/gcode.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace scallop {
namespace {

constexpr double kPi = 3.14159265358979323846;

// In-plane axes (first, second) for the plane normal to `axis`, ordered so that (first, second,
// axis) is right-handed: XY for Z (G17), ZX for Y (G18), YZ for X (G19). G3 is counter-clockwise
// in (first, second), as LinuxCNC and ISO 6983 define it.
void plane_axes(int axis, int& a, int& b) {
  a = (axis + 1) % 3;
  b = (axis + 2) % 3;
}

struct Circle {
  double cu = 0, cv = 0, R = 0;
  bool ok = false;
};

Circle circle_through(double u0, double v0, double u1, double v1, double u2, double v2) {
  Circle c;
  double ax = u1 - u0, ay = v1 - v0, bx = u2 - u0, by = v2 - v0;
  double d = 2 * (ax * by - ay * bx);
  double a2 = ax * ax + ay * ay, b2 = bx * bx + by * by;
  if (std::abs(d) < 1e-12 * std::max(a2, b2)) return c;  // collinear
  double x = (by * a2 - ay * b2) / d, y = (ax * b2 - bx * a2) / d;
  c.cu = u0 + x;
  c.cv = v0 + y;
  c.R = std::hypot(x, y);
  c.ok = true;
  return c;
}

// Worst distance between the arc through P[s..j] (centre, radius R, in plane (a, b)) and the
// polyline, bounded by sagitta + radial deviation per chord; sets ccw. Returns +inf when the
// points do not advance monotonically around the centre or sweep more than 180 degrees.
double arc_deviation(const std::vector<Eigen::Vector3d>& P, int s, int j, int a, int b,
                     const Circle& c, bool& ccw) {
  double prev = std::atan2(P[s][b] - c.cv, P[s][a] - c.cu);
  double rad_prev = std::abs(std::hypot(P[s][a] - c.cu, P[s][b] - c.cv) - c.R);
  double sweep = 0, worst = 0;
  int sign = 0;
  for (int k = s + 1; k <= j; ++k) {
    double th = std::atan2(P[k][b] - c.cv, P[k][a] - c.cu);
    double dth = std::remainder(th - prev, 2 * kPi);
    int sg = dth > 0 ? 1 : (dth < 0 ? -1 : 0);
    if (sg == 0 || (sign != 0 && sg != sign) || std::abs(dth) > kPi / 2) return INFINITY;
    sign = sg;
    sweep += std::abs(dth);
    double rad = std::abs(std::hypot(P[k][a] - c.cu, P[k][b] - c.cv) - c.R);
    double sag = c.R * (1 - std::cos(0.5 * dth));
    worst = std::max(worst, sag + std::max(rad, rad_prev));
    rad_prev = rad;
    prev = th;
  }
  if (sweep > kPi) return INFINITY;
  ccw = sign > 0;
  return worst;
}

// Tries to make an arc of P[s..j] in the plane normal to `axis`.
bool try_arc(const std::vector<Eigen::Vector3d>& P, int s, int j, int axis, double tol,
             double max_radius, ArcPiece& out) {
  int a, b;
  plane_axes(axis, a, b);
  int m = (s + j) / 2;
  Circle c = circle_through(P[s][a], P[s][b], P[m][a], P[m][b], P[j][a], P[j][b]);
  if (!c.ok || c.R > max_radius || c.R < 1e-3) return false;
  bool ccw = true;
  if (!(arc_deviation(P, s, j, a, b, c, ccw) <= tol)) return false;
  out.arc = true;
  out.axis = axis;
  out.ccw = ccw;
  out.end = P[j];
  out.centre = P[s];
  out.centre[a] = c.cu;
  out.centre[b] = c.cv;
  out.first = s;
  out.last = j;
  return true;
}

std::string fmt4(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  std::string s = buf;
  if (s == "-0.0000") s = "0.0000";
  return s;
}

// Parentheses end a comment early; keep comment text plain and short (grbl's line buffer is 80).
std::string comment_text(std::string s, bool upper) {
  std::string out;
  for (char ch : s) {
    if (ch == '(' || ch == ')' || ch == ';' || ch == '\n' || ch == '\r') ch = ' ';
    if (upper) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    out += ch;
  }
  if (out.size() > 70) out = out.substr(0, 70);
  return out;
}

}  // namespace

std::vector<ArcPiece> fit_arcs(const std::vector<Eigen::Vector3d>& P, double tolerance,
                               double max_radius) {
  std::vector<ArcPiece> out;
  const int n = static_cast<int>(P.size());
  const double same = 1e-6;  // mm: the plane coordinate of an arc's points
  int s = 0;
  while (s + 1 < n) {
    ArcPiece best;
    bool found = false;
    for (int axis : {2, 1, 0}) {
      // The run of points sharing this coordinate.
      int end = s;
      while (end + 1 < n && std::abs(P[end + 1][axis] - P[s][axis]) <= same) ++end;
      if (end - s < 3) continue;
      ArcPiece piece;
      if (!try_arc(P, s, s + 3, axis, tolerance, max_radius, piece)) continue;
      // Grow while the arc still fits (bounded, so the cost stays linear-ish).
      for (int j = s + 4; j <= end && j - s <= 400; ++j) {
        ArcPiece longer;
        if (!try_arc(P, s, j, axis, tolerance, max_radius, longer)) break;
        piece = longer;
      }
      if (!found || piece.last > best.last) {
        best = piece;
        found = true;
      }
    }
    if (found) {
      out.push_back(best);
      s = best.last;
    } else {
      ArcPiece line;
      line.end = P[s + 1];
      line.first = s;
      line.last = s + 1;
      out.push_back(line);
      ++s;
    }
  }
  return out;
}

std::vector<Eigen::Vector3d> arc_points(const Eigen::Vector3d& start, const ArcPiece& piece,
                                        double sagitta) {
  if (!piece.arc) return {piece.end};
  int a, b;
  plane_axes(piece.axis, a, b);
  double R = std::hypot(start[a] - piece.centre[a], start[b] - piece.centre[b]);
  double t0 = std::atan2(start[b] - piece.centre[b], start[a] - piece.centre[a]);
  double t1 = std::atan2(piece.end[b] - piece.centre[b], piece.end[a] - piece.centre[a]);
  double sweep = piece.ccw ? std::fmod(t1 - t0 + 4 * kPi, 2 * kPi) : -std::fmod(t0 - t1 + 4 * kPi, 2 * kPi);
  double step = R > sagitta ? 2 * std::acos(1 - sagitta / R) : kPi / 2;
  int k = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / step)));
  std::vector<Eigen::Vector3d> pts;
  for (int i = 1; i <= k; ++i) {
    double th = t0 + sweep * i / k;
    Eigen::Vector3d p = start;
    p[a] = piece.centre[a] + R * std::cos(th);
    p[b] = piece.centre[b] + R * std::sin(th);
    pts.push_back(p);
  }
  pts.back() = piece.end;
  return pts;
}

Eigen::Vector3d as_written(const Eigen::Vector3d& tip) {
  return {std::strtod(fmt4(tip.x()).c_str(), nullptr), std::strtod(fmt4(tip.y()).c_str(), nullptr),
          std::strtod(fmt4(tip.z()).c_str(), nullptr)};
}

std::string write_gcode(const LinkedPath& path, const GCodeOptions& o) {
  const std::string& d = o.dialect;
  if (d != "linuxcnc" && d != "grbl" && d != "fanuc")
    throw std::invalid_argument("unknown G-code dialect '" + d + "' (linuxcnc, grbl or fanuc)");
  if (!(o.feed > 0) || !(o.plunge_feed > 0))
    throw std::invalid_argument("feed and plunge_feed must be > 0 mm/min");
  for (const auto& m : path.moves)
    if (!m.tip.allFinite()) throw std::invalid_argument("the linked path has a non-finite coordinate");
  const bool fanuc = d == "fanuc", grbl = d == "grbl";
  // The polyline is itself within the chord error of the true curve and an arc through its points
  // is usually closer still, so the chord error is the natural default.
  double arc_tol = o.arc_tolerance > 0 ? o.arc_tolerance : std::max(1e-3, path.chord_error);

  std::ostringstream g;
  auto comment = [&](const std::string& s) { g << "(" << comment_text(s, fanuc) << ")\n"; };
  if (fanuc) {
    g << "%\n";
    char buf[32];
    std::snprintf(buf, sizeof buf, "O%04d", o.program_number);
    g << buf << " (SCALLOP FINISHING)\n";
  } else {
    comment("scallop finishing program");
  }
  comment("tool: ball end radius " + fmt4(path.tool_radius) + " mm");
  comment("scallop " + fmt4(path.scallop_height) + " chord " + fmt4(path.chord_error) + " mm");
  comment("xyz = tool tip, clearance z " + fmt4(path.clearance_z));
  if (!o.graph_name.empty()) comment("graph: " + o.graph_name);
  if (!o.input_hash.empty()) comment("input: " + o.input_hash);
  if (fanuc)
    g << "G17 G21 G40 G49 G80 G90\n";
  else if (grbl)
    g << "G17 G21 G90 G94\n";
  else
    g << "G17 G21 G40 G49 G80 G90 G94\n";
  if (o.spindle_rpm > 0) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "M3 S%.0f\n", o.spindle_rpm);
    g << buf;
  }

  // Current position as written (rounded text), so only changed axes are repeated.
  std::string cur[3] = {"", "", ""};
  Eigen::Vector3d cur_pos(NAN, NAN, NAN);
  double cur_feed = -1;
  int cur_plane = 2;
  static const char* kAxis = "XYZ";
  auto rounded = [](const Eigen::Vector3d& p) {
    Eigen::Vector3d q;
    for (int i = 0; i < 3; ++i) q[i] = std::stod(fmt4(p[i]));
    return q;
  };
  auto axes_words = [&](const Eigen::Vector3d& p, bool all) {
    std::string w;
    for (int i = 0; i < 3; ++i) {
      std::string t = fmt4(p[i]);
      if (all || t != cur[i]) w += std::string(" ") + kAxis[i] + t;
    }
    return w;
  };
  auto commit = [&](const Eigen::Vector3d& p) {
    for (int i = 0; i < 3; ++i) cur[i] = fmt4(p[i]);
    cur_pos = rounded(p);
  };
  auto feed_word = [&](double f) {
    if (f == cur_feed) return std::string();
    cur_feed = f;
    char buf[32];
    std::snprintf(buf, sizeof buf, " F%.1f", f);
    return std::string(buf);
  };
  auto straight = [&](const char* gw, const Eigen::Vector3d& p, double f) {
    std::string w = axes_words(p, false);
    if (w.empty()) return;
    g << gw << w << (f > 0 ? feed_word(f) : "") << "\n";
    commit(p);
  };

  const auto& mv = path.moves;
  std::size_t i = 0;
  bool first = true;
  while (i < mv.size()) {
    const Move& m = mv[i];
    if (first) {
      // The position before the program is unknown: rise to the move's height first when it is
      // a rapid, then travel across.
      if (m.kind == MoveKind::Rapid) {
        g << "G0 Z" << fmt4(m.tip.z()) << "\n";
        cur[2] = fmt4(m.tip.z());
        g << "G0 X" << fmt4(m.tip.x()) << " Y" << fmt4(m.tip.y()) << "\n";
        commit(m.tip);
      } else {
        g << "G1" << axes_words(m.tip, true) << feed_word(m.kind == MoveKind::Plunge ? o.plunge_feed : o.feed) << "\n";
        commit(m.tip);
      }
      first = false;
      ++i;
      continue;
    }
    if (m.kind == MoveKind::Rapid) {
      straight("G0", m.tip, 0);
      ++i;
    } else if (m.kind == MoveKind::Plunge) {
      straight("G1", m.tip, o.plunge_feed);
      ++i;
    } else {
      // A run of feed moves, starting at the current position.
      std::size_t j = i;
      while (j < mv.size() && mv[j].kind == MoveKind::Feed) ++j;
      if (!o.arcs || j - i < 3) {
        for (; i < j; ++i) straight("G1", mv[i].tip, o.feed);
        continue;
      }
      std::vector<Eigen::Vector3d> P;
      P.push_back(mv[i - 1].tip);
      for (std::size_t k = i; k < j; ++k) P.push_back(mv[k].tip);
      for (const ArcPiece& pc : fit_arcs(P, arc_tol)) {
        if (!pc.arc) {
          straight("G1", pc.end, o.feed);
          continue;
        }
        int a, b;
        plane_axes(pc.axis, a, b);
        Eigen::Vector3d s = cur_pos, e = rounded(pc.end);
        e[pc.axis] = s[pc.axis];  // the plane coordinate stays exactly as written
        double du = e[a] - s[a], dv = e[b] - s[b];
        double L2 = du * du + dv * dv;
        if (L2 < 1e-8) {  // start == end would be read as a full circle
          straight("G1", pc.end, o.feed);
          continue;
        }
        // Centre moved onto the bisector of the rounded ends so both radii agree.
        double mu = 0.5 * (s[a] + e[a]), mvv = 0.5 * (s[b] + e[b]);
        double nu = -dv / std::sqrt(L2), nv = du / std::sqrt(L2);
        double t = (pc.centre[a] - mu) * nu + (pc.centre[b] - mvv) * nv;
        double cu = mu + t * nu, cv = mvv + t * nv;
        if (pc.axis != cur_plane) {
          g << (pc.axis == 2 ? "G17" : pc.axis == 1 ? "G18" : "G19") << "\n";
          cur_plane = pc.axis;
        }
        static const char* kOffset = "IJK";
        std::string w = pc.ccw ? "G3" : "G2";
        for (int ax = 0; ax < 3; ++ax)
          if (ax != pc.axis) w += std::string(" ") + kAxis[ax] + fmt4(e[ax]);
        w += std::string(" ") + kOffset[a] + fmt4(cu - s[a]);
        w += std::string(" ") + kOffset[b] + fmt4(cv - s[b]);
        g << w << feed_word(o.feed) << "\n";
        commit(e);
      }
      i = j;
    }
  }
  if (cur_plane != 2) g << "G17\n";
  if (o.spindle_rpm > 0) g << "M5\n";
  if (fanuc) {
    g << "M30\n%\n";
  } else {
    g << "M2\n";
  }
  return g.str();
}

}  // namespace scallop
