#include "nodes/post/setup_programs.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "nodes/mesh/mesh_distance.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/post/keep_off_part.h"
#include "nodes/post/rest_passes.h"
#include "nodes/path/step_size.h"

namespace scallop {

namespace {

// The points a closed mesh's faces do not already hold: a point inside it, or on it to 1e-7 mm,
// is never nearer than the faces to a ball centre outside (the segment between them crosses a
// face), and a centre inside is a gouge by the faces alone. Asking a 200 000-point cloud at
// every distance was a fifth of the block's programs node, and mesh.cloud_envelope's outer mesh
// leaves few of its points out (points_beyond: 1 of the fandisk's). An open mesh has no inside:
// all of them.
std::vector<Eigen::Vector3d> points_outside(const Mesh& mesh, const MeshDistance& faces,
                                            const std::vector<Eigen::Vector3d>& points) {
  if (points.empty()) return {};
  const MeshEdges edges = mesh_edges(mesh);
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges.faces_on(e) != 2) return points;
  std::vector<char> outside(points.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const tbb::blocked_range<std::size_t>& b) {
    for (std::size_t i = b.begin(); i < b.end(); ++i) outside[i] = faces.signed_distance(points[i]) > 1e-7;
  });
  std::vector<Eigen::Vector3d> kept;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (outside[i]) kept.push_back(points[i]);
  return kept;
}

}  // namespace

