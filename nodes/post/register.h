// The post.* nodes: linking, G-code, simulation and pictures.
#pragma once

#include "engine/node.h"

namespace scallop {

// Adds the post.* nodes to `registry`; the value types they use must be registered already
// (register_types).
void register_post(Registry& registry);

}  // namespace scallop
