#include "nodes/all_nodes.h"

#include "engine/file_ref.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"
#include "nodes/types/svg.h"
#include "nodes/types/toolpath.h"

namespace scallop {

// Each node's declaration lives in its own nodes/<domain>/<name>_node.cpp.
NodeDecl make_read_cloud_node();
NodeDecl make_write_cloud_node();
NodeDecl make_clean_node();
NodeDecl make_knn_node();
NodeDecl make_normals_node();
NodeDecl make_boundary_node();
NodeDecl make_boundary_order_node();
NodeDecl make_smooth_node();
NodeDecl make_denoise_node();
NodeDecl make_height_field_node();
NodeDecl make_trim_steep_node();
NodeDecl make_boundary_map_node();
NodeDecl make_laplacian_node();
NodeDecl make_harmonic_node();
NodeDecl make_map_check_node();
NodeDecl make_isoparametric_node();
NodeDecl make_gouge_guard_node();
NodeDecl make_link_node();
NodeDecl make_gcode_node();
NodeDecl make_simulate_node();
NodeDecl make_render_node();
NodeDecl make_write_toolpath_node();

void register_builtins(Registry& r) {
  auto& v = r.values();
  v.add({"File", "txt", "an input file (path and content hash)", FileRef::deserialize});
  v.add({"Cloud", "ply", "points with optional unit normals (mm)", PointCloud::deserialize});
  v.add({"Neighbors", "bin", "k nearest neighbours of every point", Neighborhoods::deserialize});
  v.add({"Loops", "bin", "boundary points ordered into loops, outer first", BoundaryLoops::deserialize});
  v.add({"Laplacian", "bin", "sparse meshless Laplacian", Laplacian::deserialize});
  v.add({"UVMap", "bin", "(u,v) parameterisation of the points", UVMap::deserialize});
  v.add({"Toolpath", "json", "passes of cutter-contact points for a ball-end tool", Toolpath::deserialize});
  v.add({"LinkedPath", "bin", "linked machine moves (tool tip)", LinkedPath::deserialize});
  v.add({"GCode", "ngc", "a machine program", GCode::deserialize});
  v.add({"Report", "json", "a JSON report", Report::deserialize});
  v.add({"Image", "png", "a PNG picture", Image::deserialize});
  v.add({"Svg", "svg", "an SVG picture", Svg::deserialize});

  for (auto make : {make_read_cloud_node, make_write_cloud_node, make_write_toolpath_node,  // io
                    make_clean_node, make_knn_node, make_normals_node, make_boundary_node,
                    make_boundary_order_node, make_smooth_node, make_height_field_node, make_denoise_node,
                    make_trim_steep_node,  // cloud
                    make_boundary_map_node, make_laplacian_node, make_harmonic_node, make_map_check_node,  // param
                    make_isoparametric_node, make_gouge_guard_node,  // path
                    make_link_node, make_gcode_node, make_simulate_node, make_render_node})  // post
    r.add(make());
}

const Registry& builtin_registry() {
  static const Registry registry = [] {
    Registry r;
    register_builtins(r);
    return r;
  }();
  return registry;
}

}  // namespace scallop
