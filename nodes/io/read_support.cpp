#include "nodes/io/read_support.h"

#include <cctype>
#include <cmath>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

namespace scallop::io {

std::string read_file_bytes(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail(path, "file does not exist");
  if (std::filesystem::is_directory(path, ec)) fail(path, "is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open file");
  std::string bytes;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) fail(path, "cannot read file");
  in.seekg(0, std::ios::beg);
  bytes.resize(static_cast<std::size_t>(size));
  if (size > 0 && !in.read(bytes.data(), size)) fail(path, "cannot read file");
  if (bytes.empty()) fail(path, "file is empty");
  return bytes;
}

void fail(const std::string& path, const std::string& what) { throw CloudReadError(path + ": " + what); }

void fail_line(const std::string& path, std::size_t line, const std::string& what) {
  throw CloudReadError(path + ": line " + std::to_string(line) + ": " + what);
}

void fail_byte(const std::string& path, std::size_t offset, const std::string& what) {
  throw CloudReadError(path + ": byte " + std::to_string(offset) + ": " + what);
}

bool LineReader::next(std::string_view& line) {
  if (pos_ >= data_.size()) return false;
  std::size_t end = data_.find('\n', pos_);
  std::size_t next = end == std::string_view::npos ? data_.size() : end + 1;
  if (end == std::string_view::npos) end = data_.size();
  line = data_.substr(pos_, end - pos_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos_ = next;
  ++next_line_;
  return true;
}

void split_tokens(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  auto is_sep = [](char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f' || c == '\r'; };
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_sep(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !is_sep(line[j])) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
}

bool parse_double(std::string_view s, double& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() == '+') return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  // Out-of-range values (1e999) are errors too: they are no number the file could mean.
  return ec == std::errc() && p == s.data() + s.size();
}

bool parse_int(std::string_view s, long long& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() == '+') return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size();
}

bool parse_uint(std::string_view s, std::uint64_t& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() == '+' || s.front() == '-') return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size();
}

std::size_t bom_size(std::string_view data) { return data.starts_with("\xEF\xBB\xBF") ? 3 : 0; }

bool decimal_comma(std::string_view token) {
  if (token.find(',') == std::string_view::npos) return false;
  std::string dotted(token);
  for (char& c : dotted)
    if (c == ',') c = '.';
  double v;
  // "1," is a number followed by a separator, not a decimal comma
  return dotted.back() != '.' && parse_double(dotted, v);
}

std::string bad_number(std::string_view token, const std::string& otherwise) {
  return decimal_comma(token) ? "decimal commas are not supported; use '.'" : otherwise;
}

std::string quote(std::string_view token) {
  std::string q = "'";
  const std::size_t n = std::min<std::size_t>(token.size(), 32);
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    q += std::isprint(c) ? static_cast<char>(c) : '?';
  }
  if (token.size() > n) q += "...";
  return q + "'";
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void check_scale(const std::string& path, double scale) {
  if (std::isfinite(scale) && scale > 0) return;
  std::ostringstream s;
  s << "scale must be positive and finite, got " << scale;
  fail(path, s.str());
}

PointCloud vertices_as_cloud(Mesh&& mesh) {
  PointCloud cloud;
  cloud.points = std::move(mesh.vertices);
  cloud.normals = std::move(mesh.normals);
  return cloud;
}

bool finite_point(const double* xyz) {
  return std::isfinite(xyz[0]) && std::isfinite(xyz[1]) && std::isfinite(xyz[2]);
}

std::string non_finite_point(const std::string& item, const double* xyz) {
  const bool nan = std::isnan(xyz[0]) || std::isnan(xyz[1]) || std::isnan(xyz[2]);
  return item + (nan ? " has a NaN coordinate" : " has an infinite coordinate");
}

std::string index_past_vertices(const std::string& item, std::string_view token, std::uint64_t vertices) {
  return item + " has index " + quote(token) + " but there are " + std::to_string(vertices) + " vertices";
}

std::string too_few_corners(std::uint64_t face, std::uint64_t corners) {
  return "face " + std::to_string(face) + " has " + std::to_string(corners) + " corners; a face needs at least 3";
}

}  // namespace scallop::io
