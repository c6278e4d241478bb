// The memory checks (base/memory.h): the memory available, a size no machine has refused with
// what it would need, saturating sizes, and sizes as text.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "gwnrt/base/memory.h"

namespace gwnrt {
namespace {

TEST(Memory, AvailableAndChecks) {
  const uint64_t available = available_memory_bytes();
  EXPECT_GT(available, 0u);
  // A size no machine has is refused, saying what it would need and what there is.
  const Status s = check_memory(saturating_product(uint64_t(1) << 40, uint64_t(1) << 40), "the test's array");
  if (available != kUnknownMemory) {
    EXPECT_EQ(s.code(), StatusCode::kOutOfMemory);
    EXPECT_EQ(s.message().rfind("the test's array would need 16 EiB or more of memory, more than the ", 0), 0u)
        << s.message();
  }
  EXPECT_TRUE(check_memory(1, "a byte").ok());
  EXPECT_EQ(saturating_product(uint64_t(1) << 32, uint64_t(1) << 32), std::numeric_limits<uint64_t>::max());
  EXPECT_EQ(saturating_product(uint64_t(1) << 31, uint64_t(1) << 32), uint64_t(1) << 63);
  EXPECT_EQ(saturating_sum(std::numeric_limits<uint64_t>::max(), 1), std::numeric_limits<uint64_t>::max());
  EXPECT_EQ(memory_size_text(0), "0 B");
  EXPECT_EQ(memory_size_text(1023), "1023 B");
  EXPECT_EQ(memory_size_text(1536), "1.5 KiB");
  EXPECT_EQ(memory_size_text(uint64_t(3) << 30), "3.0 GiB");
  EXPECT_EQ(memory_size_text(uint64_t(5) << 40), "5.0 TiB");
}

}  // namespace
}  // namespace gwnrt
