#include "nodes/path/register.h"

namespace scallop {

// Each in its own nodes/path/<name>_node.cpp, in a namespace of the domain's own so that another
// domain's node of the same name (mesh.denoise beside cloud.denoise) links beside it.
namespace path_nodes {
NodeDecl make_isoparametric_node();
NodeDecl make_gouge_guard_node();
NodeDecl make_contour_grid_node();
}  // namespace path_nodes

void register_path(Registry& registry) {
  using namespace path_nodes;
  registry.add_domain("path", {make_isoparametric_node(), make_gouge_guard_node(), make_contour_grid_node()});
}

}  // namespace scallop
