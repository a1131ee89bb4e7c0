#include "nodes/io/pcd_reader.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

#include <lzf.h>

#include "nodes/io/read_support.h"

namespace scallop {
namespace {

using io::fail_byte;
using io::fail_line;
using io::quote;

struct Field {
  std::string name;
  std::size_t size = 4;
  char type = 'F';  // I, U or F
  std::size_t count = 1;
  std::size_t offset = 0;  // within a point (binary) or within the value list (ascii)
};

// One little-endian scalar of `f` at p, as a double.
double read_value(const char* p, const Field& f) {
  switch (f.type) {
    case 'F':
      if (f.size == 4) { float v; std::memcpy(&v, p, 4); return v; }
      { double v; std::memcpy(&v, p, 8); return v; }
    case 'I':
      switch (f.size) {
        case 1: { std::int8_t v; std::memcpy(&v, p, 1); return v; }
        case 2: { std::int16_t v; std::memcpy(&v, p, 2); return v; }
        case 4: { std::int32_t v; std::memcpy(&v, p, 4); return v; }
        default: { std::int64_t v; std::memcpy(&v, p, 8); return static_cast<double>(v); }
      }
    default:
      switch (f.size) {
        case 1: { std::uint8_t v; std::memcpy(&v, p, 1); return v; }
        case 2: { std::uint16_t v; std::memcpy(&v, p, 2); return v; }
        case 4: { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
        default: { std::uint64_t v; std::memcpy(&v, p, 8); return static_cast<double>(v); }
      }
  }
}

// The end of the trailing-data message: how many points the header declares.
std::string trailing_what(std::uint64_t points) {
  return " (" + std::to_string(points) + " declared): the header's POINTS is smaller than the data";
}

}  // namespace

PointCloud read_pcd(const std::string& path) {
  const std::string data = io::read_file_bytes(path);
  io::LineReader lines(data, io::bom_size(data));
  std::string_view line;
  std::vector<std::string_view> tok;

  std::vector<std::string_view> fields, sizes, types, counts;
  bool have_fields = false, have_size = false, have_type = false, have_count = false;
  bool have_points = false, have_width = false, have_data = false;
  std::uint64_t points = 0, width = 0, height = 1;
  std::string_view data_kind;
  std::size_t data_line = 0;
  while (lines.next(line)) {
    const std::size_t ln = lines.line();
    io::split_tokens(line, tok);
    if (tok.empty() || tok[0].front() == '#') continue;
    const std::string_view key = tok[0];
    const std::vector<std::string_view> rest(tok.begin() + 1, tok.end());
    auto one_number = [&](std::uint64_t& v) {
      if (rest.size() != 1 || !io::parse_uint(rest[0], v))
        fail_line(path, ln, std::string(key) + " must be one non-negative integer");
    };
    if (key == "VERSION" || key == "VIEWPOINT") {
      continue;
    } else if (key == "FIELDS" || key == "COLUMNS") {
      fields = rest;
      have_fields = true;
    } else if (key == "SIZE") {
      sizes = rest;
      have_size = true;
    } else if (key == "TYPE") {
      types = rest;
      have_type = true;
    } else if (key == "COUNT") {
      counts = rest;
      have_count = true;
    } else if (key == "WIDTH") {
      one_number(width);
      have_width = true;
    } else if (key == "HEIGHT") {
      one_number(height);
    } else if (key == "POINTS") {
      one_number(points);
      have_points = true;
    } else if (key == "DATA") {
      if (rest.size() != 1) fail_line(path, ln, "expected 'DATA ascii', 'DATA binary' or 'DATA binary_compressed'");
      data_kind = rest[0];
      if (data_kind != "ascii" && data_kind != "binary" && data_kind != "binary_compressed")
        fail_line(path, ln, "unknown DATA format " + quote(data_kind) +
                                " (expected ascii, binary or binary_compressed)");
      data_line = ln;
      have_data = true;
      break;
    } else {
      if (ln == 1) fail_line(path, ln, "not a PCD file (unknown header line starting with " + quote(key) + ")");
      fail_line(path, ln, "unknown header line starting with " + quote(key));
    }
  }
  if (!have_data) fail_line(path, lines.line(), "header ends without a DATA line");

  // Check the header as a whole at the DATA line, where it ends.
  const std::size_t hl = data_line;
  if (!have_fields || fields.empty()) fail_line(path, hl, "header has no FIELDS line");
  if (!have_size) fail_line(path, hl, "header has no SIZE line");
  if (!have_type) fail_line(path, hl, "header has no TYPE line");
  const std::size_t nf = fields.size();
  auto same_length = [&](const std::vector<std::string_view>& v, const char* name) {
    if (v.size() != nf)
      fail_line(path, hl, std::string(name) + " has " + std::to_string(v.size()) + " values but FIELDS has " +
                              std::to_string(nf));
  };
  same_length(sizes, "SIZE");
  same_length(types, "TYPE");
  if (have_count) same_length(counts, "COUNT");
  std::vector<Field> fs(nf);
  std::size_t point_step = 0, values_per_point = 0;
  for (std::size_t i = 0; i < nf; ++i) {
    Field& f = fs[i];
    f.name = std::string(fields[i]);
    std::uint64_t s = 0, c = 1;
    if (!io::parse_uint(sizes[i], s) || (s != 1 && s != 2 && s != 4 && s != 8))
      fail_line(path, hl, "SIZE " + quote(sizes[i]) + " of field '" + f.name + "' is not 1, 2, 4 or 8");
    f.size = s;
    if (types[i].size() != 1 || std::string_view("IUF").find(types[i][0]) == std::string_view::npos)
      fail_line(path, hl, "TYPE " + quote(types[i]) + " of field '" + f.name + "' is not I, U or F");
    f.type = types[i][0];
    if (f.type == 'F' && f.size != 4 && f.size != 8)
      fail_line(path, hl, "field '" + f.name + "' is F with SIZE " + std::to_string(s) + " (expected 4 or 8)");
    if (have_count && (!io::parse_uint(counts[i], c) || c < 1 || c > 1'000'000))
      fail_line(path, hl, "COUNT " + quote(counts[i]) + " of field '" + f.name + "' is not a positive integer");
    f.count = c;
    f.offset = point_step;
    point_step += f.size * f.count;
    values_per_point += f.count;
  }
  auto find = [&](const char* name) {
    for (std::size_t i = 0; i < nf; ++i)
      if (fs[i].name == name) return static_cast<int>(i);
    return -1;
  };
  const int slot[6] = {find("x"), find("y"), find("z"), find("normal_x"), find("normal_y"), find("normal_z")};
  for (int k = 0; k < 3; ++k)
    if (slot[k] < 0) fail_line(path, hl, std::string("FIELDS has no '") + "xyz"[k] + "'");
  const bool has_normals = slot[3] >= 0 && slot[4] >= 0 && slot[5] >= 0;
  if (!have_points) {
    if (!have_width) fail_line(path, hl, "header has neither POINTS nor WIDTH");
    if (height != 0 && width > UINT64_MAX / height) fail_line(path, hl, "WIDTH * HEIGHT is too large");
    points = width * height;
  }

  PointCloud cloud;
  const std::size_t start = lines.offset();
  const std::size_t left = data.size() - start;
  const std::string of = " of " + std::to_string(points);
  auto reserve = [&](std::size_t fit) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(points, fit));
    cloud.points.reserve(n);
    if (has_normals) cloud.normals.reserve(n);
  };

