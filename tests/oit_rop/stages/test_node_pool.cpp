// NodePool: node i at base + i x node_bytes; the partial node writes merge
// into whole bursts, written by the node that completes one; a flush writes
// the rest. Values derived by hand.
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "oit_rop/stages/NodePool.hpp"

using namespace oit::rop;

namespace {

using Writes = std::vector<std::pair<uint64_t, uint64_t>>;

// 12 B nodes (rgba8t8z32), 64 B bursts, base 4096: nodes 0..4 end at byte 60
// of the first burst (no write); node 5 spans bytes 60..72 and completes it
// ([4096, 4160)); node 10 ends at 132 and completes the second ([4160, 4224));
// 16 nodes end at 192 = 3 bursts, node 15 writes the third. A flush then has
// nothing; two more nodes and a flush write [4288, 4312).
TEST(NodePool, ConsecutiveNodesFormWholeBurstsWrittenByTheNodeThatCompletesThem) {
  NodePool p(4096, 12, 64);
  EXPECT_EQ(p.address(0), 4096u);
  EXPECT_EQ(p.address(5), 4096u + 60);
  Writes w;
  for (int i = 0; i < 16; ++i) {
    const NodePool::Range r = p.append();
    if (r.bytes()) w.push_back({r.begin, r.end});
    EXPECT_EQ(r.bytes() != 0, i == 5 || i == 10 || i == 15) << "node " << i;
  }
  EXPECT_EQ(w, (Writes{{4096, 4160}, {4160, 4224}, {4224, 4288}}));
  EXPECT_EQ(p.flush().bytes(), 0u);
  EXPECT_EQ(p.append().bytes(), 0u);
  EXPECT_EQ(p.append().bytes(), 0u);
  const NodePool::Range f = p.flush();
  EXPECT_EQ(f.begin, 4288u);
  EXPECT_EQ(f.end, 4288u + 24);
  EXPECT_EQ(p.nodes(), 18u);
  // After a flush the next burst boundary is still the pool's: node 21 ends at
  // 4096 + 264, past 4352, so it writes [4312, 4352).
  EXPECT_EQ(p.append().bytes(), 0u);  // node 18 ends at 4096 + 228
  EXPECT_EQ(p.append().bytes(), 0u);  // 240
  EXPECT_EQ(p.append().bytes(), 0u);  // 252
  const NodePool::Range r = p.append();  // node 21: 264
  EXPECT_EQ(r.begin, 4312u);
  EXPECT_EQ(r.end, 4352u);
}

}  // namespace
