#include "nodes/io/write_support.h"

#include <filesystem>
#include <fstream>
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

FileRef write_output_files(const NodeContext& ctx, const std::string& param, const std::string& text,
                           const std::vector<std::pair<std::string, std::string>>& beside) {
  auto write = [](const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out << bytes;
    if (!out) throw std::runtime_error("cannot write '" + path.string() + "'");
  };
  return write_output_file(ctx, param, [&](const std::string& written) {
    const std::filesystem::path folder = std::filesystem::path(written).parent_path();
    for (const auto& [name, bytes] : beside) write(folder / name, bytes);
    write(written, text);
  });
}

}  // namespace scallop::io