std::vector<SetupProgram> setup_programs(const Toolpath& path, const std::vector<std::size_t>& passes_per_patch,
                                         const std::vector<Setup>& setups, const Mesh& part,
                                         const LinkOptions& link, const GCodeOptions& gcode,
                                         const std::vector<double>& patch_off_part, const RestOptions* rest,
                                         RestResult* rest_result, const std::vector<Eigen::Vector3d>& held_points,
                                         const std::function<void(double, const std::string&)>& progress,
                                         const TangleKeepOut& keep_out) {
  const auto report = [&](double f, const std::string& what) {
    if (progress) progress(f, what);
  };
  if (std::accumulate(passes_per_patch.begin(), passes_per_patch.end(), std::size_t(0)) != path.passes.size())
    throw std::invalid_argument("the patches' pass counts do not add up to the toolpath's " +
                                std::to_string(path.passes.size()) + " passes");
  std::vector<std::size_t> first(passes_per_patch.size() + 1, 0);
  for (std::size_t p = 0; p < passes_per_patch.size(); ++p) first[p + 1] = first[p] + passes_per_patch[p];

  // Each setup's passes in its machine frame, kept off the whole part.
  std::vector<Toolpath> cuts(setups.size());
  std::vector<SetupProgram> progs(setups.size());
  const double tolerance = part_clearance_tolerance(path.chord_error);
  // One tree, placed in each setup's frame.
  const MeshDistance part_faces(part);
  const MeshDistance part_distance =
      part_faces.with_points(points_outside(part, part_faces, held_points)).with_points(keep_out.samples, keep_out.margin);
  // The part's vertices and the points it holds, for the highest point in each setup.
  std::vector<Eigen::Vector3d> part_points = part.vertices;
  part_points.insert(part_points.end(), held_points.begin(), held_points.end());
  // In a setup's frame, and the keep-out samples raised by their margin: the part may reach there.
  const auto placed_points = [&](const Setup& s) {
    std::vector<Eigen::Vector3d> placed;
    placed.reserve(part_points.size() + keep_out.samples.size());
    for (const auto& v : part_points) placed.push_back(s.rotation * v + s.translation);
    for (const auto& v : keep_out.samples)
      placed.push_back(s.rotation * v + s.translation + Eigen::Vector3d(0, 0, keep_out.margin));
    return placed;
  };
  // Progress: keeping the passes off the part up to 0.3 (by passes), rest passes to 0.85, links.
  const bool resting = rest && rest->rounds > 0 && part.num_faces() > 0;
  const double kept_share = resting ? 0.3 : 0.8;
  std::size_t passes_done = 0;
  for (std::size_t index = 0; index < setups.size(); ++index) {
    const Setup& s = setups[index];
    report(kept_share * double(passes_done) / std::max<std::size_t>(path.passes.size(), 1),
           "keeping setup " + std::to_string(index + 1) + " of " + std::to_string(setups.size()) + " off the part");
    Toolpath& local = cuts[index];
    local.tool_radius = path.tool_radius;
    local.scallop_height = path.scallop_height;
    local.chord_error = path.chord_error;
    local.pattern = path.pattern;
    std::vector<double> max_drop;  // per pass
    for (std::size_t p : s.patches) {
      if (p >= passes_per_patch.size())
        throw std::invalid_argument("setup '" + s.name + "': patch " + std::to_string(p) + " has no passes");
      for (std::size_t k = first[p]; k < first[p + 1]; ++k) {
        ToolpathPass pass = path.passes[k];
        for (auto& c : pass.contact) c = s.rotation * c + s.translation;
        for (auto& n : pass.normal) n = s.rotation * n;
        local.passes.push_back(std::move(pass));
        // Along z a patch as steep as a setup takes (n . axis >= 0.2) may stand 5 times as far
        // above the part as it is off it.
        max_drop.push_back(p < patch_off_part.size() ? 5 * patch_off_part[p] : 0.0);
      }
      passes_done += first[p + 1] - first[p];
    }
    if (local.passes.empty() || part.num_faces() == 0) continue;
    double top_z = -std::numeric_limits<double>::infinity();
    for (const auto& v : placed_points(s)) top_z = std::max(top_z, v.z());
    const KeepOffStats kept =
        keep_off_part(local, max_drop, part_distance.placed(s.rotation, s.translation), top_z, tolerance);
    SetupProgram& prog = progs[index];
    prog.lifted = kept.lifted, prog.lift_max = kept.lift_max, prog.dropped = kept.dropped, prog.splits = kept.splits;
    prog.lowered = kept.lowered, prog.lower_max = kept.lower_max;
    prog.high_lifts = kept.high, prog.high_lift_max = kept.high_max;
    prog.high_lift_at = s.rotation.transpose() * (kept.high_at - s.translation);  // to the part's frame
  }

  // What they leave, cut again from the setups that reach it (and from new ones).
  std::vector<Setup> all;
  if (resting) {
    RestOptions o = *rest;
    o.tool_radius = path.tool_radius, o.scallop = path.scallop_height, o.chord = path.chord_error;
    o.progress = [&](double f, const std::string& what) { report(0.3 + 0.55 * f, what); };
    all.assign(setups.begin(), setups.end());
    RestResult result = add_rest_passes(part, all, cuts, o, &part_distance);
    progs.resize(all.size());
    for (std::size_t index = 0; index < all.size(); ++index)
      progs[index].rest_passes = result.passes[index], progs[index].rest_length = result.length[index];
    result.added_setups.assign(all.begin() + std::ptrdiff_t(setups.size()), all.end());
    if (rest_result) *rest_result = std::move(result);
  }

  // Linked and written, the setups side by side; numbered in order after.
  if (all.empty()) all = setups;
  report(resting ? 0.85 : 0.8, "linking the passes of " + std::to_string(all.size()) + " setups");
  std::vector<std::optional<SetupProgram>> linked_setups(all.size());
  tbb::parallel_for(std::size_t(0), all.size(), [&](std::size_t index) {
    const Setup& s = all[index];
    Toolpath& local = cuts[index];
    // Every ball left out (no clear way to any of them; an ABC plate's noisy cloud had such a
    // clamping, and linking nothing stopped the whole part): no program for this setup.
    if (local.passes.empty()) return;
    const std::vector<Eigen::Vector3d> placed = placed_points(s);
    SetupProgram prog = progs[index];
    prog.setup = index;
    const MeshDistance distance = part_distance.placed(s.rotation, s.translation);
    LinkOptions linking = link;
    if (part.num_faces() > 0) {
      // Links kept as far off the part as the balls: checked against its faces, not only its
      // vertices.
      const double r = path.tool_radius;
      linking.tolerance = tolerance;
      linking.link_clear = [&distance, r, tolerance](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        return distance.clear_along(a, b, r / 4, r - tolerance);
      };
      linking.drop = [&distance](const Eigen::Vector3d& c, double radius, double max) {
        return distance.touch_along(c, Eigen::Vector3d(0, 0, -1), radius, max);
      };
    }
    const LinkedPath linked = link_passes(local, placed, linking);
    prog.name = s.name;
    GCodeOptions g = gcode;
    g.graph_name = gcode.graph_name.empty() ? "setup " + s.name : gcode.graph_name + ", setup " + s.name;
    prog.gcode = write_gcode(linked, g);
    prog.passes = local.passes.size();
    prog.moves = linked.moves.size();
    prog.clearance_z = linked.clearance_z;
    prog.linked = linked;
    for (Move& m : prog.linked.moves) m.tip = as_written(m.tip);  // as the program has them
    linked_setups[index] = std::move(prog);
  });
  std::vector<SetupProgram> out;
  for (auto& prog : linked_setups)
    if (prog) {
      prog->file = "setup_" + std::to_string(out.size() + 1) + ".ngc";
      out.push_back(std::move(*prog));
    }
  report(1, "programs written");
  return out;
}

nlohmann::json setups_file(const std::vector<SetupProgram>& programs, const std::vector<Setup>& setups) {
  nlohmann::json list = nlohmann::json::array();
  for (const SetupProgram& p : programs)
    list.push_back({{"name", p.name}, {"gcode", p.file}, {"part_to_machine", part_to_machine(setups.at(p.setup))}});
  return {{"format", "scallop-setups/1"}, {"units", "mm"}, {"setups", list}};
}

}  // namespace scallop
