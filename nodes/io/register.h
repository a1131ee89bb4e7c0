// The io.* nodes: reading and writing clouds, meshes and tool paths.
#pragma once

#include "engine/node.h"

namespace scallop {

// Adds the io.* nodes to `registry`; the value types they use must be registered already
// (register_types).
void register_io(Registry& registry);

}  // namespace scallop
