#include "nodes/surface/register.h"

namespace scallop {

namespace surface_nodes {
NodeDecl make_fit_bspline_node();
NodeDecl make_setups_node();
}  // namespace surface_nodes

void register_surface(Registry& registry) {
  using namespace surface_nodes;
  registry.add_domain("surface", {make_fit_bspline_node(), make_setups_node()});
}

}  // namespace scallop