  if (data_kind == "ascii") {
    reserve(left / (2 * values_per_point));  // each value takes two bytes at least ("0 ")
    // Where each field's first value sits among the values of a point.
    std::vector<std::size_t> first(nf);
    for (std::size_t i = 0, t = 0; i < nf; t += fs[i].count, ++i) first[i] = t;
    for (std::uint64_t i = 0; i < points; ++i) {
      bool got = false;
      while ((got = lines.next(line))) {
        io::split_tokens(line, tok);
        if (!tok.empty()) break;
      }
      if (!got) fail_line(path, lines.line() + 1, "file ends before point " + std::to_string(i) + of);
      const std::size_t ln = lines.line();
      if (tok.size() != values_per_point)
        fail_line(path, ln, "expected " + std::to_string(values_per_point) + " values for point " +
                                std::to_string(i) + ", found " + std::to_string(tok.size()));
      double v[6] = {0, 0, 0, 0, 0, 0};
      for (std::size_t f = 0; f < nf; ++f)
        for (std::size_t c = 0; c < fs[f].count; ++c) {
          const std::string_view t = tok[first[f] + c];
          double x;
          if (!io::parse_double(t, x))
            fail_line(path, ln, io::bad_number(t, "bad value " + quote(t) + " for field '" + fs[f].name +
                                                      "' of point " + std::to_string(i)));
          for (int k = 0; k < 6; ++k)
            if (slot[k] == static_cast<int>(f) && c == 0) v[k] = x;
        }
      cloud.points.emplace_back(v[0], v[1], v[2]);
      if (has_normals) cloud.normals.emplace_back(v[3], v[4], v[5]);
    }
    // Blank lines may follow; anything else means POINTS is smaller than the data, and reading
    // only what it declares would drop points silently.
    std::size_t first_extra = 0, extra = 0;
    while (lines.next(line)) {
      io::split_tokens(line, tok);
      if (tok.empty()) continue;
      if (extra++ == 0) first_extra = lines.line();
    }
    if (extra > 0)
      fail_line(path, first_extra, std::to_string(extra) + (extra == 1 ? " line" : " lines") + " after the last point" +
                                 trailing_what(points));
    return cloud;
  }

