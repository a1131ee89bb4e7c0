// Tool path export: the passes as JSON or CSV for other tools (CAM viewers, spreadsheets).
#pragma once

#include <string>

#include "nodes/types/toolpath.h"

namespace scallop {

// JSON: {"tool_radius", "scallop_height", "chord_error", "pattern", "passes": [[{"contact":
// [x,y,z], "normal": [x,y,z], "tip": [x,y,z] (, "uv": [u,v])}, ...], ...]} (mm).
std::string toolpath_json(const Toolpath& path);
// CSV with a header line: pass,index,cx,cy,cz,nx,ny,nz,tx,ty,tz (contact, normal, tool tip; mm),
// 17 significant digits.
std::string toolpath_csv(const Toolpath& path);
// Writes one of the two to `file`; format "json" or "csv". Throws std::invalid_argument for an
// unknown format, std::runtime_error when the file cannot be written.
void write_toolpath(const Toolpath& path, const std::string& file, const std::string& format);

}  // namespace scallop
