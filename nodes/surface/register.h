// The surface.* nodes: parametric surfaces fitted to a part's patches.
#pragma once

#include "engine/node.h"

namespace scallop {

// Adds the surface.* nodes to `registry`; the value types they use must be registered already
// (register_types).
void register_surface(Registry& registry);

}  // namespace scallop
