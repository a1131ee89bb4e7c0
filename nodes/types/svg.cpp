#include "nodes/types/svg.h"

#include <fstream>
#include <stdexcept>

namespace scallop {

void Svg::serialize(std::ostream& out) const { bin::write_string(out, text); }

ValuePtr Svg::deserialize(std::istream& in) {
  auto s = std::make_shared<Svg>();
  s->text = bin::read_string(in);
  return s;
}

void Svg::write_file(const std::string& path) const {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  out << text;
  if (!out) throw std::runtime_error("error writing '" + path + "'");
}

}  // namespace scallop
