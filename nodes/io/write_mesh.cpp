#include "nodes/io/write_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <stdexcept>

#include "nodes/io/read_support.h"
#include "nodes/types/ply_writer.h"

namespace scallop {
namespace {

// Appends ' ' and the integer v.
void put_index(std::string& out, std::uint64_t v) {
  char num[24];
  auto r = std::to_chars(num, num + sizeof num, v);
  out.push_back(' ');
  out.append(num, r.ptr);
}

// Appends v in its shortest form that reads back to the same double, then `sep`.
void put_number(std::string& out, double v, char sep) {
  char num[32];
  auto r = std::to_chars(num, num + sizeof num, v);
  out.append(num, r.ptr);
  out.push_back(sep);
}

// Appends the little-endian bytes of v (STL's byte order whatever the machine).
template <class T>
void put_le(std::string& out, T v) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &v, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}

// Writes `bytes` to `path`, or throws "cannot write '<path>': <reason>".
void save(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw std::runtime_error("cannot write '" + path + "': write failed");
}

std::string off_text(const Mesh& mesh) {
  const bool normals = mesh.has_normals();
  std::string s = normals ? "NOFF\n" : "OFF\n";
  s += std::to_string(mesh.num_vertices()) + " " + std::to_string(mesh.num_faces()) + " 0\n";
  for (std::size_t i = 0; i < mesh.num_vertices(); ++i) {
    for (int k = 0; k < 3; ++k) put_number(s, mesh.vertices[i][k], normals || k < 2 ? ' ' : '\n');
    if (normals)
      for (int k = 0; k < 3; ++k) put_number(s, mesh.normals[i][k], k < 2 ? ' ' : '\n');
  }
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    s += std::to_string(mesh.face_size(f));
    for (std::size_t c = 0; c < mesh.face_size(f); ++c) put_index(s, mesh.face(f)[c]);
    s += '\n';
  }
  return s;
}

std::string obj_text(const Mesh& mesh) {
  std::string s = "# written by scallop\n";
  for (const auto& v : mesh.vertices) {
    s += "v ";
    for (int k = 0; k < 3; ++k) put_number(s, v[k], k < 2 ? ' ' : '\n');
  }
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    s += 'f';
    for (std::size_t c = 0; c < mesh.face_size(f); ++c) put_index(s, std::uint64_t{mesh.face(f)[c]} + 1);
    s += '\n';
  }
  return s;
}

std::string stl_bytes(const Mesh& mesh) {
  std::size_t triangles = 0;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) triangles += mesh.face_size(f) - 2;
  if (triangles > UINT32_MAX) throw std::runtime_error("more triangles than binary STL can count");
  // A header that does not start with "solid", so that no reader takes the file for ascii.
  std::string s = "binary STL written by scallop";
  s.resize(80, ' ');
  s.reserve(84 + 50 * triangles);
  put_le(s, static_cast<std::uint32_t>(triangles));
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const std::uint32_t* c = mesh.face(f);
    for (std::size_t k = 1; k + 1 < mesh.face_size(f); ++k) {
      const Eigen::Vector3d& a = mesh.vertices[c[0]];
      const Eigen::Vector3d& b = mesh.vertices[c[k]];
      const Eigen::Vector3d& d = mesh.vertices[c[k + 1]];
      Eigen::Vector3d n = (b - a).cross(d - a);
      n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
      for (const Eigen::Vector3d* p : std::initializer_list<const Eigen::Vector3d*>{&n, &a, &b, &d})
        for (int i = 0; i < 3; ++i) put_le(s, static_cast<float>((*p)[i]));
      put_le(s, std::uint16_t{0});
    }
  }
  return s;
}

}  // namespace

std::string mesh_format_of(const std::string& path) {
  const std::string ext = io::lower_extension(path);
  for (const char* f : {"ply", "off", "obj", "stl"})
    if (ext == std::string(".") + f) return f;
  return "";
}

void write_mesh(const Mesh& mesh, const std::string& path, const std::string& format) {
  if (format == "ply") return write_mesh_ply(path, mesh);
  if (format == "off") return save(path, off_text(mesh));
  if (format == "obj") return save(path, obj_text(mesh));
  if (format == "stl") {
    std::string bytes;
    try {
      bytes = stl_bytes(mesh);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error("cannot write '" + path + "': " + e.what());
    }
    return save(path, bytes);
  }
  throw std::invalid_argument("unknown mesh format '" + format + "' (expected ply, off, obj or stl)");
}

}  // namespace scallop
