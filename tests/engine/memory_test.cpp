#include "engine/memory.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

namespace scallop {
namespace {

TEST(Memory, ThePeakSeesA256MiBBlockAndARestartForgetsItOnceFreed) {
  constexpr std::size_t kBlock = 256u << 20;
  const std::size_t before = peak_resident_bytes();
  ASSERT_GT(before, 0u);  // Linux: /proc/self/status has VmHWM
  {
    std::unique_ptr<char[]> block(new char[kBlock]);
    std::memset(block.get(), 1, kBlock);  // resident only once touched
    EXPECT_GE(peak_resident_bytes(), kBlock);
  }
  if (!reset_peak_resident()) GTEST_SKIP() << "this kernel does not allow resetting VmHWM";
  EXPECT_LT(peak_resident_bytes(), kBlock);
}

}  // namespace
}  // namespace scallop
