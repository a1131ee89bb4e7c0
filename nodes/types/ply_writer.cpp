#include "nodes/types/ply_writer.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace scallop {

void write_ply(const std::string& path, const PointCloud& cloud, bool binary) {
  if (!cloud.normals.empty() && cloud.normals.size() != cloud.points.size())
    throw std::runtime_error("cannot write '" + path + "': the cloud has " + std::to_string(cloud.normals.size()) +
                             " normals for " + std::to_string(cloud.points.size()) + " points");
  const bool normals = cloud.has_normals();
  const bool uncertainty = cloud.has_uncertainty();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));

  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
      << "comment written by scallop\n"
      << "element vertex " << cloud.points.size() << "\n"
      << "property double x\nproperty double y\nproperty double z\n";
  if (normals) out << "property double nx\nproperty double ny\nproperty double nz\n";
  if (uncertainty) out << "property double uncertainty\n";
  out << "end_header\n";

  const std::size_t per = 3 + (normals ? 3 : 0) + (uncertainty ? 1 : 0);
  if (binary) {
    // Buffer a block of points at a time; PLY wants little-endian whatever the machine.
    std::vector<std::uint64_t> buf;
    buf.reserve(per * 4096);
    auto put = [&](double v) {
      std::uint64_t b = std::bit_cast<std::uint64_t>(v);
      if constexpr (std::endian::native == std::endian::big) {
        std::uint64_t r = 0;
        for (int i = 0; i < 8; ++i) r = (r << 8) | ((b >> (8 * i)) & 0xff);
        b = r;
      }
      buf.push_back(b);
    };
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
      for (int k = 0; k < 3; ++k) put(cloud.points[i][k]);
      if (normals)
        for (int k = 0; k < 3; ++k) put(cloud.normals[i][k]);
      if (uncertainty) put(cloud.uncertainty[i]);
      if (buf.size() >= per * 4096 || i + 1 == cloud.points.size()) {
        out.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size() * 8));
        buf.clear();
      }
    }
  } else {
    std::string line;
    char num[32];
    auto put = [&](double v, char sep) {
      // Shortest round-trip form: reading it back gives the same double.
      auto r = std::to_chars(num, num + sizeof num, v);
      line.append(num, r.ptr);
      line.push_back(sep);
    };
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
      line.clear();
      for (int k = 0; k < 3; ++k) put(cloud.points[i][k], ' ');
      if (normals)
        for (int k = 0; k < 3; ++k) put(cloud.normals[i][k], ' ');
      if (uncertainty) put(cloud.uncertainty[i], ' ');
      line.back() = '\n';
      out << line;
    }
  }
  out.close();
  if (!out) throw std::runtime_error("cannot write '" + path + "': write failed");
}

namespace {
// PLY binary_little_endian: the bytes of a scalar, least significant first.
template <class T>
void put_le(std::string& buf, T v) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &v, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  buf.append(bytes, sizeof(T));
}
}  // namespace

void write_mesh_ply(const std::string& path, const Mesh& mesh) {
  const bool normals = mesh.has_normals();
  const bool labels = mesh.has_labels();
  for (std::size_t f = 0; f < mesh.num_faces(); ++f)
    if (mesh.face_size(f) > 255)
      throw std::runtime_error("cannot write '" + path + "': face " + std::to_string(f) + " has " +
                               std::to_string(mesh.face_size(f)) + " corners, more than PLY's 255");
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
  out << "ply\nformat binary_little_endian 1.0\ncomment written by scallop\n"
      << "element vertex " << mesh.num_vertices() << "\n"
      << "property double x\nproperty double y\nproperty double z\n";
  if (normals) out << "property double nx\nproperty double ny\nproperty double nz\n";
  out << "element face " << mesh.num_faces() << "\nproperty list uchar uint vertex_indices\n";
  if (labels) out << "property int label\n";
  if (!mesh.feature_edges.empty())
    out << "element edge " << mesh.feature_edges.size()
        << "\nproperty uint vertex1\nproperty uint vertex2\nproperty uchar feature\n";
  out << "end_header\n";
  std::string buf;
  auto flush = [&](bool force) {
    if (force || buf.size() > (1u << 20)) {
      out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
      buf.clear();
    }
  };
  for (std::size_t i = 0; i < mesh.num_vertices(); ++i) {
    for (int k = 0; k < 3; ++k) put_le(buf, mesh.vertices[i][k]);
    if (normals)
      for (int k = 0; k < 3; ++k) put_le(buf, mesh.normals[i][k]);
    flush(false);
  }
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    put_le(buf, static_cast<std::uint8_t>(mesh.face_size(f)));
    for (std::size_t c = 0; c < mesh.face_size(f); ++c) put_le(buf, mesh.face(f)[c]);
    if (labels) put_le(buf, mesh.face_label[f]);
    flush(false);
  }
  for (const auto& e : mesh.feature_edges) {
    put_le(buf, e[0]);
    put_le(buf, e[1]);
    put_le(buf, std::uint8_t{1});
    flush(false);
  }
  flush(true);
  out.close();
  if (!out) throw std::runtime_error("cannot write '" + path + "': write failed");
}

}  // namespace scallop
