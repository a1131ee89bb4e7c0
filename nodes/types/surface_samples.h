// SurfaceSamples value: the cloud's height field sampled on the grid post.simulate measures on
// (nodes/post/surface_grid.h). Taking them needs only the cloud, its outline and the limits, not
// the path, so a graph takes them (post.surface_samples) while the path is still being planned.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/value.h"

namespace scallop {

// What decides the grid: its spacing is sqrt(8 r h) / 12 (verify.py's) unless given, raised to
// keep the grid over the cloud's bounding box within max_samples.
struct SurfaceGridOptions {
  double tool_radius = 0;  // r (mm)
  double scallop = 0;      // h (mm)
  double spacing = 0;      // mm; 0: sqrt(8 r h) / 12
  std::size_t max_samples = 1500000;
  // The patch's outline as closed xy polygons (mm): loops[0] the outer one, the others holes;
  // empty: the outline is guessed from the cloud (SimulateOptions::loops says how).
  std::vector<std::vector<Eigen::Vector2d>> loops;
  double rim_band = 0;  // mm; SimulateOptions::rim_band

  bool operator==(const SurfaceGridOptions&) const = default;
};

// One sample of the surface: where it is, its upward unit normal, the area it stands for and
// how well the surface is known there.
struct SurfacePoint {
  Eigen::Vector3d p, n;
  double weight;       // mm²
  double uncertainty;  // mm
  bool beyond;         // in the rim band beyond the outer loop
};

struct SurfaceSamples final : Value {
  SurfaceGridOptions options;  // what they were taken for
  std::size_t cloud_points = 0;  // the size of the cloud sampled (a check that the same is meant)
  // The grid: node (i, j) at grid coordinates (u, v) = (-extent + (i + 0.37) spacing,
  // -extent + (j + 0.71) spacing), rotated by 0.3 rad about (cx, cy) (verify.py's rotation).
  double spacing = 0, cx = 0, cy = 0, extent = 0;
  int nodes = 0;  // nu: the grid is nu by nu
  std::vector<std::uint8_t> inside;  // nu × nu, row j at j nu: 0 off the patch, 1 on, 2 in the rim band
  std::vector<SurfacePoint> points;  // row by row (steep cells split into up to 4 × 4)
  std::vector<std::size_t> row_start;  // nu + 1: row j's points are [row_start[j], row_start[j + 1])
  double rim_band = 0;         // mm: the rim band's width as resolved (0: none)
  double uncertainty_max = 0;  // the largest at a sample

  std::string type_name() const override { return "SurfaceSamples"; }
  void serialize(std::ostream& out) const override;
  // Throws std::runtime_error for a truncated stream or columns of different lengths.
  static ValuePtr deserialize(std::istream& in);
};

}  // namespace scallop
