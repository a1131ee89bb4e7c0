#include "nodes/types/ply_writer.h"

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

}  // namespace scallop
