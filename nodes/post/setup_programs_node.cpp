#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "engine/output_path.h"
#include "nodes/geom/point_text.h"
#include "nodes/io/write_support.h"
#include "nodes/mesh/setup_base.h"
#include "nodes/post/setup_programs.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {

namespace {
struct SetupProgramsOptions {
  std::string dialect = "linuxcnc";
  double feed = 1000, plunge_feed = 300, spindle_rpm = 10000, lead_height = 1;
  double safety = 5;
  int rest_rounds = 3;
  int rest_setups = 2;
  double base_angle = 10;
  double tangle_margin = -1;
};
}  // namespace

NodeDecl make_setup_programs_node() {
  NodeDecl d;
  d.type = "post.setup_programs";
  d.version = 25;  // 25: the places no clamping comes down to go with the programs (SetupPaths unreached_at), and whether any direction tried would; 24: where the mesh is the part itself (no input cloud), no margin off the faces where it crosses itself (tangle_margin; the block x 5 from its mesh: 12.7 mm, its bores left uncut, 8.2 %); 23: the lifts over r and the moves not kept off told in one line each, not a line per setup; 21: down at rapid rate to 1 mm above a pass start, then the plunge (post.link v7); 22: the rapids stop where a ball of r + 1 mm would touch the part (post.link v8); 20: a pass end raised to where a ball of r - tolerance coming down from above the part first touches it, and a rest setup's way up tested the same way (MeshDistance::touch_along, one ray), not by a bisection of clear_along marches (to 1e-4); 19: balls dropped onto the part exactly (MeshDistance::touch_along: one ray through the triangles' boxes grown by r, ball_touch_triangle), not by steps of the distance less r (the rest rasters' drops took 10.8 steps a ball on the block); 18: a move's least distance from the part found exactly in one search (MeshDistance::least_on_segment), not bounded from samples: moves just clear of r - tolerance are no longer lifted by the bound's shortfall (the block's 200k cloud: 547 k lifts -> 467 k); 17: where the measured mesh (input measured, else mesh) crosses itself, the balls kept a margin farther from its tangled faces (crossing_pairs, tangled_faces, tangle_margin); 16: balls dropped by their distance less r again (15: plane steps on slopes, slower on the block: 218 -> 243 s); 14: moves, pass ends and rest setups tested clear by MeshDistance::clear_along (sooner, never less safe); 13: the balls, moves and links kept off the cloud's points too (input cloud); 12: a move lacking less than its ends' height difference goes up by what it lacks; 11: the rest search also refines the thin band beside concave edges a ball of 0.9 r reaches; 10: rest passes where the others leave material, rest setups; 2: outputs the programs' moves as written; 4: pass ends raised until the ball goes up clear; 5: the moves stored without their padding bytes; 6: a move raised level that still reaches in goes up whole; 7: passes split where a move stays too near; 8: balls lowered onto the part where the surface stands above it; 9: the report counts balls lifted more than r
                  // 3: moves and links kept off the part's faces exactly (then MeshDistance::least_along)
  d.description =
      "one G-code program per clamping: each setup's passes taken into its machine frame (tool axis +z), kept off "
      "and linked against the whole part, rest passes where they leave material over the scallop limit, and the "
      "setups file (scallop-setups/1) naming them";
  d.cache_on_disk = false;  // it writes files
  d.input("toolpath", "Toolpath", "the passes of every patch, patch by patch (path.contour_grid)")
      .input("contours", "Report", "path.contour_grid's report: how many passes each patch has")
      .input("setups", "Report", "surface.setups' report: the clampings, their part_to_machine and patches")
      .input("mesh", "Mesh", "the whole part: links avoid it and the clearance plane clears it in every setup")
      .input("base", "Report",
             "mesh.setup_base's report: faces within base_angle of its base_direction sit on the table, and rest "
             "passes leave them; absent: every face may get rest passes", false)
      .input("cloud", "Cloud",
             "the points the part was measured at (the cloud `mesh` was made from): balls, moves and links are kept "
             "off them too, where the mesh does not hold them all (a fold, a filled hole)", false)
      .input("measured", "Mesh",
             "the mesh made from the cloud, before mesh.cloud_envelope moved it out into `mesh`: where it crosses "
             "itself (a gap finer than the points), the balls are kept a margin farther from its tangled faces "
             "(absent: where `mesh` itself crosses; an outer mesh crosses itself at every concave edge, harmlessly)",
             false)
      .output("file", "File", "the setups file")
      .output("programs", "SetupPaths", "each program's moves with its part_to_machine (post.simulate_part)")
      .output("report", "Report", "{setups: [{name, gcode, passes, moves, clearance_z (mm, machine frame), lifted (ball positions kept off "
              "the part), lift_max (mm), splits (passes cut where a move could not be kept off the part), dropped (ball "
              "positions left out there), lowered (ball positions lowered onto the part where the patch's surface "
              "stands above it), lower_max (mm), high_lifts (planned ball positions lifted more than the tool's radius: "
              "from this setup the part is in the way there), high_lift_max (mm), high_lift_at (its planned contact, "
              "part frame), rest_passes (passes added where the others left material), rest_length (mm)}], rest: {rounds, inside_drops (rest balls left out: they fell through a hole in the mesh onto the inside of a face), new_setups (clampings added for places no other setup's axis comes down to), "
              "spacing, measured_area, left_area_before (mm² the setups' own passes leave over 0.8 h or uncut, by the "
              "rest search's samples), left_area_after, unreached_area (left where no setup's axis comes down clear), "
              "unreached_at [[x, y, z], ...] (part frame), unreached_by_any_direction (no direction the search for clampings "
              "tried comes down to them)}, crossing_pairs and tangled_faces (where the mesh crosses "
              "itself, and the faces beside those turned into the part: nodes/mesh/self_crossings.h), tangle_margin "
              "(mm: the balls are kept that much farther from them)}")
      .param_output_path("path", "the setups file to write, relative to the output folder (-o); the programs "
                                 "(setup_1.ngc, ...) go beside it");
  d.options<SetupProgramsOptions>()
      .choice("dialect", &SetupProgramsOptions::dialect, {"linuxcnc", "grbl", "fanuc"}, "controller dialect")
      .number("feed", &SetupProgramsOptions::feed, 1e-3, 1e6, "mm/min", "feed rate of cutting moves")
      .number("plunge_feed", &SetupProgramsOptions::plunge_feed, 1e-3, 1e6, "mm/min", "feed rate of plunges")
      .number("spindle_rpm", &SetupProgramsOptions::spindle_rpm, 0, 1e6, "rpm", "spindle speed; 0: no spindle words")
      .number("safety", &SetupProgramsOptions::safety, 0, 1e3, "mm",
              "clearance plane height above the part's highest point in each setup")
      .number("lead_height", &SetupProgramsOptions::lead_height, 0, 1e3, "mm",
              "how far the rapids keep off the part, more than the stock left on it: they stop where a ball of r + "
              "this coming down would touch it, at least this above a pass start, and the tool plunges from there")
      .integer("rest_rounds", &SetupProgramsOptions::rest_rounds, 0, 10, "",
               "rounds of rest passes: what every setup's passes leave over the scallop limit is found on the part "
               "and cut again by a raster of balls dropped onto it, from the setup whose axis reaches it best, the "
               "raster finer each round; 0: none")
      .integer("rest_setups", &SetupProgramsOptions::rest_setups, 0, 10, "",
               "clampings the rest passes may add for places no setup's axis comes down to (each along the direction "
               "that comes down to the most of them); 0: such places are left as stock and reported")
      .number("base_angle", &SetupProgramsOptions::base_angle, 0, 90, "deg",
              "faces within this of the base direction are on the table")
      .number("tangle_margin", &SetupProgramsOptions::tangle_margin, -1, 1000, "mm",
              "how much farther than r balls are kept from the faces where the measured mesh crosses itself: -1 "
              "twice those faces' mean edge where the mesh was made from a cloud (input cloud: a gap finer than "
              "its points), none where the mesh is the part itself (a CAD mesh whose facets fold)");
  d.run = [](NodeContext& ctx) {
    auto path = ctx.input<Toolpath>("toolpath");
    const auto& contours = ctx.input<Report>("contours")->data;
    const auto& setups_report = ctx.input<Report>("setups")->data;
    auto mesh = ctx.input<Mesh>("mesh");
    const SetupProgramsOptions o = ctx.options<SetupProgramsOptions>();
    const std::string param = ctx.text("path");
    if (param.empty()) throw NodeError("parameter 'path' is empty: give the setups file to write");
    std::vector<std::size_t> counts;
    std::vector<double> off_part;
    for (const auto& p : contours.value("patches", nlohmann::json::array())) {
      counts.push_back(p.value("contours", 0));
      off_part.push_back(p.value("part_distance_max", 0.0));
    }
    LinkOptions link;
    link.safety = o.safety;
    link.lead_height = o.lead_height;
    GCodeOptions g;
    g.dialect = o.dialect, g.feed = o.feed, g.plunge_feed = o.plunge_feed, g.spindle_rpm = o.spindle_rpm;
    RestOptions rest;
    rest.rounds = o.rest_rounds;
    rest.max_new_setups = o.rest_setups;
    rest.base_angle = o.base_angle;
    if (ctx.has_input("base")) {
      try {
        rest.base_normal = base_direction_of(ctx.input<Report>("base")->data);
      } catch (const std::invalid_argument& e) {
        throw NodeError(e.what());
      }
    }
    RestResult rest_result;
    // Where the mesh crosses itself its faces bound nothing: the balls are kept a margin off them.
    const auto measured = ctx.has_input("measured") ? ctx.input<Mesh>("measured") : mesh;
    const SelfCrossings crossings = self_crossings(*measured);
    const TangleKeepOut keep_out = tangle_keep_out(*measured, crossings, tangle_margin_for(o.tangle_margin, ctx.has_input("cloud")));
    if (!crossings.tangled.empty()) {
      const Eigen::Vector3d at = measured->vertices[measured->face(crossings.tangled.front())[0]];
      char text[500];
      if (keep_out.margin > 0)
        std::snprintf(text, sizeof text,
                      "the part's mesh crosses itself (%zu face pairs, %zu faces tangled, around %s): the part is not "
                      "known there, so the balls are kept %.3g mm farther from those faces (stock the certificate counts)",
                      crossings.pairs.size(), crossings.tangled.size(), point_text(at, 2).c_str(), keep_out.margin);
      else
        std::snprintf(text, sizeof text,
                      "the part's mesh crosses itself (%zu face pairs, %zu faces tangled, around %s): its faces there "
                      "are taken as the part (a mesh given as the part; tangle_margin keeps the balls farther), and a "
                      "judge's inside test may not hold there",
                      crossings.pairs.size(), crossings.tangled.size(), point_text(at, 2).c_str());
      ctx.warn(text);
    }
    std::vector<Setup> setups;
    std::vector<SetupProgram> programs;
    try {
      setups = setups_from_report(setups_report, counts.size());
      const auto cloud = ctx.has_input("cloud") ? ctx.input<PointCloud>("cloud") : nullptr;
      programs = setup_programs(*path, counts, setups, *mesh, link, g, off_part, &rest, &rest_result,
                                cloud ? cloud->points : std::vector<Eigen::Vector3d>{},
                                [&](double f, const std::string& what) { ctx.progress(f, what); }, keep_out);
    } catch (const std::exception& e) {
      throw NodeError(std::string("post.setup_programs: ") + e.what());
    }
    setups.insert(setups.end(), rest_result.added_setups.begin(), rest_result.added_setups.end());
    const nlohmann::json file = setups_file(programs, setups);
    std::vector<std::pair<std::string, std::string>> beside;
    for (const SetupProgram& p : programs) beside.emplace_back(p.file, p.gcode);
    ctx.set("file", io::write_output_files(ctx, param, file.dump(1) + "\n", beside));
    std::vector<bool> written(setups.size(), false);
    for (const SetupProgram& p : programs) written[p.setup] = true;
    for (std::size_t i = 0; i < setups.size(); ++i)
      if (!written[i] && std::any_of(setups[i].patches.begin(), setups[i].patches.end(),
                                     [&](std::size_t p) { return p < counts.size() && counts[p] > 0; }))
        ctx.warn("setup '" + setups[i].name + "': no ball of its passes could be kept off the part: no program is "
                 "written for it, and its patches are stock the certificate counts");
    // Each kind in one line however many setups it concerns (the face bust: 17 lines), the worst
    // setup named, every one in the report's setups.
    {
      std::size_t setups_lifting = 0, lifted = 0, setups_splitting = 0, splits = 0, dropped = 0;
      const SetupProgram* highest = nullptr;
      const SetupProgram* most_split = nullptr;
      for (const SetupProgram& p : programs) {
        if (p.high_lifts > 0) {
          ++setups_lifting, lifted += p.high_lifts;
          if (!highest || p.high_lift_max > highest->high_lift_max) highest = &p;
        }
        if (p.splits > 0) {
          ++setups_splitting, splits += p.splits, dropped += p.dropped;
          if (!most_split || p.splits > most_split->splits) most_split = &p;
        }
      }
      if (highest)
        ctx.warn((setups_lifting == 1 ? "setup '" + highest->name + "': " : "in " + std::to_string(setups_lifting) +
                                                                               " setups: ") +
                 std::to_string(lifted) + " ball positions were lifted more than the tool's radius to keep them off "
                 "the part (up to " + short_number(highest->high_lift_max) + " mm" +
                 (setups_lifting == 1 ? "" : " in setup '" + highest->name + "'") + ", planned at " +
                 point_text(highest->high_lift_at, 2) + " in the part's frame" +
                 (setups_lifting == 1 ? "" : "; the report's high_lifts per setup") +
                 "): from that direction the part is in the way there, and what they were to cut is stock the "
                 "certificate counts");
      if (most_split)
        ctx.warn((setups_splitting == 1 ? "setup '" + most_split->name + "': "
                                        : "in " + std::to_string(setups_splitting) + " setups (the most in '" +
                                              most_split->name + "'; the report's splits per setup): ") +
                 std::to_string(splits) + " moves could not be kept off the part (under an overhang): the passes are "
                 "cut there and " + std::to_string(dropped) + " ball positions left out (stock the certificate counts)");
    }
    if (rest_result.inside_drops > 0)
      ctx.warn(std::to_string(rest_result.inside_drops) + " rest balls came to rest on the inside of a face (through "
               "a hole in the mesh) and were left out");
    for (const Setup& s : rest_result.added_setups)
      ctx.warn("setup '" + s.name + "' added: no other setup's axis comes down to places its rest passes cut; one "
               "more clamping for the machinist (rest_rounds=0 or rest_setups=0 to leave them as stock)");
    if (rest_result.unreached_area > 0)
      ctx.warn(short_number(rest_result.unreached_area) + " mm² of the part is left over the scallop limit where no "
               "setup's axis comes down to it clear of the part (around " +
               point_text(rest_result.unreached_at.front(), 2) +
               " in the part's frame): stock the certificate counts; " +
               (rest_result.no_direction_left ? "no direction the search tried comes down to it either: not for this "
                                                "tool on a 3-axis machine"
                                              : "another clamping would reach it (rest_setups)"));
    nlohmann::json list = nlohmann::json::array();
    for (const SetupProgram& p : programs)
      list.push_back({{"name", p.name}, {"gcode", p.file}, {"passes", p.passes}, {"moves", p.moves},
                      {"clearance_z", p.clearance_z}, {"lifted", p.lifted}, {"lift_max", p.lift_max},
                      {"splits", p.splits}, {"dropped", p.dropped}, {"lowered", p.lowered},
                      {"lower_max", p.lower_max}, {"high_lifts", p.high_lifts}, {"high_lift_max", p.high_lift_max},
                      {"high_lift_at", {p.high_lift_at.x(), p.high_lift_at.y(), p.high_lift_at.z()}},
                      {"rest_passes", p.rest_passes}, {"rest_length", p.rest_length}});
    SetupPaths paths;
    for (const SetupProgram& p : programs)
      paths.setups.push_back({p.name, p.file, setups[p.setup].rotation, setups[p.setup].translation, p.linked});
    paths.unreached_at = rest_result.unreached_at;
    paths.unreached_area = rest_result.unreached_area;
    paths.unreached_by_any_direction = rest_result.no_direction_left;
    ctx.set("programs", std::move(paths));
    Report report;
    nlohmann::json unreached = nlohmann::json::array();
    for (const auto& p : rest_result.unreached_at) unreached.push_back({p.x(), p.y(), p.z()});
    report.data = {{"setups", list},
                   {"crossing_pairs", crossings.pairs.size()},
                   {"tangled_faces", crossings.tangled.size()},
                   {"tangle_margin", keep_out.margin},
                   {"rest",
                    {{"rounds", rest_result.rounds},
                     {"inside_drops", rest_result.inside_drops},
                     {"new_setups", rest_result.new_setups},
                     {"spacing", rest_result.spacing},
                     {"measured_area", rest_result.measured_area},
                     {"left_area_before", rest_result.left_area_before},
                     {"left_area_after", rest_result.left_area_after},
                     {"unreached_area", rest_result.unreached_area},
                     {"unreached_at", unreached},
                     {"unreached_by_any_direction", rest_result.no_direction_left}}}};
    ctx.set("report", std::move(report));
  };
  return d;
}

}  // namespace scallop::post_nodes
