// A graph input file: its path and a hash of its content. Source nodes take a File input, so the
// cache keys on what the file holds, never on its name or modification time.
#pragma once

#include <string>

#include "engine/value.h"

namespace scallop {

struct FileRef final : Value {
  std::string path;
  std::string content_hash;  // 32 hex digits (XXH3-128 of the bytes)

  std::string type_name() const override { return "File"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  // The content, not the path: the same bytes under another name hit the same cache entries.
  std::string content_key() const override { return content_hash; }
  // Hashes the file's content; throws std::runtime_error naming the path if it cannot be read.
  static FileRef open(const std::string& path);
};

}  // namespace scallop
