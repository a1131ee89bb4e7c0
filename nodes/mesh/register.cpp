#include "nodes/mesh/register.h"

namespace scallop {

// Each in its own nodes/mesh/<name>_node.cpp, in a namespace of the domain's own so that another
// domain's node of the same name (mesh.denoise beside cloud.denoise) links beside it.
namespace mesh_nodes {
NodeDecl make_reconstruct_node();
NodeDecl make_repair_node();
NodeDecl make_denoise_node();
NodeDecl make_sharp_edges_node();
NodeDecl make_segment_node();
NodeDecl make_quad_remesh_node();
NodeDecl make_setup_base_node();
NodeDecl make_simplify_node();
NodeDecl make_cloud_envelope_node();
NodeDecl make_sharpen_node();
}  // namespace mesh_nodes

void register_mesh(Registry& registry) {
  using namespace mesh_nodes;
  registry.add_domain("mesh", {make_reconstruct_node(), make_repair_node(), make_denoise_node(),
                               make_sharp_edges_node(), make_quad_remesh_node(), make_setup_base_node(),
                               make_segment_node(), make_simplify_node(), make_cloud_envelope_node(),
                               make_sharpen_node()});
}

}  // namespace scallop
