#include "nodes/cloud/register.h"

namespace scallop {

// Each in its own nodes/cloud/<name>_node.cpp, in a namespace of the domain's own so that another
// domain's node of the same name (mesh.denoise beside cloud.denoise) links beside it.
namespace cloud_nodes {
NodeDecl make_clean_node();
NodeDecl make_knn_node();
NodeDecl make_normals_node();
NodeDecl make_boundary_node();
NodeDecl make_boundary_order_node();
NodeDecl make_smooth_node();
NodeDecl make_height_field_node();
NodeDecl make_denoise_node();
NodeDecl make_trim_steep_node();
NodeDecl make_surface_band_node();
}  // namespace cloud_nodes

void register_cloud(Registry& registry) {
  using namespace cloud_nodes;
  registry.add_domain("cloud", {make_clean_node(), make_knn_node(), make_normals_node(), make_boundary_node(),
                                make_boundary_order_node(), make_smooth_node(), make_height_field_node(),
                                make_denoise_node(), make_trim_steep_node(), make_surface_band_node()});
}

}  // namespace scallop
