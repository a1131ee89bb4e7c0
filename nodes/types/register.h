// The value types the nodes pass: clouds, neighbourhoods, maps, tool paths, programs, reports,
// pictures.
#pragma once

#include "engine/node.h"

namespace scallop {

// Adds the built-in value types to `registry` (before any node that uses them).
void register_types(Registry& registry);

}  // namespace scallop
