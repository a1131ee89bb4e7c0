// The param.* nodes: the (u,v) parameterisation.
#pragma once

#include "engine/node.h"

namespace scallop {

// Adds the param.* nodes to `registry`; the value types they use must be registered already
// (register_types).
void register_param(Registry& registry);

}  // namespace scallop
