// The mesh.* nodes: denoising a mesh and finding its features.
#pragma once

#include "engine/node.h"

namespace scallop {

// Adds the mesh.* nodes to `registry`; the value types they use must be registered already
// (register_types).
void register_mesh(Registry& registry);

}  // namespace scallop
