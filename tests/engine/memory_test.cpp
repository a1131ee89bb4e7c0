#include "engine/memory.h"

#include <gtest/gtest.h>

#include <sys/mman.h>

#include <cstring>

namespace scallop {
namespace {

TEST(Memory, ThePeakSeesA256MiBBlockAndARestartForgetsItOnceFreed) {
  constexpr std::size_t kBlock = 256u << 20;
  const std::size_t before = peak_resident_bytes();
  ASSERT_GT(before, 0u);  // Linux: /proc/self/status has VmHWM
  {
    // Straight from the kernel: a freed heap block can stay resident (AddressSanitizer keeps
    // freed memory in quarantine).
    void* block = mmap(nullptr, kBlock, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    ASSERT_NE(block, MAP_FAILED);
    std::memset(block, 1, kBlock);  // resident only once touched
    EXPECT_GE(peak_resident_bytes(), kBlock);
    munmap(block, kBlock);
  }
  if (!reset_peak_resident()) GTEST_SKIP() << "this kernel does not allow resetting VmHWM";
  // what the process held before the block, not 0 (the ASan build of the tests holds about
  // 280 MiB from the start)
  EXPECT_LT(peak_resident_bytes(), before + kBlock / 2);
}

}  // namespace
}  // namespace scallop
