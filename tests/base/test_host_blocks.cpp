// The mesher's host blocks (base/host_blocks.h): large blocks kept and reused while a scope lives,
// cut to size, unmapped when an allocation none fits and when the last scope ends; small ones
// from operator new with their alignment.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "gwnrt/base/host_blocks.h"

namespace gwnrt {
namespace {

constexpr size_t kMiB = size_t(1) << 20;

bool aligned(const void* p, size_t alignment) { return reinterpret_cast<uintptr_t>(p) % alignment == 0; }

TEST(HostBlocks, LargeBlocksAreReusedInsideAScopeAndUnmappedAfter) {
  ASSERT_EQ(kept_host_block_bytes(), 0u);
  {
    HostBlockScope scope;
    void* a = allocate_host_block(5 * kMiB, 16);
    std::memset(a, 1, 5 * kMiB);  // writable to its last byte
    free_host_block(a, 5 * kMiB, 16);
#ifdef __linux__
    EXPECT_TRUE(aligned(a, 2 * kMiB));
    EXPECT_EQ(kept_host_block_bytes(), 6 * kMiB);  // rounded up to whole huge pages
    // A smaller block is cut from the kept one, the rest stays kept.
    void* b = allocate_host_block(3 * kMiB, 16);
    EXPECT_EQ(b, a);
    EXPECT_EQ(kept_host_block_bytes(), 2 * kMiB);
    void* c = allocate_host_block(kMiB + 1, 16);
    EXPECT_EQ(c, static_cast<char*>(a) + 4 * kMiB);
    EXPECT_EQ(kept_host_block_bytes(), 0u);
    std::memset(c, 2, kMiB + 1);
    free_host_block(b, 3 * kMiB, 16);
    free_host_block(c, kMiB + 1, 16);
    EXPECT_EQ(kept_host_block_bytes(), 6 * kMiB);
    // None fits: the kept blocks are unmapped before a new one is mapped.
    void* d = allocate_host_block(9 * kMiB, 16);
    EXPECT_EQ(kept_host_block_bytes(), 0u);
    free_host_block(d, 9 * kMiB, 16);
    EXPECT_EQ(kept_host_block_bytes(), 10 * kMiB);
#endif
  }
  EXPECT_EQ(kept_host_block_bytes(), 0u);
  // Outside every scope a freed block is unmapped at once.
  void* e = allocate_host_block(3 * kMiB, 16);
  free_host_block(e, 3 * kMiB, 16);
  EXPECT_EQ(kept_host_block_bytes(), 0u);
}

TEST(HostBlocks, NestedScopesKeepUntilTheLastEnds) {
  auto outer = std::make_unique<HostBlockScope>();
  {
    HostBlockScope inner;
    void* a = allocate_host_block(2 * kMiB, 64);
    free_host_block(a, 2 * kMiB, 64);
  }
#ifdef __linux__
  EXPECT_EQ(kept_host_block_bytes(), 2 * kMiB);
#endif
  outer.reset();
  EXPECT_EQ(kept_host_block_bytes(), 0u);
}

TEST(HostBlocks, SmallBlocksTakeTheirAlignment) {
  HostBlockScope scope;
  for (size_t alignment : {size_t(4), size_t(16), size_t(64), size_t(4096)}) {
    void* p = allocate_host_block(1000, alignment);
    EXPECT_TRUE(aligned(p, alignment)) << alignment;
    free_host_block(p, 1000, alignment);
  }
  EXPECT_EQ(kept_host_block_bytes(), 0u);  // small blocks are never kept
}

TEST(HostBlocks, AVectorOnThemHoldsItsValues) {
  HostBlockScope scope;
  for (int round = 0; round < 3; ++round) {  // the second and third rounds reuse the first's block
    std::vector<uint32_t, HostBlockAllocator<uint32_t>> v(3 * kMiB / 4 + 17u * round);
    for (size_t i = 0; i < v.size(); ++i) EXPECT_EQ(v[i], 0u) << i;  // value-initialised even when reused
    for (size_t i = 0; i < v.size(); ++i) v[i] = uint32_t(i * 2654435761u);
    for (size_t i = 0; i < v.size(); i += 4099) EXPECT_EQ(v[i], uint32_t(i * 2654435761u));
  }
  EXPECT_THROW((HostBlockAllocator<uint64_t>{}.allocate(SIZE_MAX / 4)), std::bad_array_new_length);
  // A size that rounding up to whole huge pages would wrap is refused, not made small.
  EXPECT_THROW(allocate_host_block(SIZE_MAX - 100, 16), std::bad_alloc);
}

}  // namespace
}  // namespace gwnrt
