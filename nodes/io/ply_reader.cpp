#include "nodes/io/ply_reader.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
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

std::string_view scalar_name(Scalar s) {
  static const std::string_view names[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double"};
  return names[static_cast<int>(s)];
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

// What a property of an element feeds; the values of one item are gathered in a double[kSlots].
enum Slot : int { kNone = -1, kX, kY, kZ, kNx, kNy, kNz, kLabel, kV1, kV2, kFeature, kSlots, kCorners = kSlots };

enum class Role { Skip, Vertex, Face, Edge };

// How one element is read: its role and the slot of each property.
struct Plan {
  Role role = Role::Skip;
  std::vector<int> slots;
  bool normals = false, labels = false;
};

// The first non-list (or, for corners, list) property of each name gets its slot.
Plan plan_element(const Element& e, io::MeshRead what) {
  Plan plan;
  plan.slots.assign(e.props.size(), kNone);
  auto find = [&](const char* name, bool list) -> int {
    for (std::size_t i = 0; i < e.props.size(); ++i)
      if (e.props[i].is_list == list && e.props[i].name == name) return static_cast<int>(i);
    return -1;
  };
  auto take = [&](const char* name, int slot, bool list = false) {
    const int i = find(name, list);
    if (i >= 0) plan.slots[i] = slot;
    return i >= 0;
  };
  if (e.name == "vertex") {
    plan.role = Role::Vertex;
    take("x", kX), take("y", kY), take("z", kZ);
    if (find("nx", false) >= 0 && find("ny", false) >= 0 && find("nz", false) >= 0) {
      take("nx", kNx), take("ny", kNy), take("nz", kNz);
      plan.normals = true;
    }
  } else if (what == io::MeshRead::Mesh && e.name == "face") {
    plan.role = Role::Face;
    if (!take("vertex_indices", kCorners, true)) take("vertex_index", kCorners, true);
    plan.labels = take("label", kLabel);
  } else if (what == io::MeshRead::Mesh && e.name == "edge" && find("vertex1", false) >= 0 &&
             find("vertex2", false) >= 0 && find("feature", false) >= 0) {
    // scallop's own form: the feature edges of the mesh (an edge element without the flag is
    // some other list of edges, read past)
    plan.role = Role::Edge;
    take("vertex1", kV1), take("vertex2", kV2), take("feature", kFeature);
  }
  return plan;
}

// The end of the trailing-data message: which element was last and how many the header declares.
std::string trailing_what(const Element& last) {
  return " '" + last.name + "' (" + std::to_string(last.count) + " declared): the header's count" +
         " is smaller than the data";
}

// A number as a message quotes it: 12, -1, 2.5.
std::string number_text(double x) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

// Where the items go: the mesh being read, item by item.
class Sink {
 public:
  Sink(Mesh& mesh, std::uint64_t vertices) : mesh_(mesh), nv_(vertices) {}

  // Room for `n` items of `plan`'s element (never more than the file can hold).
  void reserve(const Plan& plan, std::size_t n) {
    if (plan.role == Role::Vertex) {
      mesh_.vertices.reserve(n);
      if (plan.normals) mesh_.normals.reserve(n);
    } else if (plan.role == Role::Face) {
      mesh_.face_start.reserve(n + 1);
      mesh_.face_vertices.reserve(3 * n);
      if (plan.labels) mesh_.face_label.reserve(n);
    }
  }
  // A corner of face `face`, read as x (its text `token`); "" or what is wrong with it.
  std::string corner(std::uint64_t face, double x, std::string_view token) {
    if (!(x >= 0 && x < static_cast<double>(nv_) && x == std::floor(x)))
      return io::index_past_vertices("face " + std::to_string(face), token, nv_);
    mesh_.face_vertices.push_back(static_cast<std::uint32_t>(x));
    return {};
  }
  // Item `i` of `plan`'s element, whose values are v; "" or what is wrong with it.
  std::string finish(const Plan& plan, std::uint64_t i, const double* v, bool finite_only) {
    switch (plan.role) {
      case Role::Skip: break;
      case Role::Vertex:
        if (finite_only && !io::finite_point(v)) return io::non_finite_point("vertex " + std::to_string(i), v);
        mesh_.vertices.emplace_back(v[kX], v[kY], v[kZ]);
        if (plan.normals) mesh_.normals.emplace_back(v[kNx], v[kNy], v[kNz]);
        break;
      case Role::Face: {
        const std::size_t corners = mesh_.face_vertices.size() - mesh_.face_start.back();
        if (corners < 3) return io::too_few_corners(i, corners);
        mesh_.face_start.push_back(static_cast<std::uint32_t>(mesh_.face_vertices.size()));
        if (plan.labels) mesh_.face_label.push_back(static_cast<std::int32_t>(v[kLabel]));
        break;
      }
      case Role::Edge:
        for (int k : {kV1, kV2})
          if (!(v[k] >= 0 && v[k] < static_cast<double>(nv_)))
            return io::index_past_vertices("edge " + std::to_string(i), number_text(v[k]), nv_);
        if (v[kFeature] != 0) {
          const auto a = static_cast<std::uint32_t>(v[kV1]), b = static_cast<std::uint32_t>(v[kV2]);
          mesh_.feature_edges.push_back({std::min(a, b), std::max(a, b)});
        }
        break;
    }
    return {};
  }

 private:
  Mesh& mesh_;
  std::uint64_t nv_;
};

void read_binary(const std::string& path, const std::string& data, std::size_t pos,
                 const std::vector<Element>& elements, const std::vector<Plan>& plans, bool big,
                 bool finite_only, Sink& sink) {
  const std::size_t size = data.size();
  for (std::size_t ei = 0; ei < elements.size(); ++ei) {
    const Element& e = elements[ei];
    const Plan& plan = plans[ei];
    bool fixed = true;
    std::size_t item_min = 0;  // bytes of an item whose lists are all empty
    for (const Property& p : e.props) {
      fixed = fixed && !p.is_list;
      item_min += p.is_list ? scalar_size(p.count_type) : scalar_size(p.type);
    }
    const std::string of = " of " + std::to_string(e.count);
    if (plan.role == Role::Skip && fixed) {
      // Skip the whole element at once; check against the bytes left before doing so.
      if (item_min > 0 && e.count > (size - pos) / item_min) {
        const std::size_t k = (size - pos) / item_min;
        fail_byte(path, pos + k * item_min, "file ends inside " + e.name + " " + std::to_string(k) + of);
      }
      pos += static_cast<std::size_t>(e.count) * item_min;
      continue;
    }
    // Never trust the count for the allocation: at most what the remaining bytes can hold.
    const std::size_t fit = item_min > 0 ? (size - pos) / item_min : 0;
    sink.reserve(plan, static_cast<std::size_t>(std::min<std::uint64_t>(e.count, fit)));
    for (std::uint64_t i = 0; i < e.count; ++i) {
      const std::size_t start = pos;
      double v[kSlots] = {};
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
          if (plan.slots[j] == kCorners)
            for (std::size_t k = 0; k < static_cast<std::size_t>(n); ++k) {
              const double x = read_scalar(data.data() + pos + k * es, p.type, big);
              if (auto bad = sink.corner(i, x, number_text(x)); !bad.empty()) fail_byte(path, start, bad);
            }
          pos += static_cast<std::size_t>(n) * es;
        } else {
          const std::size_t s = scalar_size(p.type);
          if (size - pos < s)
            fail_byte(path, start, "file ends inside " + e.name + " " + std::to_string(i) + of);
          if (plan.slots[j] >= 0) v[plan.slots[j]] = read_scalar(data.data() + pos, p.type, big);
          pos += s;
        }
      }
      if (auto bad = sink.finish(plan, i, v, finite_only); !bad.empty()) fail_byte(path, start, bad);
    }
  }
  // Data past the last element means the header's counts are too small: reading only what they
  // declare would drop points silently.
  if (pos < size && !elements.empty())
    fail_byte(path, pos, std::to_string(size - pos) + " bytes after the last declared element" +
                             trailing_what(elements.back()));
}

