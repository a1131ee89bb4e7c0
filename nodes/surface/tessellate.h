// A mesh of fitted surfaces, for pictures and for measuring them against other meshes.
#pragma once

#include "nodes/types/mesh.h"
#include "nodes/types/surfaces.h"

namespace scallop {

// Each patch sampled on an n by n grid of quads of its domain (n >= 1), faces counter-clockwise
// seen along the patch's direction (S_u x S_v), face_label = patch index; patches are not welded
// to each other. feature_edges: every patch's outline, so a picture shows where patches meet.
Mesh tessellate_surfaces(const Surfaces& surfaces, int n);

}  // namespace scallop
