// Document values: G-code text, JSON reports and pictures.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "engine/value.h"

namespace scallop {

// A machine program in some dialect; written as .ngc.
struct GCode final : Value {
  std::string dialect;
  std::string text;
  std::string type_name() const override { return "GCode"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  void write_file(const std::string& path) const override;
};

// A JSON report (diagnostics, certificates); written as .json.
struct Report final : Value {
  nlohmann::json data;
  std::string type_name() const override { return "Report"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  void write_file(const std::string& path) const override;
};

// An encoded picture (PNG bytes); written as .png.
struct Image final : Value {
  std::string png;
  std::string type_name() const override { return "Image"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  void write_file(const std::string& path) const override;
};

// A point in a report: [x, y, z].
inline nlohmann::json json_xyz(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace scallop
