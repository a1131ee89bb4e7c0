#include "nodes/io/mesh_vertices_reader.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "nodes/io/read_support.h"

namespace scallop {
namespace {

using io::fail;
using io::fail_byte;
using io::fail_line;
using io::quote;

// STL is little-endian whatever the machine.
std::uint32_t load_u32_le(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
}

// Next line with tokens (comments after '#' removed); false at the end of the file.
bool next_tokens(io::LineReader& lines, std::vector<std::string_view>& tok) {
  std::string_view line;
  while (lines.next(line)) {
    if (auto h = line.find('#'); h != std::string_view::npos) line = line.substr(0, h);
    io::split_tokens(line, tok);
    if (!tok.empty()) return true;
  }
  return false;
}

// Welds corners with bit-identical coordinates (after turning -0 into +0, since -0 == 0).
class Welder {
 public:
  explicit Welder(std::size_t corners) { index_.reserve(corners); }
  void add(double x, double y, double z, PointCloud& cloud) {
    const std::array<std::uint64_t, 3> key = {bits(x), bits(y), bits(z)};
    if (index_.try_emplace(key, cloud.points.size()).second) cloud.points.emplace_back(x, y, z);
  }

 private:
  static std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v == 0.0 ? 0.0 : v); }
  struct Hash {
    std::size_t operator()(const std::array<std::uint64_t, 3>& k) const {
      std::uint64_t h = 0x9E3779B97F4A7C15ull;
      for (std::uint64_t v : k) h = (h ^ v) * 0x100000001B3ull + (h >> 29);
      return static_cast<std::size_t>(h);
    }
  };
  std::unordered_map<std::array<std::uint64_t, 3>, std::size_t, Hash> index_;
};

PointCloud read_stl_binary(const std::string& path, const std::string& data) {
  if (data.size() < 84) fail_byte(path, 0, "file too short for a binary STL header (84 bytes)");
  const std::uint32_t n = load_u32_le(data.data() + 80);
  const std::size_t left = data.size() - 84;
  if (n > left / 50) {
    const std::size_t k = left / 50;
    fail_byte(path, 84 + 50 * k, "file ends inside triangle " + std::to_string(k) + " of " + std::to_string(n));
  }
  // More bytes than the triangles take: the count is smaller than the data (or this is no binary
  // STL at all), and reading only what it declares would drop triangles silently.
  if (const std::size_t end = 84 + 50 * static_cast<std::size_t>(n); end < data.size())
    fail_byte(path, end, std::to_string(data.size() - end) + " bytes after the last declared triangle (" +
                             std::to_string(n) + " declared): the header's count is smaller than the data");
  PointCloud cloud;
  Welder weld(3 * static_cast<std::size_t>(n));
  for (std::size_t t = 0; t < n; ++t) {
    const char* p = data.data() + 84 + 50 * t + 12;  // skip the facet normal
    for (int c = 0; c < 3; ++c) {
      float v[3];
      for (int k = 0; k < 3; ++k) v[k] = std::bit_cast<float>(load_u32_le(p + 12 * c + 4 * k));
      weld.add(v[0], v[1], v[2], cloud);
    }
  }
  return cloud;
}

PointCloud read_stl_ascii(const std::string& path, const std::string& data) {
  io::LineReader lines(data, io::bom_size(data));
  std::vector<std::string_view> tok;
  std::string_view line;
  PointCloud cloud;
  Welder weld(data.size() / 40);  // a "vertex x y z" line is rarely shorter
  int in_loop = -1;               // corners seen in the current 'outer loop', -1 outside one
  std::size_t facet = 0;
  bool seen_solid = false;
  while (lines.next(line)) {
    const std::size_t ln = lines.line();
    io::split_tokens(line, tok);
    if (tok.empty()) continue;
    const std::string_view key = tok[0];
    if (key == "solid") {
      seen_solid = true;
    } else if (!seen_solid) {
      fail_line(path, ln, "expected 'solid', found " + quote(key));
    } else if (key == "vertex") {
      if (in_loop < 0) fail_line(path, ln, "'vertex' outside 'outer loop'");
      double v[3];
      if (tok.size() != 4) fail_line(path, ln, "expected 'vertex x y z'");
      for (int k = 0; k < 3; ++k)
        if (!io::parse_double(tok[k + 1], v[k]))
          fail_line(path, ln, io::bad_number(tok[k + 1], "bad number " + quote(tok[k + 1])));
      weld.add(v[0], v[1], v[2], cloud);
      ++in_loop;
    } else if (key == "outer") {
      in_loop = 0;
    } else if (key == "endloop") {
      if (in_loop != 3)
        fail_line(path, ln, "facet " + std::to_string(facet) + " has " + std::to_string(std::max(in_loop, 0)) +
                                " vertices, expected 3");
      in_loop = -1;
      ++facet;
    } else if (key != "facet" && key != "endfacet" && key != "endsolid") {
      fail_line(path, ln, "unexpected " + quote(key));
    }
  }
  if (in_loop >= 0) fail_line(path, lines.line() + 1, "file ends inside facet " + std::to_string(facet));
  return cloud;
}

}  // namespace

