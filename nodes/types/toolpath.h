// Tool path values: planned passes on the surface, and the linked machine program.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "engine/value.h"

namespace scallop {

// One pass: cutter-contact points on the surface with their upward unit normals, in cutting order.
// uv holds each point's parameter-domain position when the planner has one (else empty).
struct ToolpathPass {
  std::vector<Eigen::Vector3d> contact;
  std::vector<Eigen::Vector3d> normal;
  std::vector<Eigen::Vector2d> uv;
};

// Passes of a ball-end cutter of radius tool_radius. The ball centre (cutter location) of a
// contact point c with normal n is c + r·n; the tool tip (G-code XYZ) is the centre − r·ẑ.
struct Toolpath final : Value {
  double tool_radius = 0;
  double scallop_height = 0;
  double chord_error = 0;
  std::string pattern;  // "zigzag", "contour", ...
  std::vector<ToolpathPass> passes;

  Eigen::Vector3d centre(const Eigen::Vector3d& contact, const Eigen::Vector3d& normal) const {
    return contact + tool_radius * normal;
  }
  Eigen::Vector3d tip(const Eigen::Vector3d& contact, const Eigen::Vector3d& normal) const {
    return centre(contact, normal) - Eigen::Vector3d(0, 0, tool_radius);
  }

  // Throws std::invalid_argument for r <= 0, a pass whose normals do not match its points, a
  // non-finite point or normal, or no point at all: what every consumer of passes needs.
  void check_passes() const;
  std::string type_name() const override { return "Toolpath"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  // JSON: tool, tolerances and passes (contact, normal, tip per point).
  void write_file(const std::string& path) const override;
};

// A machine program before it is written in a dialect: tool-tip positions with move kinds.
enum class MoveKind : int { Rapid = 0, Feed = 1, Plunge = 2 };
struct Move {
  MoveKind kind;
  Eigen::Vector3d tip;
};
struct LinkedPath final : Value {
  double tool_radius = 0;
  double scallop_height = 0;
  double chord_error = 0;
  double clearance_z = 0;  // the safe plane rapids travel in
  std::vector<Move> moves;

  std::string type_name() const override { return "LinkedPath"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
};

// The programs of a part machined in several clampings (post.setup_programs): per setup its
// name, its program's file name, the rigid motion part_to_machine (a part point p is at
// rotation p + translation in the machine frame, tool axis +z) and its linked moves in the
// machine frame.
struct SetupPath {
  std::string name;
  std::string file;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  LinkedPath path;
};
struct SetupPaths final : Value {
  std::vector<SetupPath> setups;
  // Places left over the scallop limit where no setup's axis comes down clear of the part (part
  // frame; post.setup_programs' rest search): the certificate names them when it fails there.
  std::vector<Eigen::Vector3d> unreached_at;
  double unreached_area = 0;  // mm²
  bool unreached_by_any_direction = false;  // no clamping direction of the search comes down to them

  std::string type_name() const override { return "SetupPaths"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
};

}  // namespace scallop
