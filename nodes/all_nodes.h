// The registry of every built-in value type and node type.
#pragma once

#include "engine/node.h"

namespace scallop {

// Registers all built-in value types and nodes.
void register_builtins(Registry& registry);
// A process-wide registry with the built-ins.
const Registry& builtin_registry();

}  // namespace scallop
