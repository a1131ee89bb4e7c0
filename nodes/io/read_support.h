// Small helpers shared by the cloud and mesh readers: loading a file, walking its lines, parsing
// numbers and raising CloudReadError with the file name and position.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "nodes/io/read_cloud.h"
#include "nodes/types/mesh.h"

namespace scallop::io {

// The whole file as bytes. Throws CloudReadError "<path>: file does not exist",
// "<path>: is a directory, not a file", "<path>: cannot read file" or "<path>: file is empty".
std::string read_file_bytes(const std::string& path);

[[noreturn]] void fail(const std::string& path, const std::string& what);
[[noreturn]] void fail_line(const std::string& path, std::size_t line, const std::string& what);
[[noreturn]] void fail_byte(const std::string& path, std::size_t offset, const std::string& what);

// Walks the lines of `data` from byte `start`, stripping "\n" or "\r\n".
class LineReader {
 public:
  explicit LineReader(std::string_view data, std::size_t start = 0, std::size_t first_line = 1)
      : data_(data), pos_(start), next_line_(first_line) {}
  // The next line; false at the end of the data.
  bool next(std::string_view& line);
  // Number of the line last returned (the line the next call would return, before any call).
  std::size_t line() const { return next_line_ - 1; }
  // Byte offset just past the end of the last returned line and its terminator.
  std::size_t offset() const { return pos_; }

 private:
  std::string_view data_;
  std::size_t pos_;
  std::size_t next_line_;
};

// Splits on blanks (spaces, tabs, '\r') into `out`.
void split_tokens(std::string_view line, std::vector<std::string_view>& out);

// Whole-token parses. parse_double accepts a leading '+', "nan" and "inf".
bool parse_double(std::string_view s, double& v);
bool parse_int(std::string_view s, long long& v);
bool parse_uint(std::string_view s, std::uint64_t& v);

// Bytes of a UTF-8 byte order mark at the start of `data` (3), else 0. Windows editors write one;
// it is no part of the first line (it made the first point a header line, or the magic word wrong).
std::size_t bom_size(std::string_view data);

// Whether `token`, not a number as it stands, is one once its ',' is read as '.' ("1,5"): the file
// writes decimal commas, and the message should say so rather than "bad number".
bool decimal_comma(std::string_view token);
// "decimal commas are not supported; use '.'" when decimal_comma(token), else `otherwise`.
std::string bad_number(std::string_view token, const std::string& otherwise);

// A token fit to quote in a message: 'abc', with non-printable bytes as '?' and at most 32 chars.
std::string quote(std::string_view token);

// The extension of `path` in lower case with its dot (".ply"), or "" when it has none.
std::string lower_extension(const std::string& path);

// "<path>: scale must be positive and finite, got <scale>" unless it is.
void check_scale(const std::string& path, double scale);

// ---- mesh files (mesh_reader.h, ply_reader.h)

// What a mesh file's reader keeps.
enum class MeshRead {
  // io.read_cloud: the vertices (and vertex normals) only. Faces are read past (OFF's indices
  // are checked), NaN coordinates kept.
  Vertices,
  // io.read_mesh: vertices and faces. Every face needs at least 3 corners, each a vertex of the
  // file; NaN and infinite coordinates are refused.
  Mesh,
};

// The vertices (and normals) of a mesh as a point cloud, moved out of it.
PointCloud vertices_as_cloud(Mesh&& mesh);

// Whether x, y and z are all finite.
bool finite_point(const double* xyz);
// "<item> has a NaN coordinate" or "<item> has an infinite coordinate", for a non-finite xyz.
std::string non_finite_point(const std::string& item, const double* xyz);
// "<item> has index '<token>' but there are <vertices> vertices".
std::string index_past_vertices(const std::string& item, std::string_view token, std::uint64_t vertices);
// "face <f> has <corners> corners; a face needs at least 3".
std::string too_few_corners(std::uint64_t face, std::uint64_t corners);

}  // namespace scallop::io
