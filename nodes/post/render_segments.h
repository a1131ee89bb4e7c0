// What a picture of a segmentation draws over the mesh (post.render with segments): the clipping
// edges, and per patch an arrow along its machining direction from the middle of its grid.
#pragma once

#include <vector>

#include "nodes/post/render_mesh.h"
#include "nodes/types/segments.h"

namespace scallop {

// Clipping edges 2 px dark grey (hidden where faces cover them); arrows 2 px black from each
// patch's middle grid vertex along its direction, 8 % of the mesh's bounding box diagonal long,
// with a head of a quarter of that, drawn where that vertex is seen.
std::vector<MeshOverlay> segment_overlays(const Segments& segments);

// The segments' mesh with face_label a colour slot per patch (0, 1, ...): neighbouring patches
// get different slots (greedy colouring of the patches' adjacency, larger patches first).
Mesh patch_colour_mesh(const Segments& segments);

}  // namespace scallop
