#include "nodes/io/ply_reader.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string_view>
#include <vector>

#include "nodes/io/read_support.h"

namespace scallop {
namespace {

using io::fail;
using io::fail_byte;
using io::fail_line;
using io::quote;

enum class Scalar { I8, U8, I16, U16, I32, U32, F32, F64 };

bool scalar_from_name(std::string_view n, Scalar& s) {
  static const std::pair<std::string_view, Scalar> names[] = {
      {"char", Scalar::I8},     {"int8", Scalar::I8},     {"uchar", Scalar::U8},
      {"uint8", Scalar::U8},    {"short", Scalar::I16},   {"int16", Scalar::I16},
      {"ushort", Scalar::U16},  {"uint16", Scalar::U16},  {"int", Scalar::I32},
      {"int32", Scalar::I32},   {"uint", Scalar::U32},    {"uint32", Scalar::U32},
      {"float", Scalar::F32},   {"float32", Scalar::F32}, {"double", Scalar::F64},
      {"float64", Scalar::F64}};
  for (const auto& [name, type] : names)
    if (n == name) {
      s = type;
      return true;
    }
  return false;
}

std::size_t scalar_size(Scalar s) {
  switch (s) {
    case Scalar::I8: case Scalar::U8: return 1;
    case Scalar::I16: case Scalar::U16: return 2;
    case Scalar::I32: case Scalar::U32: case Scalar::F32: return 4;
    case Scalar::F64: return 8;
  }
  return 0;
}

bool is_integer(Scalar s) { return s != Scalar::F32 && s != Scalar::F64; }

// One binary scalar at p (scalar_size(s) bytes available), as a double.
double read_scalar(const char* p, Scalar s, bool big_endian) {
  unsigned char b[8];
  const std::size_t n = scalar_size(s);
  std::memcpy(b, p, n);
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
  switch (s) {
    case Scalar::I8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
    case Scalar::U8: { std::uint8_t v; std::memcpy(&v, b, 1); return v; }
    case Scalar::I16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
    case Scalar::U16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
    case Scalar::I32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
    case Scalar::U32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
    case Scalar::F32: { float v; std::memcpy(&v, b, 4); return v; }
    case Scalar::F64: { double v; std::memcpy(&v, b, 8); return v; }
  }
  return 0;
}

struct Property {
  std::string name;
  Scalar type = Scalar::F32;
  bool is_list = false;
  Scalar count_type = Scalar::U8;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> props;
};

enum class Format { Ascii, BinaryLE, BinaryBE };

// Which vertex property feeds which output slot: 0..2 position, 3..5 normal, -1 dropped.
std::vector<int> vertex_slots(const Element& v, bool& has_normals) {
  static const char* names[] = {"x", "y", "z", "nx", "ny", "nz"};
  std::vector<int> slots(v.props.size(), -1);
  int found[6] = {-1, -1, -1, -1, -1, -1};
  for (std::size_t i = 0; i < v.props.size(); ++i)
    for (int k = 0; k < 6; ++k)
      if (!v.props[i].is_list && v.props[i].name == names[k] && found[k] < 0) {
        found[k] = static_cast<int>(i);
        slots[i] = k;
      }
  has_normals = found[3] >= 0 && found[4] >= 0 && found[5] >= 0;
  if (!has_normals)
    for (int& s : slots)
      if (s >= 3) s = -1;
  return slots;
}

// The end of the trailing-data message: which element was last and how many the header declares.
std::string trailing_what(const Element& last) {
  return " '" + last.name + "' (" + std::to_string(last.count) + " declared): the header's count" +
         " is smaller than the data";
}

void read_binary(const std::string& path, const std::string& data, std::size_t pos,
                 const std::vector<Element>& elements, bool big, PointCloud& cloud) {
  const std::size_t size = data.size();
  for (const Element& e : elements) {
    const bool is_vertex = e.name == "vertex";
    bool fixed = true;
    std::size_t item_min = 0;  // bytes of an item whose lists are all empty
    for (const Property& p : e.props) {
      fixed = fixed && !p.is_list;
      item_min += p.is_list ? scalar_size(p.count_type) : scalar_size(p.type);
    }
    const std::string of = " of " + std::to_string(e.count);
    if (!is_vertex && fixed) {
      // Skip the whole element at once; check against the bytes left before doing so.
      if (item_min > 0 && e.count > (size - pos) / item_min) {
        const std::size_t k = (size - pos) / item_min;
        fail_byte(path, pos + k * item_min, "file ends inside " + e.name + " " + std::to_string(k) + of);
      }
      pos += static_cast<std::size_t>(e.count) * item_min;
      continue;
    }
    bool has_normals = false;
    std::vector<int> slots;
    if (is_vertex) {
      slots = vertex_slots(e, has_normals);
      // Never trust the count for the allocation: at most what the remaining bytes can hold.
      const std::size_t fit = item_min > 0 ? (size - pos) / item_min : 0;
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(e.count, fit));
      cloud.points.reserve(n);
      if (has_normals) cloud.normals.reserve(n);
    }
    for (std::uint64_t i = 0; i < e.count; ++i) {
      const std::size_t start = pos;
      double v[6] = {0, 0, 0, 0, 0, 0};
      for (std::size_t j = 0; j < e.props.size(); ++j) {
        const Property& p = e.props[j];
        if (p.is_list) {
          const std::size_t cs = scalar_size(p.count_type);
          if (size - pos < cs)
            fail_byte(path, start, "file ends inside " + e.name + " " + std::to_string(i) + of);
          const double n = read_scalar(data.data() + pos, p.count_type, big);
          if (n < 0)
            fail_byte(path, pos, "negative list length " + std::to_string(static_cast<long long>(n)) +
                                     " in property '" + p.name + "' of " + e.name + " " +
                                     std::to_string(i));
          pos += cs;
          const std::size_t es = scalar_size(p.type);
          if (n > static_cast<double>((size - pos) / es))
            fail_byte(path, start, "file ends inside " + e.name + " " + std::to_string(i) + of);
          pos += static_cast<std::size_t>(n) * es;
        } else {
          const std::size_t s = scalar_size(p.type);
          if (size - pos < s)
            fail_byte(path, start, "file ends inside " + e.name + " " + std::to_string(i) + of);
          if (is_vertex && slots[j] >= 0) v[slots[j]] = read_scalar(data.data() + pos, p.type, big);
          pos += s;
        }
      }
      if (is_vertex) {
        cloud.points.emplace_back(v[0], v[1], v[2]);
        if (has_normals) cloud.normals.emplace_back(v[3], v[4], v[5]);
      }
    }
  }
  // Data past the last element means the header's counts are too small: reading only what they
  // declare would drop points silently.
  if (pos < size && !elements.empty())
    fail_byte(path, pos, std::to_string(size - pos) + " bytes after the last declared element" +
                             trailing_what(elements.back()));
}

void read_ascii(const std::string& path, io::LineReader& lines, const std::vector<Element>& elements,
                PointCloud& cloud, std::size_t bytes_left) {
  std::vector<std::string_view> tok;
  std::string_view line;
  for (const Element& e : elements) {
    const bool is_vertex = e.name == "vertex";
    bool has_lists = false;
    for (const Property& p : e.props) has_lists = has_lists || p.is_list;
    bool has_normals = false;
    std::vector<int> slots;
    if (is_vertex) {
      slots = vertex_slots(e, has_normals);
      // Each value takes at least two bytes ("0 "): never reserve more than the file can hold.
      const std::size_t fit = bytes_left / (2 * std::max<std::size_t>(1, e.props.size()));
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(e.count, fit));
      cloud.points.reserve(n);
      if (has_normals) cloud.normals.reserve(n);
    }
    const std::string of = " of " + std::to_string(e.count);
    for (std::uint64_t i = 0; i < e.count; ++i) {
      const std::string item = e.name + " " + std::to_string(i);
      bool got = false;
      while ((got = lines.next(line))) {
        io::split_tokens(line, tok);
        if (!tok.empty()) break;
      }
      if (!got) fail_line(path, lines.line() + 1, "file ends before " + item + of);
      const std::size_t ln = lines.line();
      double v[6] = {0, 0, 0, 0, 0, 0};
      std::size_t t = 0;
      for (std::size_t j = 0; j < e.props.size(); ++j) {
        const Property& p = e.props[j];
        if (t >= tok.size()) {
          // Lists still to come count one value (their length) at least.
          const std::size_t need = t + (e.props.size() - j);
          fail_line(path, ln, std::string("expected ") + (has_lists ? "at least " : "") +
                                  std::to_string(need) + " values for " + item + ", found " +
                                  std::to_string(tok.size()));
        }
        if (p.is_list) {
          long long n = 0;
          if (!io::parse_int(tok[t], n) || n < 0)
            fail_line(path, ln, "bad list length " + quote(tok[t]) + " for property '" + p.name +
                                    "' of " + item);
          ++t;
          if (static_cast<unsigned long long>(n) > tok.size() - t) {
            const std::size_t need = t + static_cast<std::size_t>(n) + (e.props.size() - j - 1);
            fail_line(path, ln, std::string("expected ") + (j + 1 < e.props.size() ? "at least " : "") +
                                    std::to_string(need) + " values for " + item + ", found " +
                                    std::to_string(tok.size()));
          }
          for (long long k = 0; k < n; ++k, ++t) {
            double x;
            if (!io::parse_double(tok[t], x))
              fail_line(path, ln, io::bad_number(tok[t], "bad value " + quote(tok[t]) + " for property '" + p.name +
                                                           "' of " + item));
          }
        } else {
          double x;
          if (!io::parse_double(tok[t], x))
            fail_line(path, ln, io::bad_number(tok[t], "bad value " + quote(tok[t]) + " for property '" + p.name +
                                                         "' of " + item));
          if (is_vertex && slots[j] >= 0) v[slots[j]] = x;
          ++t;
        }
      }
      if (t != tok.size())
        fail_line(path, ln, "expected " + std::to_string(t) + " values for " + item + ", found " +
                                std::to_string(tok.size()));
      if (is_vertex) {
        cloud.points.emplace_back(v[0], v[1], v[2]);
        if (has_normals) cloud.normals.emplace_back(v[3], v[4], v[5]);
      }
    }
  }
  // Blank lines may follow; anything else means the header's counts are too small.
  std::size_t first = 0, extra = 0;
  while (lines.next(line)) {
    io::split_tokens(line, tok);
    if (tok.empty()) continue;
    if (extra++ == 0) first = lines.line();
  }
  if (extra > 0 && !elements.empty())
    fail_line(path, first, std::to_string(extra) + (extra == 1 ? " line" : " lines") +
                               " after the last declared element" + trailing_what(elements.back()));
}

}  // namespace

