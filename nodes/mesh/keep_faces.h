// The part of a mesh made of some of its faces, with only the vertices they use.
#pragma once

#include <cstdint>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

// mesh  any polygon mesh
// keep  #F, true for the faces to keep
// Returns the kept faces in their order, on the vertices they use renumbered in their order
// (new_index[v] receives each old vertex's new index, or UINT32_MAX for a vertex no kept face
// uses, when given); vertex normals and face labels carried when the mesh has them, feature
// edges carried when both ends are kept and they are still an edge of a kept face.
Mesh keep_faces(const Mesh& mesh, const std::vector<bool>& keep, std::vector<std::uint32_t>* new_index = nullptr);

}  // namespace scallop
