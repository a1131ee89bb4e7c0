// What the io.write_* nodes share: writing a file inside the run's output folder.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "engine/file_ref.h"
#include "engine/node.h"

namespace scallop::io {

// Writes the node's file: `param` (its path parameter's value, relative to the output folder)
// resolved by output_file (engine/output_path.h), `write(path)` called on it, and the written
// file returned. A path that would leave the output folder throws NodeError "parameter 'path':
// <why>"; a folder that cannot be made, or a writer's std::runtime_error, NodeError with its
// message.
FileRef write_output_file(const NodeContext& ctx, const std::string& param,
                          const std::function<void(const std::string& path)>& write);

// The same for a file with others beside it (a setups file and its programs, a setup sheet and
// its pictures): each (name, bytes) of `beside` written into the main file's folder, then the
// main file with `text`. Errors as write_output_file's.
FileRef write_output_files(const NodeContext& ctx, const std::string& param, const std::string& text,
                           const std::vector<std::pair<std::string, std::string>>& beside);

}  // namespace scallop::io
