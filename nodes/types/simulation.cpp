#include "nodes/types/simulation.h"

#include <cstdint>
#include <stdexcept>

namespace scallop {
namespace {
// The number columns of the binary form, in their order.
constexpr double SimSample::*kColumns[] = {&SimSample::x,       &SimSample::y,       &SimSample::z,
                                           &SimSample::weight,  &SimSample::scallop, &SimSample::gouge};
}  // namespace

void Simulation::serialize(std::ostream& out) const {
  bin::write_string(out, report.dump());
  bin::write_f64(out, spacing);
  bin::write_f64(out, scallop_limit);
  bin::write_f64(out, gouge_tolerance);
  bin::write_vector(out, outline);
  auto column = [&](double SimSample::*field) {
    std::vector<double> c(samples.size());
    for (std::size_t i = 0; i < samples.size(); ++i) c[i] = samples[i].*field;
    bin::write_vector(out, c);
  };
  for (double SimSample::*field : kColumns) column(field);
  std::vector<std::uint8_t> interior(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) interior[i] = samples[i].interior;
  bin::write_vector(out, interior);
  bin::write_vector(out, face);
}

ValuePtr Simulation::deserialize(std::istream& in) {
  auto s = std::make_shared<Simulation>();
  s->report = nlohmann::json::parse(bin::read_string(in));
  s->spacing = bin::read_f64(in);
  s->scallop_limit = bin::read_f64(in);
  s->gouge_tolerance = bin::read_f64(in);
  s->outline = bin::read_vector<Eigen::Vector2d>(in);
  bool first = true;
  for (double SimSample::*field : kColumns) {
    const std::vector<double> c = bin::read_vector<double>(in);
    if (first) s->samples.resize(c.size());
    first = false;
    if (c.size() != s->samples.size()) throw std::runtime_error("corrupt simulation: columns of different lengths");
    for (std::size_t i = 0; i < c.size(); ++i) s->samples[i].*field = c[i];
  }
  const std::vector<std::uint8_t> interior = bin::read_vector<std::uint8_t>(in);
  if (interior.size() != s->samples.size()) throw std::runtime_error("corrupt simulation: columns of different lengths");
  for (std::size_t i = 0; i < interior.size(); ++i) s->samples[i].interior = interior[i] != 0;
  s->face = bin::read_vector<std::uint32_t>(in);
  if (!s->face.empty() && s->face.size() != s->samples.size())
    throw std::runtime_error("corrupt simulation: columns of different lengths");
  return s;
}

}  // namespace scallop
