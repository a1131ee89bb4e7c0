#include "nodes/io/text_cloud_reader.h"

#include <algorithm>
#include <string_view>
#include <vector>

#include "nodes/io/read_support.h"

namespace scallop {
namespace {

// A line with ',' or ';' is split there, each field trimmed, so an empty field stays visible
// (and is an error) instead of shifting the columns after it; other lines split on blanks.
void split_fields(std::string_view line, std::vector<std::string_view>& out) {
  if (line.find_first_of(",;") == std::string_view::npos) return io::split_tokens(line, out);
  out.clear();
  if (line.find_first_not_of(" \t\r") == std::string_view::npos) return;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = std::min(line.find_first_of(",;", start), line.size());
    std::string_view f = line.substr(start, end - start);
    const std::size_t a = f.find_first_not_of(" \t\r");
    f = a == std::string_view::npos ? std::string_view() : f.substr(a, f.find_last_not_of(" \t\r") - a + 1);
    out.push_back(f);
    if (end == line.size()) break;
    start = end + 1;
  }
}

// True when `line` writes its numbers with decimal commas: "1,5 2,0 3,0" (blank-separated) or
// "1,5;2,0;3,0" (semicolon-separated), every field a number once its ',' is read as '.'.
bool has_decimal_commas(std::string_view line) {
  if (line.find(',') == std::string_view::npos) return false;
  std::vector<std::string_view> fields;
  if (line.find(';') != std::string_view::npos) {
    // the semicolon-separated form: split on ';' alone
    std::size_t start = 0;
    while (start <= line.size()) {
      const std::size_t end = std::min(line.find(';', start), line.size());
      std::vector<std::string_view> t;
      io::split_tokens(line.substr(start, end - start), t);
      if (t.size() != 1) return false;
      fields.push_back(t[0]);
      start = end + 1;
    }
  } else {
    io::split_tokens(line, fields);
  }
  bool comma = false;
  for (std::string_view f : fields) {
    double v;
    const bool dc = io::decimal_comma(f);
    if (!dc && !io::parse_double(f, v)) return false;
    comma = comma || dc;
  }
  return comma && fields.size() >= 3;
}

}  // namespace

PointCloud read_text_cloud(const std::string& path, bool columns_4_to_6_are_normals) {
  const std::string data = io::read_file_bytes(path);
  // A UTF-8 byte order mark (Windows editors write one) is no part of the first line.
  io::LineReader lines(data, io::bom_size(data));
  std::string_view line;
  std::vector<std::string_view> tok;
  std::vector<double> values;
  PointCloud cloud;
  std::size_t columns = 0;  // of the first data line; 0 until it is seen
  bool first_content = true;
  while (lines.next(line)) {
    const std::size_t ln = lines.line();
    if (auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    if (has_decimal_commas(line)) io::fail_line(path, ln, "decimal commas are not supported; use '.'");
    split_fields(line, tok);
    if (tok.empty()) continue;
    values.resize(tok.size());
    std::size_t bad = tok.size();  // index of the first token that is not a number
    for (std::size_t i = 0; i < tok.size() && bad == tok.size(); ++i)
      if (!io::parse_double(tok[i], values[i])) bad = i;
    const bool header = first_content && (bad < tok.size() || tok.size() == 1);
    first_content = false;
    if (header) continue;
    if (bad < tok.size() && tok[bad].empty())
      io::fail_line(path, ln, "empty value in column " + std::to_string(bad + 1));
    if (bad < tok.size())
      io::fail_line(path, ln, "bad number " + io::quote(tok[bad]) + " in column " + std::to_string(bad + 1));
    if (columns == 0) {
      if (tok.size() < 3)
        io::fail_line(path, ln, "expected at least 3 values (x y z), found " + std::to_string(tok.size()));
      columns = tok.size();
    } else if (tok.size() != columns) {
      io::fail_line(path, ln, "expected " + std::to_string(columns) + " values like the first point, found " +
                                  std::to_string(tok.size()));
    }
    cloud.points.emplace_back(values[0], values[1], values[2]);
    if (columns >= 6 && columns_4_to_6_are_normals) cloud.normals.emplace_back(values[3], values[4], values[5]);
  }
  return cloud;
}

}  // namespace scallop
