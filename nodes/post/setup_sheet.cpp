#include "nodes/post/setup_sheet.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "nodes/post/render.h"
#include "nodes/post/render_mesh.h"

namespace scallop {
namespace {

std::string fixed(double v, int decimals) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

// "+x" for a coordinate axis (within 0.5 degrees), else "(0.707, 0.000, 0.707)".
std::string direction(const Eigen::Vector3d& a) {
  static const char* names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k)
    if (std::abs(a[k]) > std::cos(0.5 * 3.14159265358979 / 180)) return std::string(a[k] > 0 ? "+" : "-") + names[k];
  return "(" + fixed(a.x(), 3) + ", " + fixed(a.y(), 3) + ", " + fixed(a.z(), 3) + ")";
}

}  // namespace

SetupSheet setup_sheet(const SetupPaths& programs, const std::vector<Setup>& setups, const Mesh& surfaces,
                       const nlohmann::json* certificate, int picture_width) {
  SetupSheet sheet;
  std::string& md = sheet.markdown;
  md = "# Setup sheet\n\n";
  if (!programs.setups.empty()) {
    const LinkedPath& p = programs.setups.front().path;
    md += "Tool: ball-end mill, radius " + fixed(p.tool_radius, 3) + " mm (diameter " + fixed(2 * p.tool_radius, 3) +
          " mm), the same in every setup. Scallop limit " + fixed(p.scallop_height, 4) + " mm, chord error " +
          fixed(p.chord_error, 4) + " mm. Programs: G21 (mm), G90, XYZ = the ball's tip.\n\n";
  }
  if (certificate) {
    if (certificate->value("pass", false)) {
      md += "**Certificate: PASS.** ";
    } else {
      md += "**Certificate: FAIL — do not cut.** ";
      for (const auto& r : certificate->value("fail_reasons", nlohmann::json::array())) md += r.get<std::string>() + ". ";
    }
    md += "Interior scallop max " + fixed(certificate->value("scallop_max_interior", 0.0), 4) + " mm, gouge max " +
          fixed(certificate->value("gouge_max", 0.0), 4) + " mm, on the table " +
          fixed(100 * certificate->value("base_fraction", 0.0), 1) + " % of the surface, out of the ball's reach " +
          fixed(100 * certificate->value("unreachable_fraction", 0.0), 2) + " % (report.json lists where).\n\n";
  }
  md += "Work zero (G54) in every setup: X0 Y0 at the centre of the part's bounding box as it stands in that "
        "clamping, Z0 on the table under the part (its lowest point). Cut the setups in this order:\n\n";
  md += "| # | program | turn the part so that this direction points up | patches | moves | cut length (mm) | "
        "clearance Z (mm) |\n|---|---|---|---|---|---|---|\n";
  // A clamping post.setup_programs added for its rest passes is not in the report: it cuts no
  // patch of its own, its axis is its part_to_machine's.
  std::vector<Setup> added(programs.setups.size());
  std::vector<const Setup*> of(programs.setups.size(), nullptr);
  for (std::size_t k = 0; k < programs.setups.size(); ++k) {
    for (const Setup& s : setups)
      if (s.name == programs.setups[k].name) of[k] = &s;
    if (!of[k] && programs.setups[k].name.find(": rest ") != std::string::npos) {
      added[k].name = programs.setups[k].name;
      added[k].rotation = programs.setups[k].rotation;
      added[k].translation = programs.setups[k].translation;
      added[k].axis = added[k].rotation.row(2).transpose();
      of[k] = &added[k];
    }
    if (!of[k]) throw std::invalid_argument("program '" + programs.setups[k].file + "' is for setup '" +
                                            programs.setups[k].name + "', which the setups report does not have");
  }
  auto cut_length = [](const LinkedPath& p) {
    double L = 0;
    for (std::size_t i = 1; i < p.moves.size(); ++i)
      if (p.moves[i].kind != MoveKind::Rapid) L += (p.moves[i].tip - p.moves[i - 1].tip).norm();
    return L;
  };
  for (std::size_t k = 0; k < programs.setups.size(); ++k) {
    const SetupPath& p = programs.setups[k];
    md += "| " + std::to_string(k + 1) + " | `" + p.file + "` | " + direction(of[k]->axis) + " | " +
          std::to_string(of[k]->patches.size()) + " | " + std::to_string(p.path.moves.size()) + " | " +
          fixed(cut_length(p.path), 0) + " | " + fixed(p.path.clearance_z, 2) + " |\n";
  }
  md += "\n";
  // How near above a pass start the rapids come down (a rapid, then the plunge; post.link keeps
  // them that far off the part): the roughing's stock must stand lower, or a rapid runs into it.
  auto rapid_down_to = [](const LinkedPath& p) {
    double lead = INFINITY;
    for (std::size_t i = 1; i < p.moves.size(); ++i)
      if (p.moves[i].kind == MoveKind::Plunge && p.moves[i - 1].kind == MoveKind::Rapid)
        lead = std::min(lead, p.moves[i - 1].tip.z() - p.moves[i].tip.z());
    return lead;
  };
  auto rapids = [&](const LinkedPath& p) {
    const double lead = rapid_down_to(p);
    return "rapids at Z " + fixed(p.clearance_z, 2) +
           (std::isfinite(lead) ? ", stopping at least " + fixed(lead, 2) +
                                      " mm above each pass start (leave less stock than that)"
                                : "");
  };
  for (std::size_t k = 0; k < programs.setups.size(); ++k) {
    const SetupPath& p = programs.setups[k];
    const Setup& s = *of[k];
    md += "## Setup " + std::to_string(k + 1) + ": `" + p.file + "`\n\n";
    md += "- **Clamp**: turn the part so that its direction " + direction(s.axis) +
          " points up at the spindle; the side facing " + direction(-s.axis) + " rests on the table or fixture" +
          (s.axis.z() > 0.9999 ? " (the part as it stands)" : "") + ".\n";
    md += "- **part_to_machine** (a part point p is at R p + t):";
    for (int r = 0; r < 3; ++r)
      md += std::string(r ? "," : "") + " [" + fixed(s.rotation(r, 0), 4) + ", " + fixed(s.rotation(r, 1), 4) + ", " +
            fixed(s.rotation(r, 2), 4) + " | " + fixed(s.translation[r], 3) + "]";
    if (s.patches.empty()) {
      md += ".\n- **Cuts** only what the other setups leave (rest passes, no patch of its own); " +
            fixed(cut_length(p.path), 0) + " mm of cut; " + rapids(p.path) + ".\n";
    } else {
      md += ".\n- **Cuts** " + std::to_string(s.patches.size()) + " patch" + (s.patches.size() == 1 ? "" : "es") + " (";
      for (std::size_t i = 0; i < s.patches.size(); ++i) md += (i ? ", " : "") + std::to_string(s.patches[i]);
      md += "), steepest surface at " +
            fixed(std::acos(std::clamp(s.min_normal_dot, -1.0, 1.0)) * 180 / 3.14159265358979, 0) +
            "° from the tool axis; " + fixed(cut_length(p.path), 0) + " mm of cut; " + rapids(p.path) + ".\n";
    }
    if (certificate && certificate->contains("setups"))
      for (const auto& c : (*certificate)["setups"])
        if (c.value("name", "") == p.name)
          md += "- **Certificate**: this setup leaves the finished surface on " +
                fixed(100 * c.value("finished_fraction", 0.0), 1) + " % of the measured area; its gouge max " +
                fixed(c.value("gouge_max", 0.0), 4) + " mm.\n";
    if (surfaces.num_faces() > 0) {
      Mesh placed = surfaces;
      for (auto& v : placed.vertices) v = s.rotation * v + s.translation;
      MeshPictureOptions o;
      o.view = "iso", o.width = picture_width;
      for (std::size_t f = 0; f < placed.num_faces(); ++f) {
        const int label = placed.has_labels() ? placed.face_label[f] : -1;
        const bool cut = label >= 0 && std::find(s.patches.begin(), s.patches.end(), std::uint32_t(label)) != s.patches.end();
        o.face_colours.push_back(cut ? std::array<double, 3>{1.0, 0.55, 0.1} : std::array<double, 3>{0.72, 0.74, 0.78});
      }
      // The spindle's axis: a line straight up from the top of the part.
      double top = -INFINITY;
      for (const auto& v : placed.vertices) top = std::max(top, v.z());
      MeshOverlay spindle;
      spindle.points = {{0, 0, top}, {0, 0, top + 0.3 * (top + 1)}};
      spindle.thick = 3;
      spindle.whole_if_start_seen = true;
      o.overlays.push_back(spindle);
      const std::string name = "setup_" + std::to_string(k + 1) + ".png";
      sheet.pictures.emplace_back(name, encode_png(render_mesh(placed, o)));
      md += "\n![setup " + std::to_string(k + 1) + ": the part as clamped, the faces it cuts in orange, the "
            "spindle's axis in black](" + name + ")\n";
    }
    md += "\n";
  }
  return sheet;
}

}  // namespace scallop
