#include "nodes/types/param.h"

#include <stdexcept>
#include <string>

namespace scallop {

void BoundaryLoops::serialize(std::ostream& out) const {
  bin::write_u64(out, loops.size());
  for (const auto& l : loops) bin::write_vector(out, l);
  bin::write_vector(out, is_boundary);
}

ValuePtr BoundaryLoops::deserialize(std::istream& in) {
  auto b = std::make_shared<BoundaryLoops>();
  std::uint64_t n = bin::read_u64(in);
  if (n > (1u << 30)) throw std::runtime_error("corrupt loop count");
  b->loops.resize(n);
  for (auto& l : b->loops) l = bin::read_vector<int>(in);
  b->is_boundary = bin::read_vector<std::uint8_t>(in);
  return b;
}

void Laplacian::serialize(std::ostream& out) const {
  bin::write_string(out, scheme);
  bin::write_f64(out, heat_time);
  bin::write_f64(out, regularization);
  bin::write_u64(out, static_cast<std::uint64_t>(L.rows()));
  bin::write_u64(out, static_cast<std::uint64_t>(L.cols()));
  std::vector<int> rows, cols;
  std::vector<double> vals;
  for (int r = 0; r < L.outerSize(); ++r)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(L, r); it; ++it) {
      rows.push_back(static_cast<int>(it.row()));
      cols.push_back(static_cast<int>(it.col()));
      vals.push_back(it.value());
    }
  bin::write_vector(out, rows);
  bin::write_vector(out, cols);
  bin::write_vector(out, vals);
}

ValuePtr Laplacian::deserialize(std::istream& in) {
  auto l = std::make_shared<Laplacian>();
  l->scheme = bin::read_string(in);
  l->heat_time = bin::read_f64(in);
  l->regularization = bin::read_f64(in);
  auto nr = static_cast<Eigen::Index>(bin::read_u64(in));
  auto nc = static_cast<Eigen::Index>(bin::read_u64(in));
  auto rows = bin::read_vector<int>(in);
  auto cols = bin::read_vector<int>(in);
  auto vals = bin::read_vector<double>(in);
  if (rows.size() != cols.size() || rows.size() != vals.size()) throw std::runtime_error("corrupt Laplacian");
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(vals.size());
  for (std::size_t i = 0; i < vals.size(); ++i) {
    if (rows[i] < 0 || rows[i] >= nr || cols[i] < 0 || cols[i] >= nc) throw std::runtime_error("corrupt Laplacian");
    t.emplace_back(rows[i], cols[i], vals[i]);
  }
  l->L.resize(nr, nc);
  l->L.setFromTriplets(t.begin(), t.end());
  return l;
}

void UVMap::serialize(std::ostream& out) const {
  bin::write_string(out, domain);
  bin::write_f64(out, radius);
  bin::write_f64(out, width);
  bin::write_f64(out, height);
  bin::write_vector(out, uv);
  bin::write_vector(out, outer_loop);
  bin::write_vector(out, boundary_uv);
  bin::write_vector(out, corners);
  bin::write_f64(out, residual);
}

ValuePtr UVMap::deserialize(std::istream& in) {
  auto m = std::make_shared<UVMap>();
  m->domain = bin::read_string(in);
  m->radius = bin::read_f64(in);
  m->width = bin::read_f64(in);
  m->height = bin::read_f64(in);
  m->uv = bin::read_vector<Eigen::Vector2d>(in);
  m->outer_loop = bin::read_vector<int>(in);
  m->boundary_uv = bin::read_vector<Eigen::Vector2d>(in);
  m->corners = bin::read_vector<int>(in);
  m->residual = bin::read_f64(in);
  return m;
}

std::vector<std::vector<Eigen::Vector2d>> loop_polygons_xy(const BoundaryLoops& loops,
                                                           const std::vector<Eigen::Vector3d>& points) {
  if (loops.loops.empty()) throw std::invalid_argument("the input 'loops' has no loop");
  const int n = static_cast<int>(points.size());
  std::vector<std::vector<Eigen::Vector2d>> polygons;
  for (const auto& L : loops.loops) {
    auto& poly = polygons.emplace_back();
    for (int i : L) {
      if (i < 0 || i >= n)
        throw std::invalid_argument("a loop refers to point " + std::to_string(i) + " but the cloud has " +
                                    std::to_string(n) + " points; give 'loops' computed on the same cloud");
      poly.emplace_back(points[i].x(), points[i].y());
    }
  }
  return polygons;
}

}  // namespace scallop
