// Fitted B-spline patches as a STEP file (io.write_step), with OpenCASCADE behind this header.
#pragma once

#include <cstddef>
#include <string>

#include "nodes/types/surfaces.h"

namespace scallop {

struct WriteStepOptions {
  bool sew = true;                 // sew the faces along shared borders into shells
  double sewing_tolerance = 0.01;  // mm: borders closer than this are sewn into one edge
};

// What a STEP file holds, as OpenCASCADE reads it back.
struct StepSummary {
  std::size_t file_faces = 0;  // ADVANCED_FACE entities in the file: what was written
  // After the reader's shape healing, which may split a face whose patch pinches or twists (the
  // fandisk's noisy cloud gave a 2 x 19-pole sliver whose edges cross near its tip: 3 faces).
  std::size_t faces = 0, shells = 0, free_edges = 0;  // free: on one face only (outlines, gaps)
  std::size_t bspline_faces = 0;                      // faces whose surface is a B-spline
};

// Writes every patch of `surfaces` as a trimmed-to-its-domain B-spline face (AP214, mm) to `path`;
// throws std::runtime_error naming the patch OpenCASCADE refuses, or the file it cannot write.
void write_step(const Surfaces& surfaces, const std::string& path, const WriteStepOptions& options);

// Reads `path` back with OpenCASCADE's STEP reader; throws std::runtime_error when it cannot.
StepSummary read_step_summary(const std::string& path);

}  // namespace scallop