PointCloud read_off_vertices(const std::string& path) {
  const std::string data = io::read_file_bytes(path);
  io::LineReader lines(data, io::bom_size(data));
  std::vector<std::string_view> tok;
  if (!next_tokens(lines, tok)) fail(path, "no OFF header");
  const std::string_view head = tok[0];
  const bool normals = head == "NOFF" || head == "CNOFF";
  if (head != "OFF" && head != "COFF" && !normals) {
    if (head.size() >= 3 && head.substr(head.size() - 3) == "OFF")
      fail_line(path, lines.line(), "unsupported OFF variant " + quote(head) + " (expected OFF, COFF, NOFF or CNOFF)");
    fail_line(path, lines.line(), "not an OFF file (the first word must be 'OFF')");
  }
  if (tok.size() >= 2 && tok[1] == "BINARY") fail_line(path, lines.line(), "binary OFF is not supported");
  if (tok.size() > 1) {
    tok.erase(tok.begin());  // "OFF nv nf ne" on one line
  } else if (!next_tokens(lines, tok)) {
    fail_line(path, lines.line() + 1, "file ends before the counts line");
  }
  std::uint64_t nv = 0, nf = 0;
  if (tok.size() < 2 || tok.size() > 3 || !io::parse_uint(tok[0], nv) || !io::parse_uint(tok[1], nf))
    fail_line(path, lines.line(), "expected the counts 'vertices faces [edges]'");

  PointCloud cloud;
  const std::size_t fit = (data.size() - lines.offset()) / 6;  // "0 0 0\n" is the shortest vertex
  cloud.points.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(nv, fit)));
  if (normals) cloud.normals.reserve(cloud.points.capacity());
  const std::size_t need = normals ? 6 : 3;
  const std::string ofv = " of " + std::to_string(nv);
  for (std::uint64_t i = 0; i < nv; ++i) {
    if (!next_tokens(lines, tok)) fail_line(path, lines.line() + 1, "file ends before vertex " + std::to_string(i) + ofv);
    const std::size_t ln = lines.line();
    if (tok.size() < need)
      fail_line(path, ln, "expected " + std::to_string(need) + " values for vertex " + std::to_string(i) +
                              ", found " + std::to_string(tok.size()));
    double v[6];
    for (std::size_t k = 0; k < need; ++k)
      if (!io::parse_double(tok[k], v[k]))
        fail_line(path, ln, io::bad_number(tok[k], "bad number " + quote(tok[k]) + " for vertex " + std::to_string(i)));
    cloud.points.emplace_back(v[0], v[1], v[2]);
    if (normals) cloud.normals.emplace_back(v[3], v[4], v[5]);
  }
  const std::string off = " of " + std::to_string(nf);
  for (std::uint64_t f = 0; f < nf; ++f) {
    const std::string face = "face " + std::to_string(f);
    if (!next_tokens(lines, tok)) fail_line(path, lines.line() + 1, "file ends before " + face + off);
    const std::size_t ln = lines.line();
    std::uint64_t k = 0;
    if (!io::parse_uint(tok[0], k)) fail_line(path, ln, "bad corner count " + quote(tok[0]) + " for " + face);
    if (k > tok.size() - 1)
      fail_line(path, ln, face + " has " + std::to_string(k) + " corners but only " +
                              std::to_string(tok.size() - 1) + " indices");
    for (std::size_t c = 1; c <= k; ++c) {
      std::uint64_t idx = 0;
      if (!io::parse_uint(tok[c], idx) || idx >= nv)
        fail_line(path, ln, face + " has index " + quote(tok[c]) + " but there are " + std::to_string(nv) +
                                " vertices");
    }
  }
  // Anything after the last face means the counts are smaller than the data: its vertices would
  // be dropped silently.
  if (next_tokens(lines, tok)) {
    const std::size_t first = lines.line();
    std::size_t extra = 1;
    while (next_tokens(lines, tok)) ++extra;
    fail_line(path, first, std::to_string(extra) + (extra == 1 ? " line" : " lines") +
                               " after the last declared face (" + std::to_string(nv) + " vertices, " +
                               std::to_string(nf) + " faces declared): the header's counts are smaller than the data");
  }
  return cloud;
}

PointCloud read_obj_vertices(const std::string& path) {
  const std::string data = io::read_file_bytes(path);
  io::LineReader lines(data, io::bom_size(data));
  std::vector<std::string_view> tok;
  PointCloud cloud;
  while (next_tokens(lines, tok)) {
    if (tok[0] != "v") continue;
    const std::size_t ln = lines.line();
    if (tok.size() < 4) fail_line(path, ln, "expected 'v x y z', found " + std::to_string(tok.size() - 1) + " values");
    double v[3];
    for (int k = 0; k < 3; ++k)
      if (!io::parse_double(tok[k + 1], v[k]))
        fail_line(path, ln, io::bad_number(tok[k + 1], "bad number " + quote(tok[k + 1])));
    cloud.points.emplace_back(v[0], v[1], v[2]);
  }
  return cloud;
}

PointCloud read_stl_vertices(const std::string& path) {
  const std::string data = io::read_file_bytes(path);
  if (data.size() >= 84) {
    const std::uint32_t n = load_u32_le(data.data() + 80);
    if (84 + 50 * static_cast<std::uint64_t>(n) == data.size()) return read_stl_binary(path, data);
  }
  // Ascii when it starts with "solid" and looks like text; binary headers may say "solid" too, but
  // their triangle count and float data nearly always hold a zero byte early on.
  std::size_t i = data.find_first_not_of(" \t\r\n", io::bom_size(data));
  const bool solid = i != std::string::npos && data.compare(i, 5, "solid") == 0;
  const bool text = std::memchr(data.data(), 0, std::min<std::size_t>(data.size(), 1024)) == nullptr;
  if (solid && text) return read_stl_ascii(path, data);
  return read_stl_binary(path, data);
}

PointCloud read_mesh_vertices(const std::string& path) {
  const std::string ext = io::lower_extension(path);
  if (ext == ".off") return read_off_vertices(path);
  if (ext == ".obj") return read_obj_vertices(path);
  if (ext == ".stl") return read_stl_vertices(path);
  fail(path, "unsupported mesh extension '" + ext + "' (expected .off, .obj or .stl)");
}

}  // namespace scallop
