#include "nodes/types/document.h"

#include <fstream>
#include <stdexcept>

namespace scallop {
namespace {
void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  out << text;
  if (!out) throw std::runtime_error("error writing '" + path + "'");
}
}  // namespace

void GCode::serialize(std::ostream& out) const {
  bin::write_string(out, dialect);
  bin::write_string(out, text);
}
ValuePtr GCode::deserialize(std::istream& in) {
  auto g = std::make_shared<GCode>();
  g->dialect = bin::read_string(in);
  g->text = bin::read_string(in);
  return g;
}
void GCode::write_file(const std::string& path) const { write_text(path, text); }

void Report::serialize(std::ostream& out) const { bin::write_string(out, data.dump()); }
ValuePtr Report::deserialize(std::istream& in) {
  auto r = std::make_shared<Report>();
  r->data = nlohmann::json::parse(bin::read_string(in));
  return r;
}
void Report::write_file(const std::string& path) const { write_text(path, data.dump(2) + "\n"); }

void Image::serialize(std::ostream& out) const { bin::write_string(out, png); }
ValuePtr Image::deserialize(std::istream& in) {
  auto i = std::make_shared<Image>();
  i->png = bin::read_string(in);
  return i;
}
void Image::write_file(const std::string& path) const { write_text(path, png); }

}  // namespace scallop
