// Point cloud and neighbourhood values.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "engine/value.h"

namespace scallop {

// P  #P by 3 positions (mm); N  #P by 3 unit normals, or empty when the cloud has none;
// U  #P bounds (mm) on how far each point may lie from the real surface along its normal, or
// empty when unknown (set by cloud.denoise from the standard error of its fits).
struct PointCloud final : Value {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;  // empty, or one per point
  std::vector<double> uncertainty;       // empty, or one per point (mm)

  std::size_t size() const { return points.size(); }
  bool has_normals() const { return !normals.empty() && normals.size() == points.size(); }
  bool has_uncertainty() const {
    return !uncertainty.empty() && uncertainty.size() == points.size();
  }

  std::string type_name() const override { return "Cloud"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  // Writes binary little-endian PLY (x y z [nx ny nz] [uncertainty] as double).
  void write_file(const std::string& path) const override;
};

// The k nearest neighbours of every point, the point itself excluded, nearest first.
// index(i, j) is the j-th neighbour of point i; sq_dist(i, j) its squared distance.
struct Neighborhoods final : Value {
  int k = 0;
  std::vector<int> indices;       // #P*k
  std::vector<double> sq_dists;   // #P*k

  std::size_t size() const { return k == 0 ? 0 : indices.size() / static_cast<std::size_t>(k); }
  int index(std::size_t i, int j) const { return indices[i * k + j]; }
  double sq_dist(std::size_t i, int j) const { return sq_dists[i * k + j]; }

  std::string type_name() const override { return "Neighbors"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
};

}  // namespace scallop
