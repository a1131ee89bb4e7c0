// The path.* nodes: tool-path planning.
#pragma once

#include "engine/node.h"

namespace scallop {

// Adds the path.* nodes to `registry`; the value types they use must be registered already
// (register_types).
void register_path(Registry& registry);

}  // namespace scallop
