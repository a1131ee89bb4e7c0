#include "nodes/post/register.h"

namespace scallop {

// Each in its own nodes/post/<name>_node.cpp, in a namespace of the domain's own so that another
// domain's node of the same name (mesh.denoise beside cloud.denoise) links beside it.
namespace post_nodes {
NodeDecl make_link_node();
NodeDecl make_gcode_node();
NodeDecl make_simulate_node();
NodeDecl make_surface_samples_node();
NodeDecl make_render_node();
NodeDecl make_setup_programs_node();
NodeDecl make_simulate_part_node();
NodeDecl make_setup_sheet_node();
}  // namespace post_nodes

void register_post(Registry& registry) {
  using namespace post_nodes;
  registry.add_domain("post",
                      {make_link_node(), make_gcode_node(), make_simulate_node(), make_surface_samples_node(), make_render_node(),
                       make_setup_programs_node(), make_simulate_part_node(),
                       make_setup_sheet_node()});
}

}  // namespace scallop
