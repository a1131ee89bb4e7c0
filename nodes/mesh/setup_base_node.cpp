#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/mesh/setup_base.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"

namespace scallop::mesh_nodes {

namespace {

// "x,y,z" (brackets and spaces allowed around the numbers) -> the vector.
Eigen::Vector3d parse_direction(const std::string& text) {
  std::string s = text;
  for (char& c : s)
    if (c == ',' || c == '[' || c == ']') c = ' ';
  std::istringstream in(s);
  Eigen::Vector3d d;
  std::string rest;
  if (!(in >> d.x() >> d.y() >> d.z()) || (in >> rest) || !d.allFinite() || std::count(text.begin(), text.end(), ',') != 2)
    throw NodeError("mesh.setup_base: direction must be three numbers \"x,y,z\" (the base's outward normal; "
                    "\"0,0,0\": find the base); got \"" + text + "\"");
  return d;
}

}  // namespace

NodeDecl make_setup_base_node() {
  NodeDecl d;
  d.type = "mesh.setup_base";
  d.version = 1;
  d.description =
      "finds the clamping base as the paper does (K-means of the face normals, the cluster of the best "
      "mu*S + gamma*Gamma) and removes its flat part on the part's extreme plane";
  d.input("mesh", "Mesh", "the part's mesh (triangles or quads), faces outward")
      .output("mesh", "Mesh",
              "the mesh without the base's faces; the vertices still used renumbered in their order, face labels "
              "and feature edges carried")
      .output("report", "Report",
              "{base_direction (the base's outward unit normal: mesh.segment's base input reads it), base_area "
              "(mm2), base_faces, base_fraction (of the area), plane_offset (the extreme plane: v.d = it, mm), how, "
              "clusters: [{centre (the area-weighted mean of its unit normals), direction (the centre's), faces, area, "
              "similarity S (the centre's length), quantity Gamma, objective, flat_direction, flat_area}] best "
              "objective first, chosen (index into clusters, -1: direction given), facing_kept: {faces, area} "
              "(facing the base but off its plane or not joined to it: not removed), vertices_removed, mu, gamma}");
  d.options<SetupBaseOptions>()
      .integer("clusters", &SetupBaseOptions::clusters, 1, 64, "", "k of the K-means of the face normals")
      .number("mu", &SetupBaseOptions::mu, 0, 1, "", "weight of a cluster's similarity S (its area-weighted mean cosine to its mean normal)")
      .number("gamma", &SetupBaseOptions::gamma, 0, 1, "", "weight of a cluster's quantity Gamma (its area over the largest cluster's)")
      .integer("seed", &SetupBaseOptions::seed, 0, 2147483647, "", "seed of the K-means seeding")
      .number("flat_angle", &SetupBaseOptions::flat_angle_deg, 0, 45, "deg",
              "a base face's normal lies within this of the base direction")
      .number("plane_tolerance", &SetupBaseOptions::plane_tolerance, 0, 0.1, "",
              "a base face's corners lie this close to the part's extreme plane along the base direction, times "
              "the bounding box diagonal")
      .number("min_area", &SetupBaseOptions::min_area, 0, 1, "",
              "the smallest flat part taken for a base, as a fraction of the mesh's area; smaller: the part has no "
              "base and the direction must be given");
  d.param_string("direction", "0,0,0",
                 "the base's outward normal \"x,y,z\" (e.g. \"0,0,-1\": the bottom); \"0,0,0\": found by the clusters");
  d.run = [](NodeContext& ctx) {
    auto mesh = ctx.input<Mesh>("mesh");
    SetupBaseOptions o = ctx.options<SetupBaseOptions>();
    o.direction = parse_direction(ctx.text("direction"));
    SetupBaseResult r;
    try {
      r = setup_base(*mesh, o);
    } catch (const std::exception& e) {
      throw NodeError(std::string("mesh.setup_base: ") + e.what());
    }
    if (r.direction.squaredNorm() == 0)
      ctx.warn(r.how);
    else if (r.base_faces.empty())
      ctx.warn("no face faces the given direction " + ctx.text("direction") +
               " on the part's extreme plane: nothing removed");
    nlohmann::json clusters = nlohmann::json::array();
    for (const BaseCluster& c : r.clusters)
      clusters.push_back({{"centre", json_xyz(c.similarity * c.direction)}, {"direction", json_xyz(c.direction)},
                          {"faces", c.faces}, {"area", c.area},
                          {"similarity", c.similarity}, {"quantity", c.quantity}, {"objective", c.objective},
                          {"flat_direction", {c.flat_direction.x(), c.flat_direction.y(), c.flat_direction.z()}},
                          {"flat_area", c.flat_area}});
    Report report;
    report.data = {{"base_direction", json_xyz(r.direction)},
                   {"base_area", r.base_area},
                   {"base_faces", r.base_faces.size()},
                   {"base_fraction", r.base_area / r.area},
                   {"plane_offset", r.plane_offset},
                   {"how", r.how},
                   {"clusters", std::move(clusters)},
                   {"chosen", r.chosen},
                   {"facing_kept", {{"faces", r.facing_kept_faces}, {"area", r.facing_kept_area}}},
                   {"vertices_removed", r.vertices_removed},
                   {"mu", o.mu},
                   {"gamma", o.gamma}};
    ctx.set("report", std::move(report));
    ctx.set("mesh", std::move(r.mesh));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
