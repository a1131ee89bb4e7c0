// libFuzzer target: the .obj reader, through read_cloud as `io.read_cloud` calls it.
#include "fuzz/read_fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = scallop::fuzz::temp_path(".obj");
  scallop::fuzz::write_file(path, data, size);
  scallop::fuzz::read_checked(path, [](const std::string& p) { return scallop::read_cloud(p); });
  return 0;
}
