// The certificate's surface between the points (issue 10): HeightFieldModel, the model that
// path.isoparametric, path.gouge_guard and post.simulate share, evaluated where a script that
// knows the exact surface asks, so it can measure |error| / uncertainty between the cloud's
// points and not only at them (bench/extra_surfaces.py model-error drives it).
//
//   height_field_error CLOUD.txt < queries > answers
//
// CLOUD.txt: "x y z uncertainty" per point (mm; the product's PLY reader keeps no uncertainty);
// queries: "x y" per line (mm); answers: "z uncertainty" per line, z "nan" where the model has
// no surface (beyond the cloud).
#include <cstdio>
#include <fstream>
#include <iostream>
#include <vector>

#include "nodes/geom/height_field_model.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: height_field_error CLOUD.txt < queries > answers\n");
    return 2;
  }
  std::vector<Eigen::Vector3d> points;
  std::vector<double> uncertainty;
  std::ifstream in(argv[1]);
  double x, y, z, u;
  while (in >> x >> y >> z >> u) points.emplace_back(x, y, z), uncertainty.push_back(u);
  const scallop::HeightFieldModel model(points, 20, &uncertainty);
  while (std::cin >> x >> y) {
    u = 0;
    Eigen::Vector3d n;
    if (model.eval(x, y, z, n, /*force=*/false, &u))
      std::printf("%.9g %.9g\n", z, u);
    else
      std::printf("nan %.9g\n", u);
  }
  return 0;
}
