#include "nodes/io/register.h"

namespace scallop {

// Each in its own nodes/io/<name>_node.cpp, in a namespace of the domain's own so that another
// domain's node of the same name (mesh.denoise beside cloud.denoise) links beside it.
namespace io_nodes {
NodeDecl make_read_cloud_node();
NodeDecl make_write_cloud_node();
NodeDecl make_read_mesh_node();
NodeDecl make_write_mesh_node();
NodeDecl make_write_toolpath_node();
NodeDecl make_write_step_node();
}  // namespace io_nodes

void register_io(Registry& registry) {
  using namespace io_nodes;
  registry.add_domain("io", {make_read_cloud_node(), make_write_cloud_node(), make_read_mesh_node(), make_write_mesh_node(),
                             make_write_toolpath_node(), make_write_step_node()});
}

}  // namespace scallop