  if (data_kind == "binary") {
    if (points > left / point_step) {
      const std::size_t k = left / point_step;
      fail_byte(path, start + k * point_step, "file ends inside point " + std::to_string(k) + of);
    }
    if (const std::size_t end = start + points * point_step; end < data.size())
      fail_byte(path, end, std::to_string(data.size() - end) + " bytes after the last point" + trailing_what(points));
    reserve(points);
    for (std::size_t i = 0; i < points; ++i) {
      const char* p = data.data() + start + i * point_step;
      double v[6] = {0, 0, 0, 0, 0, 0};
      for (int k = 0; k < (has_normals ? 6 : 3); ++k) v[k] = read_value(p + fs[slot[k]].offset, fs[slot[k]]);
      cloud.points.emplace_back(v[0], v[1], v[2]);
      if (has_normals) cloud.normals.emplace_back(v[3], v[4], v[5]);
    }
    return cloud;
  }

  // binary_compressed
  if (left < 8) fail_byte(path, start, "file ends inside the compressed and uncompressed sizes");
  std::uint32_t csize = 0, usize = 0;
  std::memcpy(&csize, data.data() + start, 4);
  std::memcpy(&usize, data.data() + start + 4, 4);
  if (csize > left - 8)
    fail_byte(path, start, "compressed size " + std::to_string(csize) + " but only " +
                               std::to_string(left - 8) + " bytes follow");
  if (points > usize / point_step || points * point_step != usize)
    fail_byte(path, start + 4, "uncompressed size " + std::to_string(usize) + " does not match " +
                                   std::to_string(points) + " points of " + std::to_string(point_step) +
                                   " bytes");
  // An LZF back reference of 3 bytes expands to at most 264: a larger ratio is a lie, and
  // checking it first keeps a forged header from making us allocate gigabytes.
  if (usize / 88 > csize)
    fail_byte(path, start + 4, "uncompressed size " + std::to_string(usize) + " is impossible for " +
                                   std::to_string(csize) + " compressed bytes");
  // Bytes after the compressed block are not an error: PCL's own writer leaves some (the file is
  // sized for the worst-case compression; shared/data/milk_kinect/milk.pcd has 3913), and the
  // point count is checked against the uncompressed size above.
  std::vector<char> raw(usize);
  if (usize > 0) {
    const unsigned got = lzf_decompress(data.data() + start + 8, csize, raw.data(), usize);
    if (got != usize) fail_byte(path, start + 8, "corrupt LZF data");
  }
  // Structure of arrays: field f of point i at (sum of the earlier fields' blocks) + i * size*count.
  std::vector<std::size_t> block(nf);
  for (std::size_t f = 0, off = 0; f < nf; off += points * fs[f].size * fs[f].count, ++f) block[f] = off;
  reserve(points);
  for (std::size_t i = 0; i < points; ++i) {
    double v[6] = {0, 0, 0, 0, 0, 0};
    for (int k = 0; k < (has_normals ? 6 : 3); ++k) {
      const Field& f = fs[slot[k]];
      v[k] = read_value(raw.data() + block[slot[k]] + i * f.size * f.count, f);
    }
    cloud.points.emplace_back(v[0], v[1], v[2]);
    if (has_normals) cloud.normals.emplace_back(v[3], v[4], v[5]);
  }
  return cloud;
}

}  // namespace scallop
