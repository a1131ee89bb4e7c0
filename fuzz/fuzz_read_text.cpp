// libFuzzer target: the text-column reader, as .xyz/.csv/.txt (columns 4-6 are normals) and as
// .pts (they are intensity and colour).
#include "fuzz/read_fuzz_support.h"
#include "nodes/io/text_cloud_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = scallop::fuzz::temp_path(".xyz");
  scallop::fuzz::write_file(path, data, size);
  scallop::fuzz::read_checked(path, [](const std::string& p) { return scallop::read_cloud(p); });
  scallop::fuzz::read_checked(path, [](const std::string& p) { return scallop::read_text_cloud(p, false); });
  return 0;
}
