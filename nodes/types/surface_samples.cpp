#include "nodes/types/surface_samples.h"

#include <stdexcept>

namespace scallop {

void SurfaceSamples::serialize(std::ostream& out) const {
  bin::write_f64(out, options.tool_radius);
  bin::write_f64(out, options.scallop);
  bin::write_f64(out, options.spacing);
  bin::write_u64(out, options.max_samples);
  bin::write_f64(out, options.rim_band);
  bin::write_u64(out, options.loops.size());
  for (const auto& loop : options.loops) bin::write_vector(out, loop);
  bin::write_u64(out, cloud_points);
  for (double v : {spacing, cx, cy, extent, rim_band, uncertainty_max}) bin::write_f64(out, v);
  bin::write_u64(out, std::uint64_t(nodes));
  bin::write_vector(out, inside);
  // column by column, so the bytes are the same for the same samples (a struct's padding would not be)
  std::vector<Eigen::Vector3d> p(points.size()), n(points.size());
  std::vector<double> weight(points.size()), uncertainty(points.size());
  std::vector<std::uint8_t> beyond(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    p[i] = points[i].p, n[i] = points[i].n, weight[i] = points[i].weight;
    uncertainty[i] = points[i].uncertainty, beyond[i] = points[i].beyond;
  }
  bin::write_vector(out, p);
  bin::write_vector(out, n);
  bin::write_vector(out, weight);
  bin::write_vector(out, uncertainty);
  bin::write_vector(out, beyond);
  bin::write_vector(out, std::vector<std::uint64_t>(row_start.begin(), row_start.end()));
}

ValuePtr SurfaceSamples::deserialize(std::istream& in) {
  auto s = std::make_shared<SurfaceSamples>();
  s->options.tool_radius = bin::read_f64(in);
  s->options.scallop = bin::read_f64(in);
  s->options.spacing = bin::read_f64(in);
  s->options.max_samples = bin::read_u64(in);
  s->options.rim_band = bin::read_f64(in);
  const std::uint64_t loops = bin::read_u64(in);
  if (loops > (std::uint64_t(1) << 24)) throw std::runtime_error("corrupt surface samples: " + std::to_string(loops) + " loops");
  for (std::uint64_t k = 0; k < loops; ++k) s->options.loops.push_back(bin::read_vector<Eigen::Vector2d>(in));
  s->cloud_points = bin::read_u64(in);
  for (double* v : {&s->spacing, &s->cx, &s->cy, &s->extent, &s->rim_band, &s->uncertainty_max}) *v = bin::read_f64(in);
  const std::uint64_t nodes = bin::read_u64(in);
  s->inside = bin::read_vector<std::uint8_t>(in);
  if (nodes > (std::uint64_t(1) << 20) || s->inside.size() != nodes * nodes)
    throw std::runtime_error("corrupt surface samples: the grid's mask does not match its size");
  s->nodes = int(nodes);
  const auto p = bin::read_vector<Eigen::Vector3d>(in), n = bin::read_vector<Eigen::Vector3d>(in);
  const auto weight = bin::read_vector<double>(in), uncertainty = bin::read_vector<double>(in);
  const auto beyond = bin::read_vector<std::uint8_t>(in);
  const auto row_start = bin::read_vector<std::uint64_t>(in);
  const std::size_t m = p.size();
  if (n.size() != m || weight.size() != m || uncertainty.size() != m || beyond.size() != m ||
      row_start.size() != nodes + 1 || row_start.front() != 0 || row_start.back() != m)
    throw std::runtime_error("corrupt surface samples: columns of different lengths");
  s->points.resize(m);
  for (std::size_t i = 0; i < m; ++i) s->points[i] = {p[i], n[i], weight[i], uncertainty[i], beyond[i] != 0};
  s->row_start.assign(row_start.begin(), row_start.end());
  for (std::size_t j = 0; j < nodes; ++j)
    if (s->row_start[j] > s->row_start[j + 1]) throw std::runtime_error("corrupt surface samples: rows out of order");
  return s;
}

}  // namespace scallop
