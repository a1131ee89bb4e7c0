#include "nodes/post/gcode.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace scallop {
namespace {

constexpr double kPi = 3.14159265358979323846;

LinkedPath small_path() {
  LinkedPath p;
  p.tool_radius = 3;
  p.scallop_height = 0.01;
  p.chord_error = 0.005;
  p.clearance_z = 20;
  p.moves = {{MoveKind::Rapid, {0, 0, 20}},   {MoveKind::Rapid, {0, 0, 6}},
             {MoveKind::Plunge, {0, 0, 5}},   {MoveKind::Feed, {10, 0, 5}},
             {MoveKind::Feed, {10, 1.5, 5.25}}, {MoveKind::Rapid, {10, 1.5, 20}}};
  return p;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool have_rs274() { return std::system("command -v rs274 > /dev/null 2>&1") == 0; }

// Runs LinuxCNC's interpreter; returns the canonical calls, and the error lines (stderr other
// than its "executing" banner, or a non-zero exit) in `errors`.
std::string run_rs274(const std::string& program, std::string& errors) {
  auto dir = std::filesystem::temp_directory_path() /
             ("scallop_gcode_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::string ngc = (dir / "p.ngc").string(), out = (dir / "out").string(),
              err = (dir / "err").string();
  std::ofstream(ngc) << program;
  // One rs274 at a time: two interpreters running at once (ctest -j) crash with a bus error
  // (measured: 8 of 15 concurrent pairs), so they take turns on a lock file (flock, util-linux).
  const std::string lock = (std::filesystem::temp_directory_path() / "scallop-rs274.lock").string();
  std::string cmd = "cd '" + dir.string() + "' && flock '" + lock + "' rs274 -g '" + ngc + "' > '" +
                    out + "' 2> '" + err + "' < /dev/null";
  int rc = std::system(cmd.c_str());
  std::string canon = slurp(out);
  errors.clear();
  std::istringstream e(slurp(err));
  for (std::string line; std::getline(e, line);)
    if (!line.empty() && line != "executing") errors += line + "\n";
  if (rc != 0) errors += "exit status " + std::to_string(rc) + "\n";
  std::filesystem::remove_all(dir);
  return canon;
}

// Feed polyline (tips) from the canonical calls, arcs cut into chords of sagitta <= 1e-5 mm.
std::vector<Eigen::Vector3d> canon_feed_points(const std::string& canon) {
  std::vector<Eigen::Vector3d> pts;
  Eigen::Vector3d pos(0, 0, 0);
  int a = 0, b = 1, n = 2;
  std::istringstream in(canon);
  for (std::string line; std::getline(in, line);) {
    auto open = line.find('('), close = line.rfind(')');
    if (open == std::string::npos) continue;
    std::string name = line.substr(0, open);
    name = name.substr(name.find_last_of(' ') + 1);
    std::string args = line.substr(open + 1, close - open - 1);
    std::vector<double> v;
    std::istringstream as(args);
    for (std::string tok; std::getline(as, tok, ',');) {
      try {
        v.push_back(std::stod(tok));
      } catch (...) {
        v.push_back(0);
      }
    }
    if (name == "SELECT_PLANE") {
      if (args.find("XY") != std::string::npos) a = 0, b = 1, n = 2;
      if (args.find("XZ") != std::string::npos) a = 2, b = 0, n = 1;
      if (args.find("YZ") != std::string::npos) a = 1, b = 2, n = 0;
    } else if (name == "STRAIGHT_TRAVERSE") {
      pos = {v[0], v[1], v[2]};
    } else if (name == "STRAIGHT_FEED") {
      pos = {v[0], v[1], v[2]};
      pts.push_back(pos);
    } else if (name == "ARC_FEED") {
      ArcPiece pc;
      pc.arc = true;
      pc.axis = n;
      pc.ccw = v[4] > 0;
      pc.end = pos;
      pc.end[a] = v[0];
      pc.end[b] = v[1];
      pc.end[n] = v[5];
      pc.centre = pos;
      pc.centre[a] = v[2];
      pc.centre[b] = v[3];
      for (const auto& p : arc_points(pos, pc, 1e-5)) pts.push_back(p);
      pos = pc.end;
    }
  }
  return pts;
}

double dist_to_polyline(const Eigen::Vector3d& q, const std::vector<Eigen::Vector3d>& P) {
  double best = INFINITY;
  for (std::size_t i = 0; i + 1 < P.size(); ++i) {
    Eigen::Vector3d e = P[i + 1] - P[i];
    double t = e.squaredNorm() > 0 ? std::clamp((q - P[i]).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0;
    best = std::min(best, (P[i] + t * e - q).norm());
  }
  return best;
}

// A cutting path with arcs in all three planes: a circle in XY, a dome meridian in XZ, a bowl
// meridian in YZ, with a little radial noise.
LinkedPath arc_path(double noise) {
  LinkedPath p;
  p.tool_radius = 3;
  p.scallop_height = 0.01;
  p.chord_error = 0.004;
  p.clearance_z = 30;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-noise, noise);
  p.moves.push_back({MoveKind::Rapid, {20, 0, 30}});
  p.moves.push_back({MoveKind::Plunge, {20, 0, 5}});
  for (int i = 1; i <= 300; ++i) {  // three quarters of a circle of radius 20 in z = 5, ccw
    double t = 1.5 * kPi * i / 300, r = 20 + u(rng);
    p.moves.push_back({MoveKind::Feed, {r * std::cos(t), r * std::sin(t), 5}});
  }
  Eigen::Vector3d s = p.moves.back().tip;  // (0, -20, 5): meridian in x = 0 (YZ plane)
  for (int i = 1; i <= 100; ++i) {
    double t = 0.5 * kPi * i / 100, r = 20 + u(rng);
    p.moves.push_back({MoveKind::Feed, {0, -r * std::cos(t), s.z() + r * std::sin(t)}});
  }
  s = p.moves.back().tip;  // (0, 0, 25): meridian in y = 0 (XZ plane), going down
  for (int i = 1; i <= 100; ++i) {
    double t = 0.5 * kPi * i / 100, r = 20 + u(rng);
    p.moves.push_back({MoveKind::Feed, {r * std::sin(t), 0, 5 + r * std::cos(t)}});
  }
  p.moves.push_back({MoveKind::Feed, {25, 0, 5}});
  p.moves.push_back({MoveKind::Rapid, {25, 0, 30}});
  return p;
}

TEST(GCode, GrblHeaderAndFooter) {
  GCodeOptions o;
  o.dialect = "grbl";
  o.graph_name = "finish";
  o.input_hash = "abc123";
  std::string text = write_gcode(small_path(), o);
  const std::string golden =
      "(scallop finishing program)\n"
      "(tool: ball end radius 3.0000 mm)\n"
      "(scallop 0.0100 chord 0.0050 mm)\n"
      "(xyz = tool tip, clearance z 20.0000)\n"
      "(graph: finish)\n"
      "(input: abc123)\n"
      "G17 G21 G90 G94\n"
      "M3 S10000\n"
      "G0 Z20.0000\n"
      "G0 X0.0000 Y0.0000\n"
      "G0 Z6.0000\n"
      "G1 Z5.0000 F300.0\n"
      "G1 X10.0000 F1000.0\n"
      "G1 Y1.5000 Z5.2500\n"
      "G0 Z20.0000\n"
      "M5\n"
      "M2\n";
  EXPECT_EQ(text, golden);
}

TEST(GCode, FanucHeaderAndFooter) {
  GCodeOptions o;
  o.dialect = "fanuc";
  o.program_number = 42;
  o.spindle_rpm = 0;
  std::string text = write_gcode(small_path(), o);
  const std::string head =
      "%\n"
      "O0042 (SCALLOP FINISHING)\n"
      "(TOOL: BALL END RADIUS 3.0000 MM)\n"
      "(SCALLOP 0.0100 CHORD 0.0050 MM)\n"
      "(XYZ = TOOL TIP, CLEARANCE Z 20.0000)\n"
      "G17 G21 G40 G49 G80 G90\n"
      "G0 Z20.0000\n";
  const std::string tail = "G0 Z20.0000\nM30\n%\n";
  EXPECT_EQ(text.substr(0, head.size()), head);
  ASSERT_GE(text.size(), tail.size());
  EXPECT_EQ(text.substr(text.size() - tail.size()), tail);
  EXPECT_EQ(text.find("M3 S"), std::string::npos);
}

TEST(GCode, UnknownDialectAndBadFeedAreRefused) {
  GCodeOptions o;
  o.dialect = "heidenhain";
  try {
    write_gcode(small_path(), o);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "unknown G-code dialect 'heidenhain' (linuxcnc, grbl or fanuc)");
  }
  o.dialect = "linuxcnc";
  o.feed = 0;
  EXPECT_THROW(write_gcode(small_path(), o), std::invalid_argument);
}

TEST(GCode, FitArcsStaysWithinTolerance) {
  // A noisy arc and a straight tail: arcs found, every arc within tolerance of the polyline.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.0005, 0.0005);  // sagitta of the chords 0.0019
  std::vector<Eigen::Vector3d> P;
  for (int i = 0; i <= 100; ++i) {
    double t = kPi * i / 100, r = 15 + u(rng);
    P.push_back({r * std::cos(t), 2 + r * std::sin(t), 1});
  }
  for (int i = 1; i <= 10; ++i) P.push_back({-15.0 - i, 2, 1});
  const double tol = 0.005;
  auto pieces = fit_arcs(P, tol);
  int arcs = 0;
  Eigen::Vector3d pos = P[0];
  for (const auto& pc : pieces) {
    std::vector<Eigen::Vector3d> sub(P.begin() + pc.first, P.begin() + pc.last + 1);
    auto pts = arc_points(pos, pc, 1e-6);
    for (const auto& q : pts) EXPECT_LE(dist_to_polyline(q, sub), tol);
    if (pc.arc) {
      ++arcs;
      std::vector<Eigen::Vector3d> dense = {pos};
      dense.insert(dense.end(), pts.begin(), pts.end());
      for (const auto& q : sub) EXPECT_LE(dist_to_polyline(q, dense), tol);
    }
    pos = pc.end;
  }
  EXPECT_GE(arcs, 1);
  EXPECT_LE(arcs, 3);
  EXPECT_EQ(pieces.back().last, static_cast<int>(P.size()) - 1);
}

TEST(GCode, LinuxcncProgramPassesRs274) {
  if (!have_rs274()) GTEST_SKIP() << "rs274 (LinuxCNC interpreter, package linuxcnc-uspace) not installed";
  GCodeOptions o;
  o.graph_name = "finish (test)";
  o.input_hash = "0123456789abcdef";
  for (bool arcs : {false, true}) {
    o.arcs = arcs;
    for (const LinkedPath& p : {small_path(), arc_path(0.0)}) {
      std::string errors;
      std::string canon = run_rs274(write_gcode(p, o), errors);
      EXPECT_EQ(errors, "") << "arcs " << arcs;
      EXPECT_NE(canon.find("PROGRAM_END"), std::string::npos);
    }
  }
}

TEST(GCode, ArcsReadByRs274StayWithinTolerance) {
  if (!have_rs274()) GTEST_SKIP() << "rs274 (LinuxCNC interpreter, package linuxcnc-uspace) not installed";
  LinkedPath p = arc_path(0.0003);
  GCodeOptions o;
  o.arcs = true;
  o.arc_tolerance = 0.002;
  std::string text = write_gcode(p, o);
  EXPECT_NE(text.find("G18"), std::string::npos);
  EXPECT_NE(text.find("G19"), std::string::npos);
  EXPECT_NE(text.find("G3"), std::string::npos);
  EXPECT_NE(text.find("G2"), std::string::npos);
  std::string errors;
  auto pts = canon_feed_points(run_rs274(text, errors));
  ASSERT_EQ(errors, "");
  std::vector<Eigen::Vector3d> poly;
  for (std::size_t i = 1; i < p.moves.size() - 1; ++i) poly.push_back(p.moves[i].tip);
  double worst = 0;
  for (const auto& q : pts) worst = std::max(worst, dist_to_polyline(q, poly));
  // Tolerance plus the 4-decimal rounding of ends and centre offsets.
  EXPECT_LE(worst, o.arc_tolerance + 2e-4);
  // The arcs shorten the program a lot.
  o.arcs = false;
  EXPECT_LT(text.size() * 4, write_gcode(p, o).size());
}

}  // namespace
}  // namespace scallop
