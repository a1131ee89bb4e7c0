// Content hashes for cache keys (XXH3, 128 bit, as 32 hex digits).
#pragma once

#include <string>
#include <string_view>

namespace scallop {

std::string hash_bytes(std::string_view bytes);
// Streams the file through the hash; throws std::runtime_error if it cannot be read.
std::string hash_file(const std::string& path);

}  // namespace scallop
