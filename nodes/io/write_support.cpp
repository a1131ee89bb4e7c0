#include "nodes/io/write_support.h"

#include <stdexcept>

#include "engine/output_path.h"

namespace scallop::io {

FileRef write_output_file(const NodeContext& ctx, const std::string& param,
                          const std::function<void(const std::string& path)>& write) {
  try {
    const std::string path = output_file(ctx.output_dir(), param);
    write(path);
    return FileRef::open(path);
  } catch (const NodeError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw NodeError("parameter 'path': " + std::string(e.what()));
  } catch (const std::runtime_error& e) {
    throw NodeError(e.what());
  }
}

}  // namespace scallop::io
