// Files a node writes itself (io.write_cloud, io.write_toolpath): inside the run's output folder.
//
// A graph handed to you must not write elsewhere on your disk, whatever its parameters say: the
// graph's outputs are plain file names (graph.cpp), and a node's file parameter is a relative
// path resolved against the output folder (-o) that cannot leave it.
#pragma once

#include <string>

namespace scallop {

// "" when `path` is a relative path that stays inside the folder it is resolved against (no
// root, no '..' component, no '\' or control characters, not empty, not the folder itself),
// else why not, e.g. "'../x.ply' would be written outside the output folder; expected a relative
// path inside it, without '..'". The path is quoted up to 64 bytes.
std::string output_path_problem(const std::string& path);

// out_dir / path, the file to write (out_dir "" : the working directory). Creates the folders on
// the way. Throws std::invalid_argument with output_path_problem's message for a path that would
// leave out_dir, std::runtime_error naming the folder when it cannot be created.
std::string output_file(const std::string& out_dir, const std::string& path);

}  // namespace scallop
