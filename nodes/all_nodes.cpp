#include "nodes/all_nodes.h"

#include "nodes/cloud/register.h"
#include "nodes/io/register.h"
#include "nodes/mesh/register.h"
#include "nodes/param/register.h"
#include "nodes/path/register.h"
#include "nodes/post/register.h"
#include "nodes/surface/register.h"
#include "nodes/types/register.h"

namespace scallop {

// Each domain registers its own nodes (nodes/<domain>/register.cpp), after the value types.
void register_builtins(Registry& r) {
  register_types(r);
  register_io(r);
  register_cloud(r);
  register_mesh(r);
  register_surface(r);
  register_param(r);
  register_path(r);
  register_post(r);
}

const Registry& builtin_registry() {
  static const Registry registry = [] {
    Registry r;
    register_builtins(r);
    return r;
  }();
  return registry;
}

}  // namespace scallop
