#include "nodes/types/surfaces.h"

#include <stdexcept>

#include "nodes/types/document.h"

namespace scallop {

namespace {
std::vector<double> vec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Vector3d read_vec3(std::istream& in, const char* what) {
  auto v = bin::read_vector<Eigen::Vector3d>(in);
  if (v.size() != 1) throw std::runtime_error(std::string("corrupt surfaces: ") + what);
  return v[0];
}
}  // namespace

void Surfaces::serialize(std::ostream& out) const {
  bin::write_u64(out, patches.size());
  for (const auto& p : patches) {
    const BSplineSurface& s = p.surface;
    bin::write_u64(out, static_cast<std::uint64_t>(s.degree_u));
    bin::write_u64(out, static_cast<std::uint64_t>(s.degree_v));
    bin::write_vector(out, s.knots_u);
    bin::write_vector(out, s.knots_v);
    bin::write_u64(out, s.poles_u);
    bin::write_u64(out, s.poles_v);
    bin::write_vector(out, s.poles);
    bin::write_vector(out, std::vector<Eigen::Vector3d>{p.direction});
    bin::write_f64(out, p.min_normal_dot);
    bin::write_u64(out, p.segment);
    bin::write_u64(out, p.rows);
    bin::write_u64(out, p.cols);
    bin::write_f64(out, p.fit_max_error);
    bin::write_f64(out, p.fit_mean_error);
    bin::write_f64(out, p.smoothing);
    bin::write_f64(out, p.mesh_distance_max);
  }
  bin::write_f64(out, tolerance);
  bin::write_vector(out, std::vector<Eigen::Vector3d>{base_direction});
}

ValuePtr Surfaces::deserialize(std::istream& in) {
  auto s = std::make_shared<Surfaces>();
  const std::uint64_t n = bin::read_u64(in);
  if (n > (1u << 24)) throw std::runtime_error("corrupt surfaces: patch count");
  s->patches.resize(n);
  for (auto& p : s->patches) {
    BSplineSurface& b = p.surface;
    b.degree_u = static_cast<int>(bin::read_u64(in) & 0xff);
    b.degree_v = static_cast<int>(bin::read_u64(in) & 0xff);
    b.knots_u = bin::read_vector<double>(in);
    b.knots_v = bin::read_vector<double>(in);
    b.poles_u = static_cast<std::uint32_t>(bin::read_u64(in));
    b.poles_v = static_cast<std::uint32_t>(bin::read_u64(in));
    b.poles = bin::read_vector<Eigen::Vector3d>(in);
    if (const std::string problem = bspline_problem(b); !problem.empty())
      throw std::runtime_error("corrupt surfaces: " + problem);
    p.direction = read_vec3(in, "direction");
    p.min_normal_dot = bin::read_f64(in);
    p.segment = static_cast<std::uint32_t>(bin::read_u64(in));
    p.rows = static_cast<std::uint32_t>(bin::read_u64(in));
    p.cols = static_cast<std::uint32_t>(bin::read_u64(in));
    p.fit_max_error = bin::read_f64(in);
    p.fit_mean_error = bin::read_f64(in);
    p.smoothing = bin::read_f64(in);
    p.mesh_distance_max = bin::read_f64(in);
  }
  s->tolerance = bin::read_f64(in);
  s->base_direction = read_vec3(in, "base direction");
  return s;
}

void Surfaces::write_file(const std::string& path) const {
  Report r;
  r.data["tolerance"] = tolerance;
  r.data["base_direction"] = vec3(base_direction);
  auto& list = r.data["patches"] = nlohmann::json::array();
  for (const auto& p : patches) {
    const BSplineSurface& s = p.surface;
    nlohmann::json poles = nlohmann::json::array();
    for (const auto& q : s.poles) poles.push_back(vec3(q));
    list.push_back({{"segment", p.segment},
                    {"direction", vec3(p.direction)},
                    {"min_normal_dot", p.min_normal_dot},
                    {"grid", {p.rows, p.cols}},
                    {"fit_max_error", p.fit_max_error},
                    {"fit_mean_error", p.fit_mean_error},
                    {"smoothing", p.smoothing},
                    {"mesh_distance_max", p.mesh_distance_max},
                    {"degree", {s.degree_u, s.degree_v}},
                    {"knots_u", s.knots_u},
                    {"knots_v", s.knots_v},
                    {"poles_count", {s.poles_u, s.poles_v}},
                    {"poles", std::move(poles)}});
  }
  r.write_file(path);
}

}  // namespace scallop
