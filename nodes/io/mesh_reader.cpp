#include "nodes/io/mesh_reader.h"

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
  // The vertex at (x, y, z), appended to `vertices` when it is new.
  std::uint32_t add(double x, double y, double z, std::vector<Eigen::Vector3d>& vertices) {
    const std::array<std::uint64_t, 3> key = {bits(x), bits(y), bits(z)};
    auto [it, added] = index_.try_emplace(key, static_cast<std::uint32_t>(vertices.size()));
    if (added) vertices.emplace_back(x, y, z);
    return it->second;
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
  std::unordered_map<std::array<std::uint64_t, 3>, std::uint32_t, Hash> index_;
};

// Little-endian float at p, as a double.
double load_f32_le(const char* p) { return std::bit_cast<float>(load_u32_le(p)); }

Mesh read_stl_binary(const std::string& path, const std::string& data, io::MeshRead what) {
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
  const bool faces = what == io::MeshRead::Mesh;
  Mesh mesh;
  Welder weld(3 * static_cast<std::size_t>(n));
  if (faces) {
    mesh.face_vertices.resize(3 * static_cast<std::size_t>(n));
    mesh.face_start.resize(static_cast<std::size_t>(n) + 1);
  }
  for (std::size_t t = 0; t < n; ++t) {
    const std::size_t at = 84 + 50 * t + 12;  // skip the facet normal
    for (std::size_t c = 0; c < 3; ++c) {
      const char* p = data.data() + at + 12 * c;
      const double v[3] = {load_f32_le(p), load_f32_le(p + 4), load_f32_le(p + 8)};
      if (faces && !io::finite_point(v))
        fail_byte(path, at + 12 * c, io::non_finite_point("corner " + std::to_string(c) + " of triangle " + std::to_string(t), v));
      const std::uint32_t i = weld.add(v[0], v[1], v[2], mesh.vertices);
      if (faces) mesh.face_vertices[3 * t + c] = i;
    }
    if (faces) mesh.face_start[t + 1] = static_cast<std::uint32_t>(3 * (t + 1));
  }
  return mesh;
}

Mesh read_stl_ascii(const std::string& path, const std::string& data, io::MeshRead what) {
  io::LineReader lines(data, io::bom_size(data));
  std::vector<std::string_view> tok;
  std::string_view line;
  const bool faces = what == io::MeshRead::Mesh;
  Mesh mesh;
  Welder weld(data.size() / 40);  // a "vertex x y z" line is rarely shorter
  int in_loop = -1;               // corners seen in the current 'outer loop', -1 outside one
  std::uint32_t corner[3] = {0, 0, 0};
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
      if (faces && !io::finite_point(v)) fail_line(path, ln, io::non_finite_point("facet " + std::to_string(facet), v));
      const std::uint32_t i = weld.add(v[0], v[1], v[2], mesh.vertices);
      if (in_loop < 3) corner[in_loop] = i;
      ++in_loop;
    } else if (key == "outer") {
      in_loop = 0;
    } else if (key == "endloop") {
      if (in_loop != 3)
        fail_line(path, ln, "facet " + std::to_string(facet) + " has " + std::to_string(std::max(in_loop, 0)) +
                                " vertices, expected 3");
      if (faces) mesh.add_face({corner[0], corner[1], corner[2]});
      in_loop = -1;
      ++facet;
    } else if (key != "facet" && key != "endfacet" && key != "endsolid") {
      fail_line(path, ln, "unexpected " + quote(key));
    }
  }
  if (in_loop >= 0) fail_line(path, lines.line() + 1, "file ends inside facet " + std::to_string(facet));
  return mesh;
}

// Parses the vertex index of an OBJ face corner ("i", "i/t", "i//n", "i/t/n") into a 0-based
// index; `seen` vertices have been read so far. false when it is no integer or 0.
bool obj_corner(std::string_view token, std::uint64_t seen, long long& index) {
  long long i = 0;
  if (!io::parse_int(token.substr(0, token.find('/')), i) || i == 0) return false;
  index = i > 0 ? i - 1 : static_cast<long long>(seen) + i;
  return true;
}

}  // namespace

