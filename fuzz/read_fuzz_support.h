// Shared by the cloud-reader fuzz targets: the readers take a file path (the format is chosen by
// its extension), so each input is written to a temporary file and read back through the same
// entry points the product uses. A reader's contract is: a PointCloud with one normal per point
// or none, or a CloudReadError. Anything else (another exception, a crash, a sanitizer report) is
// a bug, and libFuzzer stops on it.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "nodes/io/read_cloud.h"

namespace scallop::fuzz {

// One file per process (libFuzzer's -jobs/-fork run several), in memory when /dev/shm exists,
// removed at exit.
inline std::string g_temp_path;

inline const std::string& temp_path(const char* ext) {
  if (g_temp_path.empty()) {
    const char* tmp = std::getenv("TMPDIR");
    const char* dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : (tmp ? tmp : "/tmp");
    g_temp_path = std::string(dir) + "/scallop-fuzz-" + std::to_string(getpid()) + ext;
    std::atexit([] { std::remove(g_temp_path.c_str()); });
  }
  return g_temp_path;
}

inline void write_file(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();  // not the reader's fault: stop rather than fuzz nothing
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
}

// The cloud a reader returned must be consistent: normals one per point or none, no uncertainty.
inline void check_cloud(const PointCloud& c) {
  if (!(c.normals.empty() || c.normals.size() == c.points.size())) std::abort();
  if (!c.uncertainty.empty()) std::abort();
}

// Reads `path` with `read`; a CloudReadError is a valid outcome, everything else escapes.
template <class Read>
void read_checked(const std::string& path, Read read) {
  try {
    check_cloud(read(path));
  } catch (const CloudReadError&) {
  }
}

}  // namespace scallop::fuzz
