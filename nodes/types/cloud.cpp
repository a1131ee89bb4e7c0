#include "nodes/types/cloud.h"

#include "nodes/types/ply_writer.h"

namespace scallop {

void PointCloud::serialize(std::ostream& out) const {
  bin::write_vector(out, points);
  bin::write_vector(out, normals);
  bin::write_vector(out, uncertainty);
}

ValuePtr PointCloud::deserialize(std::istream& in) {
  auto c = std::make_shared<PointCloud>();
  c->points = bin::read_vector<Eigen::Vector3d>(in);
  c->normals = bin::read_vector<Eigen::Vector3d>(in);
  c->uncertainty = bin::read_vector<double>(in);
  return c;
}

void PointCloud::write_file(const std::string& path) const { write_ply(path, *this); }

void Neighborhoods::serialize(std::ostream& out) const {
  bin::write_u64(out, static_cast<std::uint64_t>(k));
  bin::write_vector(out, indices);
  bin::write_vector(out, sq_dists);
}

ValuePtr Neighborhoods::deserialize(std::istream& in) {
  auto n = std::make_shared<Neighborhoods>();
  n->k = static_cast<int>(bin::read_u64(in));
  n->indices = bin::read_vector<int>(in);
  n->sq_dists = bin::read_vector<double>(in);
  return n;
}

}  // namespace scallop
