#include "nodes/post/setup_programs.h"

#include <Eigen/LU>
#include <numeric>
#include <stdexcept>

namespace scallop {

std::vector<SetupSpec> setups_from_report(const nlohmann::json& report, std::size_t patches) {
  if (!report.contains("setups") || !report["setups"].is_array() || report["setups"].empty())
    throw std::invalid_argument("the setups report has no setups");
  std::vector<SetupSpec> out;
  for (const auto& s : report["setups"]) {
    SetupSpec spec;
    spec.name = s.value("name", "setup " + std::to_string(out.size() + 1));
    const auto& m = s.value("part_to_machine", nlohmann::json());
    if (!m.is_array() || m.size() != 3)
      throw std::invalid_argument("setup '" + spec.name + "': part_to_machine is not 3 rows [R|t]");
    for (int r = 0; r < 3; ++r) {
      if (!m[r].is_array() || m[r].size() != 4)
        throw std::invalid_argument("setup '" + spec.name + "': part_to_machine is not 3 rows [R|t]");
      for (int c = 0; c < 3; ++c) spec.rotation(r, c) = m[r][c].get<double>();
      spec.translation[r] = m[r][3].get<double>();
    }
    const Eigen::Matrix3d RtR = spec.rotation.transpose() * spec.rotation;
    if ((RtR - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 || spec.rotation.determinant() < 0)
      throw std::invalid_argument("setup '" + spec.name + "': part_to_machine's R is not a rotation");
    for (const auto& p : s.value("patches", nlohmann::json::array())) {
      const auto k = p.get<std::size_t>();
      if (k >= patches)
        throw std::invalid_argument("setup '" + spec.name + "': patch " + std::to_string(k) + " of " +
                                    std::to_string(patches));
      spec.patches.push_back(k);
    }
    out.push_back(std::move(spec));
  }
  return out;
}

std::vector<SetupProgram> setup_programs(const Toolpath& path, const std::vector<std::size_t>& passes_per_patch,
                                         const std::vector<SetupSpec>& setups,
                                         const std::vector<Eigen::Vector3d>& part, const LinkOptions& link,
                                         const GCodeOptions& gcode) {
  if (std::accumulate(passes_per_patch.begin(), passes_per_patch.end(), std::size_t(0)) != path.passes.size())
    throw std::invalid_argument("the patches' pass counts do not add up to the toolpath's " +
                                std::to_string(path.passes.size()) + " passes");
  std::vector<std::size_t> first(passes_per_patch.size() + 1, 0);
  for (std::size_t p = 0; p < passes_per_patch.size(); ++p) first[p + 1] = first[p] + passes_per_patch[p];

  std::vector<SetupProgram> out;
  for (const SetupSpec& s : setups) {
    Toolpath local;
    local.tool_radius = path.tool_radius;
    local.scallop_height = path.scallop_height;
    local.chord_error = path.chord_error;
    local.pattern = path.pattern;
    for (std::size_t p : s.patches) {
      if (p >= passes_per_patch.size())
        throw std::invalid_argument("setup '" + s.name + "': patch " + std::to_string(p) + " has no passes");
      for (std::size_t k = first[p]; k < first[p + 1]; ++k) {
        ToolpathPass pass = path.passes[k];
        for (auto& c : pass.contact) c = s.rotation * c + s.translation;
        for (auto& n : pass.normal) n = s.rotation * n;
        local.passes.push_back(std::move(pass));
      }
    }
    if (local.passes.empty()) continue;
    std::vector<Eigen::Vector3d> surface(part.size());
    for (std::size_t i = 0; i < part.size(); ++i) surface[i] = s.rotation * part[i] + s.translation;
    const LinkedPath linked = link_passes(local, surface, link);
    SetupProgram prog;
    prog.name = s.name;
    prog.file = "setup_" + std::to_string(out.size() + 1) + ".ngc";
    GCodeOptions g = gcode;
    g.graph_name = gcode.graph_name.empty() ? "setup " + s.name : gcode.graph_name + ", setup " + s.name;
    prog.gcode = write_gcode(linked, g);
    prog.passes = local.passes.size();
    prog.moves = linked.moves.size();
    prog.clearance_z = linked.clearance_z;
    out.push_back(std::move(prog));
  }
  return out;
}

nlohmann::json setups_file(const std::vector<SetupProgram>& programs, const std::vector<SetupSpec>& setups) {
  nlohmann::json list = nlohmann::json::array();
  for (const SetupProgram& p : programs) {
    for (const SetupSpec& s : setups) {
      if (s.name != p.name) continue;
      nlohmann::json m = nlohmann::json::array();
      for (int r = 0; r < 3; ++r)
        m.push_back({s.rotation(r, 0), s.rotation(r, 1), s.rotation(r, 2), s.translation[r]});
      list.push_back({{"name", p.name}, {"gcode", p.file}, {"part_to_machine", m}});
      break;
    }
  }
  return {{"format", "scallop-setups/1"}, {"units", "mm"}, {"setups", list}};
}

}  // namespace scallop
