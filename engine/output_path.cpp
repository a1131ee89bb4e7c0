#include "engine/output_path.h"

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace scallop {
namespace fs = std::filesystem;

std::string output_path_problem(const std::string& path) {
  const std::string shown = "'" + (path.size() > 64 ? path.substr(0, 60) + "…" : path) + "'";
  const std::string expected = "; expected a relative path inside it, without '..'";
  if (path.empty()) return "the path is empty" + expected;
  for (unsigned char c : path)
    if (c < 0x20 || c == 0x7f || c == '\\')
      return shown + " has a '\\' or a control character" + expected;
  const fs::path p(path);
  if (p.has_root_path()) return shown + " is absolute: it would be written outside the output folder" + expected;
  bool has_name = false;
  for (const auto& part : p) {
    if (part == "..") return shown + " would be written outside the output folder" + expected;
    has_name |= !part.empty() && part != ".";
  }
  if (!has_name) return shown + " names the output folder itself, not a file in it" + expected;
  return "";
}

std::string output_file(const std::string& out_dir, const std::string& path) {
  if (auto problem = output_path_problem(path); !problem.empty()) throw std::invalid_argument(problem);
  const fs::path file = out_dir.empty() ? fs::path(path) : fs::path(out_dir) / path;
  if (file.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(file.parent_path(), ec);
    if (ec) throw std::runtime_error("cannot create folder '" + file.parent_path().string() + "': " + ec.message());
  }
  return file.string();
}

}  // namespace scallop
