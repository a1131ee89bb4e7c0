#include "engine/file_ref.h"

#include <filesystem>

#include "engine/hash.h"

namespace scallop {

void FileRef::serialize(std::ostream& out) const {
  bin::write_string(out, path);
  bin::write_string(out, content_hash);
}

ValuePtr FileRef::deserialize(std::istream& in) {
  auto f = std::make_shared<FileRef>();
  f->path = bin::read_string(in);
  f->content_hash = bin::read_string(in);
  return f;
}

FileRef FileRef::open(const std::string& path) {
  if (!std::filesystem::exists(path)) throw std::runtime_error("file '" + path + "' does not exist");
  if (std::filesystem::is_directory(path)) throw std::runtime_error("'" + path + "' is a directory, not a file");
  FileRef f;
  f.path = path;
  f.content_hash = hash_file(path);
  return f;
}

}  // namespace scallop
