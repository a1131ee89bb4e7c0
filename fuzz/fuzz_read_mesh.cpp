// libFuzzer target: the mesh readers, through read_mesh as `io.read_mesh` calls it. The first
// byte picks the format (0 ply, 1 off, 2 obj, 3 stl, by its value mod 4); the rest is the file.
// A reader's contract: a Mesh whose faces, normals, labels and feature edges all index inside it,
// or a CloudReadError.
#include <cstdlib>

#include "fuzz/read_fuzz_support.h"
#include "nodes/io/read_mesh.h"

namespace {

void check_mesh(const scallop::Mesh& m) {
  if (m.face_start.empty() || m.face_start.front() != 0 || m.face_start.back() != m.face_vertices.size())
    std::abort();
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    if (m.face_size(f) < 3) std::abort();
  for (auto v : m.face_vertices)
    if (v >= m.num_vertices()) std::abort();
  for (const auto& e : m.feature_edges)
    if (e[0] >= m.num_vertices() || e[1] >= m.num_vertices()) std::abort();
  if (!m.normals.empty() && m.normals.size() != m.num_vertices()) std::abort();
  if (!m.face_label.empty() && m.face_label.size() != m.num_faces()) std::abort();
  for (const auto& p : m.vertices)
    if (!p.allFinite()) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const ext[4] = {".ply", ".off", ".obj", ".stl"};
  // This process's temp name with the extension of this input's format (each input may pick another).
  const std::string file = scallop::fuzz::temp_path("") + ext[data[0] % 4];
  scallop::fuzz::write_file(file, data + 1, size - 1);
  try {
    check_mesh(scallop::read_mesh(file));
  } catch (const scallop::CloudReadError&) {
  }
  std::remove(file.c_str());
  return 0;
}
