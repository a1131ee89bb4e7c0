#include "nodes/io/write_toolpath.h"

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace scallop {

std::string toolpath_json(const Toolpath& path) {
  nlohmann::json j;
  j["tool_radius"] = path.tool_radius;
  j["scallop_height"] = path.scallop_height;
  j["chord_error"] = path.chord_error;
  j["pattern"] = path.pattern;
  j["passes"] = nlohmann::json::array();
  for (const auto& p : path.passes) {
    if (p.normal.size() != p.contact.size()) throw std::invalid_argument("a pass has fewer normals than points");
    nlohmann::json pts = nlohmann::json::array();
    for (std::size_t i = 0; i < p.contact.size(); ++i) {
      Eigen::Vector3d t = path.tip(p.contact[i], p.normal[i]);
      nlohmann::json q = {{"contact", {p.contact[i].x(), p.contact[i].y(), p.contact[i].z()}},
                          {"normal", {p.normal[i].x(), p.normal[i].y(), p.normal[i].z()}},
                          {"tip", {t.x(), t.y(), t.z()}}};
      if (i < p.uv.size()) q["uv"] = {p.uv[i].x(), p.uv[i].y()};
      pts.push_back(std::move(q));
    }
    j["passes"].push_back(std::move(pts));
  }
  return j.dump(1) + "\n";
}

std::string toolpath_csv(const Toolpath& path) {
  std::string out = "pass,index,cx,cy,cz,nx,ny,nz,tx,ty,tz\n";
  char buf[512];
  for (std::size_t k = 0; k < path.passes.size(); ++k) {
    const auto& p = path.passes[k];
    if (p.normal.size() != p.contact.size()) throw std::invalid_argument("a pass has fewer normals than points");
    for (std::size_t i = 0; i < p.contact.size(); ++i) {
      const Eigen::Vector3d &c = p.contact[i], &n = p.normal[i];
      Eigen::Vector3d t = path.tip(c, n);
      std::snprintf(buf, sizeof buf, "%zu,%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", k, i, c.x(),
                    c.y(), c.z(), n.x(), n.y(), n.z(), t.x(), t.y(), t.z());
      out += buf;
    }
  }
  return out;
}

void write_toolpath(const Toolpath& path, const std::string& file, const std::string& format) {
  std::string text;
  if (format == "json")
    text = toolpath_json(path);
  else if (format == "csv")
    text = toolpath_csv(path);
  else
    throw std::invalid_argument("unknown tool path format '" + format + "' (json or csv)");
  std::ofstream out(file, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write '" + file + "'");
  out << text;
  if (!out) throw std::runtime_error("error writing '" + file + "'");
}

}  // namespace scallop