void read_ascii(const std::string& path, io::LineReader& lines, const std::vector<Element>& elements,
                const std::vector<Plan>& plans, std::size_t bytes_left, bool finite_only, Sink& sink) {
  std::vector<std::string_view> tok;
  std::string_view line;
  for (std::size_t ei = 0; ei < elements.size(); ++ei) {
    const Element& e = elements[ei];
    const Plan& plan = plans[ei];
    bool has_lists = false;
    for (const Property& p : e.props) has_lists = has_lists || p.is_list;
    // Each value takes at least two bytes ("0 "): never reserve more than the file can hold.
    const std::size_t fit = bytes_left / (2 * std::max<std::size_t>(1, e.props.size()));
    sink.reserve(plan, static_cast<std::size_t>(std::min<std::uint64_t>(e.count, fit)));
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
      double v[kSlots] = {};
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
            if (plan.slots[j] == kCorners)
              if (auto bad = sink.corner(i, x, tok[t]); !bad.empty()) fail_line(path, ln, bad);
          }
        } else {
          double x;
          if (!io::parse_double(tok[t], x))
            fail_line(path, ln, io::bad_number(tok[t], "bad value " + quote(tok[t]) + " for property '" + p.name +
                                                         "' of " + item));
          if (plan.slots[j] >= 0) v[plan.slots[j]] = x;
          ++t;
        }
      }
      if (t != tok.size())
        fail_line(path, ln, "expected " + std::to_string(t) + " values for " + item + ", found " +
                                std::to_string(tok.size()));
      if (auto bad = sink.finish(plan, i, v, finite_only); !bad.empty()) fail_line(path, ln, bad);
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

Mesh read_ply_mesh(const std::string& path, io::MeshRead what) {
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

  std::vector<Plan> plans;
  const Element* face = nullptr;
  for (const Element& e : elements) {
    plans.push_back(plan_element(e, what));
    if (plans.back().role == Role::Face) face = &e;
  }
  if (face) {
    const Plan& plan = plans[face - elements.data()];
    const auto corners = std::find(plan.slots.begin(), plan.slots.end(), kCorners);
    if (corners == plan.slots.end())
      fail_line(path, end_line, "face element has no 'vertex_indices' list property");
    const Property& p = face->props[corners - plan.slots.begin()];
    if (!is_integer(p.type))
      fail_line(path, end_line, "face property '" + p.name + "' holds " + quote(scalar_name(p.type)) +
                                    " values; vertex indices must be integers");
  }

  Mesh mesh;
  Sink sink(mesh, vertex->count);
  const bool finite_only = what == io::MeshRead::Mesh;
  if (format == Format::Ascii)
    read_ascii(path, lines, elements, plans, data.size() - lines.offset(), finite_only, sink);
  else
    read_binary(path, data, lines.offset(), elements, plans, format == Format::BinaryBE, finite_only, sink);
  return mesh;
}

PointCloud read_ply(const std::string& path) { return io::vertices_as_cloud(read_ply_mesh(path, io::MeshRead::Vertices)); }

}  // namespace scallop
