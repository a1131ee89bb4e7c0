// What io.read_cloud and io.read_mesh share: reading the node's input file as bad input when
// it fails.
#pragma once

#include <string>

#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/read_cloud.h"

namespace scallop::io {

// read(path, scale) on the node's 'file' input and 'scale' parameter, and its path. A file the
// reader refuses (CloudReadError) is bad input: InputError with its message, so that `scallop`
// exits 2, as for a missing file.
template <class Read>
auto read_input(const NodeContext& ctx, Read&& read, std::string& path) {
  path = ctx.input<FileRef>("file")->path;
  try {
    return read(path, ctx.number("scale"));
  } catch (const CloudReadError& e) {
    throw InputError(e.what());
  }
}

}  // namespace scallop::io
