#include "nodes/geom/surface_band.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace scallop {

SurfaceBand surface_band(const HeightFieldModel& surface, const std::vector<Eigen::Vector3d>& points) {
  SurfaceBand band;
  band.at.resize(points.size());
  band.uncertainty.assign(points.size(), 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size()), [&](const tbb::blocked_range<std::size_t>& rg) {
    for (std::size_t i = rg.begin(); i < rg.end(); ++i) {
      // outside the patch's fit (at its rim) eval leaves z alone: the point itself, with the
      // uncertainty of the fit extrapolated there
      double z = points[i].z(), u = 0;
      Eigen::Vector3d n;
      surface.eval(points[i].x(), points[i].y(), z, n, /*force=*/true, &u);
      band.at[i] = Eigen::Vector3d(points[i].x(), points[i].y(), z);
      band.uncertainty[i] = std::isfinite(u) ? std::max(u, 0.0) : 0.0;
    }
  });
  return band;
}

}  // namespace scallop
