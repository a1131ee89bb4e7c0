// Simulation value: what a cutting simulation (post.simulate) found on the surface, sample by
// sample, with the limits it judged them against and its report (the certificate). Pictures of
// the scallop left (post.render, view "scallop") are drawn from it, so they show the very
// simulation the certificate rests on.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine/value.h"

namespace scallop {

// One surface sample and what the path left there.
struct SimSample {
  double x, y, z;
  double weight;     // surface area it stands for (mm²); 0 for refinement samples
  double scallop;    // NaN when uncut
  double gouge;
  bool interior;
};

struct Simulation final : Value {
  nlohmann::json report;           // the certificate's fields (nodes/post/simulate.h lists them)
  std::vector<SimSample> samples;  // grid samples, then refinement samples
  double spacing = 0;              // grid spacing (mm)
  std::vector<Eigen::Vector2d> outline;  // grid nodes just outside the patch (xy, mm)
  double scallop_limit = 0;        // h (mm): a scallop above 1.01 h fails
  double gouge_tolerance = 0;      // mm: a deeper gouge fails, max(e, 0.001)
  std::vector<std::uint32_t> face;  // a whole part's simulation (post.simulate_part): the mesh
                                    // face of each sample; empty for a patch's

  std::string type_name() const override { return "Simulation"; }
  // Column by column (x, y, z, weight, scallop, gouge, interior, face), so the bytes are the same for
  // the same simulation (a struct's padding would not be).
  void serialize(std::ostream& out) const override;
  // Throws std::runtime_error for a truncated stream or columns of different lengths.
  static ValuePtr deserialize(std::istream& in);
};

}  // namespace scallop
