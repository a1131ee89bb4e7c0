// SVG picture value: the text of a standalone SVG document; written as .svg.
#pragma once

#include <string>

#include "engine/value.h"

namespace scallop {

struct Svg final : Value {
  std::string text;
  std::string type_name() const override { return "Svg"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  void write_file(const std::string& path) const override;
};

}  // namespace scallop
