#include "nodes/param/register.h"

namespace scallop {

// Each in its own nodes/param/<name>_node.cpp, in a namespace of the domain's own so that another
// domain's node of the same name (mesh.denoise beside cloud.denoise) links beside it.
namespace param_nodes {
NodeDecl make_boundary_map_node();
NodeDecl make_laplacian_node();
NodeDecl make_harmonic_node();
NodeDecl make_map_check_node();
NodeDecl make_planar_node();
}  // namespace param_nodes

void register_param(Registry& registry) {
  using namespace param_nodes;
  registry.add_domain("param", {make_boundary_map_node(), make_laplacian_node(), make_harmonic_node(),
                                make_map_check_node(), make_planar_node()});
}

}  // namespace scallop
