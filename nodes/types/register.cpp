#include "nodes/types/register.h"

#include "engine/file_ref.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"
#include "nodes/types/param.h"
#include "nodes/types/segments.h"
#include "nodes/types/simulation.h"
#include "nodes/types/surface_samples.h"
#include "nodes/types/surfaces.h"
#include "nodes/types/svg.h"
#include "nodes/types/toolpath.h"

namespace scallop {

void register_types(Registry& r) {
  auto& v = r.values();
  v.add({"File", "txt", "an input file (path and content hash)", FileRef::deserialize});
  // format 2: per-point uncertainty
  v.add({"Cloud", "ply", "points with optional unit normals (mm)", PointCloud::deserialize, 2});
  v.add({"Mesh", "ply", "polygon mesh: vertices, faces, optional normals, face labels, feature edges (mm)", Mesh::deserialize});
  v.add({"Segments", "ply", "a quad mesh cut into sharp height fields: per patch its grid of vertices and machining direction",
         Segments::deserialize});
  v.add({"Surfaces", "json", "one B-spline surface per sharp height field: poles, knots, machining direction, fit error",
         Surfaces::deserialize});
  v.add({"Neighbors", "bin", "k nearest neighbours of every point", Neighborhoods::deserialize});
  v.add({"Loops", "bin", "boundary points ordered into loops, outer first", BoundaryLoops::deserialize});
  v.add({"Laplacian", "bin", "sparse meshless Laplacian", Laplacian::deserialize});
  v.add({"UVMap", "bin", "(u,v) parameterisation of the points", UVMap::deserialize});
  v.add({"Toolpath", "json", "passes of cutter-contact points for a ball-end tool", Toolpath::deserialize});
  v.add({"LinkedPath", "bin", "linked machine moves (tool tip)", LinkedPath::deserialize});
  v.add({"SetupPaths", "bin",
         "a part's programs, one per clamping: name, file, part_to_machine and linked moves; the places no clamping "
         "comes down to",
         SetupPaths::deserialize, 2});  // 2: unreached_at, unreached_area, unreached_by_any_direction
  v.add({"GCode", "ngc", "a machine program", GCode::deserialize});
  v.add({"Report", "json", "a JSON report", Report::deserialize});
  v.add({"Simulation", "bin", "a cutting simulation: what the path left at every surface sample, its limits and its report",
         Simulation::deserialize, 2});  // 2: the face of each sample (whole parts)
  v.add({"SurfaceSamples", "bin",
         "the cloud's height field sampled on the certificate's grid: place, normal, area and uncertainty of each sample",
         SurfaceSamples::deserialize});
  v.add({"Image", "png", "a PNG picture", Image::deserialize});
  v.add({"Svg", "svg", "an SVG picture", Svg::deserialize});
}

}  // namespace scallop