Mesh read_off(const std::string& path, io::MeshRead what) {
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

  const bool faces = what == io::MeshRead::Mesh;
  Mesh mesh;
  const std::size_t fit = (data.size() - lines.offset()) / 6;  // "0 0 0\n" is the shortest vertex
  mesh.vertices.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(nv, fit)));
  if (normals) mesh.normals.reserve(mesh.vertices.capacity());
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
    if (faces && !io::finite_point(v)) fail_line(path, ln, io::non_finite_point("vertex " + std::to_string(i), v));
    mesh.vertices.emplace_back(v[0], v[1], v[2]);
    if (normals) mesh.normals.emplace_back(v[3], v[4], v[5]);
  }
  const std::string off = " of " + std::to_string(nf);
  for (std::uint64_t f = 0; f < nf; ++f) {
    if (!next_tokens(lines, tok)) fail_line(path, lines.line() + 1, "file ends before face " + std::to_string(f) + off);
    const std::size_t ln = lines.line();
    const std::string face = "face " + std::to_string(f);
    std::uint64_t k = 0;
    if (!io::parse_uint(tok[0], k)) fail_line(path, ln, "bad corner count " + quote(tok[0]) + " for " + face);
    if (k > tok.size() - 1)
      fail_line(path, ln, face + " has " + std::to_string(k) + " corners but only " +
                              std::to_string(tok.size() - 1) + " indices");
    if (faces && k < 3) fail_line(path, ln, io::too_few_corners(f, k));
    for (std::size_t c = 1; c <= k; ++c) {
      std::uint64_t idx = 0;
      if (!io::parse_uint(tok[c], idx) || idx >= nv) fail_line(path, ln, io::index_past_vertices(face, tok[c], nv));
      if (faces) mesh.face_vertices.push_back(static_cast<std::uint32_t>(idx));
    }
    if (faces) mesh.face_start.push_back(static_cast<std::uint32_t>(mesh.face_vertices.size()));
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
  return mesh;
}

Mesh read_obj(const std::string& path, io::MeshRead what) {
  const std::string data = io::read_file_bytes(path);
  io::LineReader lines(data, io::bom_size(data));
  std::vector<std::string_view> tok;
  const bool faces = what == io::MeshRead::Mesh;
  Mesh mesh;
  // A face may name a vertex defined further down: checked once every vertex is read.
  struct Forward {
    std::size_t line, face;
    std::string token;
    long long index;
  };
  std::vector<Forward> forward;
  while (next_tokens(lines, tok)) {
    const std::size_t ln = lines.line();
    if (tok[0] == "v") {
      if (tok.size() < 4) fail_line(path, ln, "expected 'v x y z', found " + std::to_string(tok.size() - 1) + " values");
      double v[3];
      for (int k = 0; k < 3; ++k)
        if (!io::parse_double(tok[k + 1], v[k]))
          fail_line(path, ln, io::bad_number(tok[k + 1], "bad number " + quote(tok[k + 1])));
      if (faces && !io::finite_point(v))
        fail_line(path, ln, io::non_finite_point("vertex " + std::to_string(mesh.vertices.size()), v));
      mesh.vertices.emplace_back(v[0], v[1], v[2]);
    } else if (faces && tok[0] == "f") {
      const std::size_t f = mesh.num_faces();
      if (tok.size() < 4) fail_line(path, ln, io::too_few_corners(f, tok.size() - 1));
      const std::uint64_t seen = mesh.vertices.size();
      for (std::size_t c = 1; c < tok.size(); ++c) {
        long long i = 0;
        if (!obj_corner(tok[c], seen, i))
          fail_line(path, ln, "bad vertex index " + quote(tok[c]) + " in face " + std::to_string(f) +
                                  " (OBJ counts vertices from 1, or back from -1)");
        if (i < 0) fail_line(path, ln, io::index_past_vertices("face " + std::to_string(f), tok[c], seen));
        if (static_cast<std::uint64_t>(i) >= seen) forward.push_back({ln, f, std::string(tok[c]), i});
        mesh.face_vertices.push_back(static_cast<std::uint32_t>(std::min<long long>(i, UINT32_MAX)));
      }
      mesh.face_start.push_back(static_cast<std::uint32_t>(mesh.face_vertices.size()));
    }
  }
  for (const Forward& r : forward)
    if (static_cast<std::uint64_t>(r.index) >= mesh.vertices.size())
      fail_line(path, r.line, io::index_past_vertices("face " + std::to_string(r.face), r.token, mesh.vertices.size()));
  return mesh;
}

Mesh read_stl(const std::string& path, io::MeshRead what) {
  const std::string data = io::read_file_bytes(path);
  if (data.size() >= 84) {
    const std::uint32_t n = load_u32_le(data.data() + 80);
    if (84 + 50 * static_cast<std::uint64_t>(n) == data.size()) return read_stl_binary(path, data, what);
  }
  // Ascii when it starts with "solid" and looks like text; binary headers may say "solid" too, but
  // their triangle count and float data nearly always hold a zero byte early on.
  std::size_t i = data.find_first_not_of(" \t\r\n", io::bom_size(data));
  const bool solid = i != std::string::npos && data.compare(i, 5, "solid") == 0;
  const bool text = std::memchr(data.data(), 0, std::min<std::size_t>(data.size(), 1024)) == nullptr;
  if (solid && text) return read_stl_ascii(path, data, what);
  return read_stl_binary(path, data, what);
}

PointCloud read_mesh_vertices(const std::string& path) {
  const std::string ext = io::lower_extension(path);
  const auto what = io::MeshRead::Vertices;
  if (ext == ".off") return io::vertices_as_cloud(read_off(path, what));
  if (ext == ".obj") return io::vertices_as_cloud(read_obj(path, what));
  if (ext == ".stl") return io::vertices_as_cloud(read_stl(path, what));
  fail(path, "unsupported mesh extension '" + ext + "' (expected .off, .obj or .stl)");
}

}  // namespace scallop
