#include "nodes/types/toolpath.h"

#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace scallop {

void Toolpath::serialize(std::ostream& out) const {
  bin::write_f64(out, tool_radius);
  bin::write_f64(out, scallop_height);
  bin::write_f64(out, chord_error);
  bin::write_string(out, pattern);
  bin::write_u64(out, passes.size());
  for (const auto& p : passes) {
    bin::write_vector(out, p.contact);
    bin::write_vector(out, p.normal);
    bin::write_vector(out, p.uv);
  }
}

ValuePtr Toolpath::deserialize(std::istream& in) {
  auto t = std::make_shared<Toolpath>();
  t->tool_radius = bin::read_f64(in);
  t->scallop_height = bin::read_f64(in);
  t->chord_error = bin::read_f64(in);
  t->pattern = bin::read_string(in);
  std::uint64_t n = bin::read_u64(in);
  if (n > (1u << 30)) throw std::runtime_error("corrupt pass count");
  t->passes.resize(n);
  for (auto& p : t->passes) {
    p.contact = bin::read_vector<Eigen::Vector3d>(in);
    p.normal = bin::read_vector<Eigen::Vector3d>(in);
    p.uv = bin::read_vector<Eigen::Vector2d>(in);
  }
  return t;
}

void Toolpath::write_file(const std::string& path) const {
  nlohmann::json j;
  j["tool_radius"] = tool_radius;
  j["scallop_height"] = scallop_height;
  j["chord_error"] = chord_error;
  j["pattern"] = pattern;
  j["passes"] = nlohmann::json::array();
  for (const auto& p : passes) {
    nlohmann::json pts = nlohmann::json::array();
    for (std::size_t i = 0; i < p.contact.size(); ++i) {
      Eigen::Vector3d t = tip(p.contact[i], p.normal[i]);
      pts.push_back({{"contact", {p.contact[i].x(), p.contact[i].y(), p.contact[i].z()}},
                     {"normal", {p.normal[i].x(), p.normal[i].y(), p.normal[i].z()}},
                     {"tip", {t.x(), t.y(), t.z()}}});
    }
    j["passes"].push_back(pts);
  }
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  out << j.dump(1) << "\n";
}

void LinkedPath::serialize(std::ostream& out) const {
  bin::write_f64(out, tool_radius);
  bin::write_f64(out, scallop_height);
  bin::write_f64(out, chord_error);
  bin::write_f64(out, clearance_z);
  // Kinds and tips in columns: a Move has padding bytes after its kind, which written whole
  // would put whatever memory held there into the file (cache entries differed run to run).
  std::vector<std::uint8_t> kinds(moves.size());
  std::vector<Eigen::Vector3d> tips(moves.size());
  for (std::size_t i = 0; i < moves.size(); ++i) kinds[i] = static_cast<std::uint8_t>(moves[i].kind), tips[i] = moves[i].tip;
  bin::write_vector(out, kinds);
  bin::write_vector(out, tips);
}

ValuePtr LinkedPath::deserialize(std::istream& in) {
  auto l = std::make_shared<LinkedPath>();
  l->tool_radius = bin::read_f64(in);
  l->scallop_height = bin::read_f64(in);
  l->chord_error = bin::read_f64(in);
  l->clearance_z = bin::read_f64(in);
  const std::vector<std::uint8_t> kinds = bin::read_vector<std::uint8_t>(in);
  const std::vector<Eigen::Vector3d> tips = bin::read_vector<Eigen::Vector3d>(in);
  if (kinds.size() != tips.size()) throw std::runtime_error("corrupt linked path: " + std::to_string(kinds.size()) +
                                                            " move kinds for " + std::to_string(tips.size()) + " tips");
  l->moves.resize(kinds.size());
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    if (kinds[i] > static_cast<std::uint8_t>(MoveKind::Plunge))
      throw std::runtime_error("corrupt linked path: move kind " + std::to_string(kinds[i]));
    l->moves[i] = {static_cast<MoveKind>(kinds[i]), tips[i]};
  }
  return l;
}

void SetupPaths::serialize(std::ostream& out) const {
  bin::write_u64(out, setups.size());
  for (const SetupPath& s : setups) {
    bin::write_string(out, s.name);
    bin::write_string(out, s.file);
    for (int k = 0; k < 9; ++k) bin::write_f64(out, s.rotation.data()[k]);
    for (int k = 0; k < 3; ++k) bin::write_f64(out, s.translation[k]);
    s.path.serialize(out);
  }
  bin::write_u64(out, unreached_at.size());
  for (const Eigen::Vector3d& p : unreached_at)
    for (int k = 0; k < 3; ++k) bin::write_f64(out, p[k]);
  bin::write_f64(out, unreached_area);
  bin::write_u64(out, unreached_by_any_direction ? 1 : 0);
}

ValuePtr SetupPaths::deserialize(std::istream& in) {
  auto v = std::make_shared<SetupPaths>();
  const std::uint64_t n = bin::read_u64(in);
  if (n > (1u << 20)) throw std::runtime_error("corrupt setup paths: " + std::to_string(n) + " setups");
  for (std::uint64_t i = 0; i < n; ++i) {
    SetupPath s;
    s.name = bin::read_string(in);
    s.file = bin::read_string(in);
    for (int k = 0; k < 9; ++k) s.rotation.data()[k] = bin::read_f64(in);
    for (int k = 0; k < 3; ++k) s.translation[k] = bin::read_f64(in);
    s.path = *std::static_pointer_cast<const LinkedPath>(LinkedPath::deserialize(in));
    v->setups.push_back(std::move(s));
  }
  const std::uint64_t m = bin::read_u64(in);
  if (m > (1u << 20)) throw std::runtime_error("corrupt setup paths: " + std::to_string(m) + " unreached places");
  for (std::uint64_t i = 0; i < m; ++i) {
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) p[k] = bin::read_f64(in);
    v->unreached_at.push_back(p);
  }
  v->unreached_area = bin::read_f64(in);
  v->unreached_by_any_direction = bin::read_u64(in) != 0;
  return v;
}

void Toolpath::check_passes() const {
  if (!(tool_radius > 0)) throw std::invalid_argument("tool radius must be > 0");
  bool any = false;
  for (const auto& p : passes) {
    if (p.normal.size() != p.contact.size())
      throw std::invalid_argument("a pass has " + std::to_string(p.contact.size()) + " points but " +
                                  std::to_string(p.normal.size()) + " normals");
    for (std::size_t i = 0; i < p.contact.size(); ++i)
      if (!p.contact[i].allFinite() || !p.normal[i].allFinite())
        throw std::invalid_argument("the tool path has a non-finite point");
    any |= !p.contact.empty();
  }
  if (!any) throw std::invalid_argument("the tool path has no points");
}

}  // namespace scallop
