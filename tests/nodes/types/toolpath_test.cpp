#include "nodes/types/toolpath.h"

#include <gtest/gtest.h>

#include <cstring>
#include <new>
#include <sstream>

namespace scallop {
namespace {

std::string bytes_of(const Value& v) {
  std::ostringstream out;
  v.serialize(out);
  return out.str();
}

// A linked path whose moves were built in memory first filled with `fill`: what lies in a Move's
// padding after its kind must not reach the bytes.
LinkedPath linked_from_memory_filled_with(unsigned char fill) {
  LinkedPath l;
  l.tool_radius = 4;
  l.scallop_height = 0.05;
  l.chord_error = 0.01;
  l.clearance_z = 12.5;
  alignas(Move) unsigned char raw[3 * sizeof(Move)];
  std::memset(raw, fill, sizeof raw);
  Move* m = reinterpret_cast<Move*>(raw);
  const Move wanted[3] = {{MoveKind::Rapid, {0, 0, 12.5}}, {MoveKind::Plunge, {0, 0, 1}}, {MoveKind::Feed, {3, 0, 1.25}}};
  for (int i = 0; i < 3; ++i) {
    new (&m[i]) Move;
    m[i].kind = wanted[i].kind;
    m[i].tip = wanted[i].tip;
    l.moves.push_back(m[i]);
  }
  return l;
}

TEST(LinkedPathValue, BytesDependOnTheMovesOnlyAndReadBack) {
  const LinkedPath a = linked_from_memory_filled_with(0x00), b = linked_from_memory_filled_with(0xA5);
  EXPECT_EQ(bytes_of(a), bytes_of(b));
  std::istringstream in(bytes_of(a));
  const auto back = std::static_pointer_cast<const LinkedPath>(LinkedPath::deserialize(in));
  ASSERT_EQ(back->moves.size(), 3u);
  EXPECT_EQ(back->clearance_z, 12.5);
  EXPECT_EQ(back->moves[1].kind, MoveKind::Plunge);
  EXPECT_EQ(back->moves[2].tip, Eigen::Vector3d(3, 0, 1.25));
  // 4 numbers, then the kinds (count + 1 byte each), then the tips (count + 24 bytes each)
  EXPECT_EQ(bytes_of(a).size(), 4 * 8 + (8 + 3) + (8 + 3 * 24));
}

TEST(LinkedPathValue, AnUnknownMoveKindIsRefused) {
  std::string bytes = bytes_of(linked_from_memory_filled_with(0));
  bytes[4 * 8 + 8 + 1] = 7;  // the second move's kind
  std::istringstream in(bytes);
  try {
    LinkedPath::deserialize(in);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "corrupt linked path: move kind 7");
  }
}

TEST(SetupPathsValue, SetupsAndUnreachedPlacesReadBack) {
  SetupPaths v;
  SetupPath& s = v.setups.emplace_back();
  s.name = "1: +z", s.file = "setup_1.ngc";
  s.translation = Eigen::Vector3d(1, 2, 3);
  s.path = linked_from_memory_filled_with(0x00);
  v.unreached_at = {Eigen::Vector3d(-0.8, 1650.3, 96.47), Eigen::Vector3d(1, 2, 3)};
  v.unreached_area = 0.141;
  v.unreached_by_any_direction = true;
  std::istringstream in(bytes_of(v));
  const auto back = std::dynamic_pointer_cast<const SetupPaths>(SetupPaths::deserialize(in));
  ASSERT_TRUE(back);
  ASSERT_EQ(back->setups.size(), 1u);
  EXPECT_EQ(back->setups[0].name, "1: +z");
  EXPECT_EQ(back->setups[0].translation, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(back->setups[0].path.moves.size(), 3u);
  EXPECT_EQ(back->unreached_at, v.unreached_at);
  EXPECT_EQ(back->unreached_area, 0.141);
  EXPECT_TRUE(back->unreached_by_any_direction);
}

}  // namespace
}  // namespace scallop