PointCloud read_ply(const std::string& path) {
  const std::string data = io::read_file_bytes(path);
  io::LineReader lines(data, io::bom_size(data));
  std::string_view line;
  std::vector<std::string_view> tok;

  lines.next(line);
  io::split_tokens(line, tok);
  if (tok.size() != 1 || tok[0] != "ply") fail_line(path, 1, "not a PLY file (the first line must be 'ply')");

  bool have_format = false, ended = false;
  Format format = Format::Ascii;
  std::vector<Element> elements;
  while (lines.next(line)) {
    const std::size_t ln = lines.line();
    io::split_tokens(line, tok);
    if (tok.empty()) continue;
    const std::string_view key = tok[0];
    if (key == "comment" || key == "obj_info") continue;
    if (key == "end_header") {
      ended = true;
      break;
    }
    if (key == "format") {
      if (have_format) fail_line(path, ln, "second 'format' line");
      if (tok.size() != 3) fail_line(path, ln, "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
      if (tok[1] == "ascii") format = Format::Ascii;
      else if (tok[1] == "binary_little_endian") format = Format::BinaryLE;
      else if (tok[1] == "binary_big_endian") format = Format::BinaryBE;
      else fail_line(path, ln, "unknown format " + quote(tok[1]) + " (expected ascii, binary_little_endian or binary_big_endian)");
      if (tok[2] != "1.0") fail_line(path, ln, "unsupported PLY version " + quote(tok[2]) + " (expected 1.0)");
      have_format = true;
    } else if (key == "element") {
      if (tok.size() != 3) fail_line(path, ln, "expected 'element <name> <count>'");
      Element e;
      e.name = std::string(tok[1]);
      if (!io::parse_uint(tok[2], e.count))
        fail_line(path, ln, "bad count " + quote(tok[2]) + " for element '" + e.name + "'");
      for (const Element& o : elements)
        if (o.name == e.name) fail_line(path, ln, "second element '" + e.name + "'");
      elements.push_back(std::move(e));
    } else if (key == "property") {
      if (elements.empty()) fail_line(path, ln, "property before any element");
      Property p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        if (!scalar_from_name(tok[2], p.count_type)) fail_line(path, ln, "unknown property type " + quote(tok[2]));
        if (!is_integer(p.count_type)) fail_line(path, ln, "list length type " + quote(tok[2]) + " is not an integer type");
        if (!scalar_from_name(tok[3], p.type)) fail_line(path, ln, "unknown property type " + quote(tok[3]));
        p.name = std::string(tok[4]);
      } else if (tok.size() == 3 && tok[1] != "list") {
        if (!scalar_from_name(tok[1], p.type)) fail_line(path, ln, "unknown property type " + quote(tok[1]));
        p.name = std::string(tok[2]);
      } else {
        fail_line(path, ln, "expected 'property <type> <name>' or 'property list <type> <type> <name>'");
      }
      elements.back().props.push_back(std::move(p));
    } else {
      fail_line(path, ln, "unknown header line starting with " + quote(key));
    }
  }
  const std::size_t end_line = lines.line();
  if (!ended) fail_line(path, end_line, "header ends without 'end_header'");
  if (!have_format) fail_line(path, end_line, "header has no 'format' line");
  const Element* vertex = nullptr;
  for (const Element& e : elements)
    if (e.name == "vertex") vertex = &e;
  if (!vertex) fail_line(path, end_line, "header has no 'element vertex'");
  for (const char* c : {"x", "y", "z"}) {
    bool found = false;
    for (const Property& p : vertex->props) found = found || (!p.is_list && p.name == c);
    if (!found) fail_line(path, end_line, std::string("vertex element has no '") + c + "' property");
  }

  PointCloud cloud;
  if (format == Format::Ascii)
    read_ascii(path, lines, elements, cloud, data.size() - lines.offset());
  else
    read_binary(path, data, lines.offset(), elements, format == Format::BinaryBE, cloud);
  return cloud;
}

}  // namespace scallop
