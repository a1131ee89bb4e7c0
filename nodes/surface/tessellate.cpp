#include "nodes/surface/tessellate.h"

#include <algorithm>
#include <stdexcept>

namespace scallop {

Mesh tessellate_surfaces(const Surfaces& surfaces, int n) {
  if (n < 1) throw std::invalid_argument("tessellate_surfaces: n must be 1 or more");
  Mesh m;
  for (std::size_t p = 0; p < surfaces.patches.size(); ++p) {
    const BSplineSurface& s = surfaces.patches[p].surface;
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(i * (n + 1) + j); };
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) m.vertices.push_back(surface_point(s, double(j) / n, double(i) / n));
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        m.add_face({at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)});
        m.face_label.push_back(static_cast<std::int32_t>(p));
      }
    auto edge = [&](std::uint32_t a, std::uint32_t b) { m.feature_edges.push_back({std::min(a, b), std::max(a, b)}); };
    for (int k = 0; k < n; ++k) {
      edge(at(0, k), at(0, k + 1));
      edge(at(n, k), at(n, k + 1));
      edge(at(k, 0), at(k + 1, 0));
      edge(at(k, n), at(k + 1, n));
    }
  }
  return m;
}

}  // namespace scallop
