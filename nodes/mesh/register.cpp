#include "nodes/mesh/register.h"

namespace scallop {

// Each in its own nodes/mesh/<name>_node.cpp.
namespace mesh_nodes {
NodeDecl make_denoise_node();
NodeDecl make_sharp_edges_node();
}  // namespace mesh_nodes

void register_mesh(Registry& registry) {
  using namespace mesh_nodes;
  registry.add_domain("mesh", {make_denoise_node(), make_sharp_edges_node()});
}

}  // namespace scallop
