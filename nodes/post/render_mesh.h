// A picture of a mesh for people: shaded faces (a z-buffer), feature edges in a strong colour,
// optionally a colour per face label (segments).
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "nodes/post/render.h"
#include "nodes/types/mesh.h"

namespace scallop {

// A polyline drawn over the mesh: clipping edges, direction arrows, a surface's iso-lines.
struct MeshOverlay {
  std::vector<Eigen::Vector3d> points;  // mm, joined in order
  std::array<double, 3> colour{0, 0, 0};  // RGB in [0, 1]
  int thick = 1;                          // pixels
  bool whole_if_start_seen = false;       // drawn whole when its first point is not hidden by a
                                          // face (arrows standing out of it), else not at all
};

struct MeshPictureOptions {
  std::string view = "iso";  // "iso" (seen from (-1, -1, 1), as render_path's), "back" (from (1, 1, 1)),
                             // "top", "front" (from -Y)
  int width = 1000;          // pixels; the height follows the mesh's projected aspect
  bool by_label = false;     // colour each face by its label (grey when -1 or no labels)
  bool wireframe = false;    // thin dark polygon edges (readable up to a few thousand faces)
  std::vector<MeshOverlay> overlays;  // drawn last, in order
  std::vector<std::array<double, 3>> face_colours;  // a colour per face (RGB in [0, 1]), before labels
};

// The mesh shaded with a headlight (Lambert on both sides, so an inverted face still shows) over
// white, feature edges drawn 2 px wide in red on top where visible, then the overlays. Throws std::invalid_argument
// for an unknown view or a mesh with no faces.
Picture render_mesh(const Mesh& mesh, const MeshPictureOptions& options);

// An SVG holding a PNG picture (base64 data URI): the vector form of a picture with too many
// faces to draw as vectors.
std::string svg_of_png(const Picture& picture, const std::string& png);

}  // namespace scallop
