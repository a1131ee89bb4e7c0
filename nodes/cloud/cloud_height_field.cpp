#include "nodes/cloud/cloud_height_field.h"

namespace scallop {

std::shared_ptr<const HeightFieldModel> cloud_height_field(const PointCloud& cloud) {
  return cloud.derived<HeightFieldModel>("height_field/20", [&cloud] {
    return std::make_shared<const HeightFieldModel>(cloud.points, 20,
                                                    cloud.has_uncertainty() ? &cloud.uncertainty : nullptr);
  });
}

}  // namespace scallop
