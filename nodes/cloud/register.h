// The cloud.* nodes: cleaning and analysing the cloud.
#pragma once

#include "engine/node.h"

namespace scallop {

// Adds the cloud.* nodes to `registry`; the value types they use must be registered already
// (register_types).
void register_cloud(Registry& registry);

}  // namespace scallop
