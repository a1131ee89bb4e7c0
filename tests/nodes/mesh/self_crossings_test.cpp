#include "nodes/mesh/self_crossings.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "tests/nodes/mesh/mesh_test_util.h"

namespace scallop {
namespace {

TEST(SelfCrossings, AClosedMeshThatDoesNotCrossItselfHasNone) {
  for (const Mesh& m : {test::cube_mesh(4, 4.0), test::icosphere(3), test::unit_cube()}) {
    const SelfCrossings c = self_crossings(m);
    EXPECT_TRUE(c.pairs.empty());
    EXPECT_TRUE(c.tangled.empty());
    EXPECT_EQ(c.inward, 0u);
    EXPECT_EQ(c.faces_left_out, 0u);
  }
}

TEST(SelfCrossings, ASpikeThroughTheBottomCrossesItAndNothingElseIsTangled) {
  std::set<std::size_t> spike;
  const Mesh m = test::spiked_cube(spike);
  ASSERT_EQ(spike.size(), 8u);  // the alternating diagonals all meet at the middle vertex
  const SelfCrossings c = self_crossings(m);
  ASSERT_FALSE(c.pairs.empty());
  std::set<std::size_t> crossing;
  for (const auto& [a, b] : c.pairs) {
    EXPECT_LT(a, b);
    // One face of the spike and one of the bottom (z = 0, side 2), which it pierces around (2, 2).
    const bool a_spike = spike.count(a), b_spike = spike.count(b);
    EXPECT_NE(a_spike, b_spike) << a << " " << b;
    const std::size_t bottom = a_spike ? b : a;
    EXPECT_EQ(m.face_label[bottom], 2);
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(m.vertices[m.face(bottom)[k]].x(), 1.0);
      EXPECT_LE(m.vertices[m.face(bottom)[k]].x(), 3.0);
    }
    crossing.insert(a), crossing.insert(b);
  }
  // Every face of the spike crosses the bottom (each runs from z = 4 to z = -1 over (2, 2)).
  for (std::size_t f : spike) EXPECT_TRUE(crossing.count(f)) << f;
  // Tangled: the crossing faces and perhaps bottom faces beside them; never a side or the top.
  EXPECT_TRUE(std::is_sorted(c.tangled.begin(), c.tangled.end()));
  for (std::size_t f : crossing) EXPECT_TRUE(std::binary_search(c.tangled.begin(), c.tangled.end(), f)) << f;
  for (std::size_t f : c.tangled) EXPECT_TRUE(spike.count(f) || m.face_label[f] == 2) << f;
  EXPECT_EQ(c.tangled.size(), crossing.size() + c.inward);
}

TEST(SelfCrossings, AFaceTurnedIntoThePartBesideACrossingIsTangled) {
  // Two closed cubes overlapping in [1, 2]^3, as one mesh: each crosses the other, and the faces of
  // one inside the other face into the part (the point just off them lies inside by the rays).
  Mesh m = test::cube_mesh(4, 2.0);
  const Mesh b = test::cube_mesh(4, 2.0);
  const std::uint32_t base = std::uint32_t(m.vertices.size());
  for (const Eigen::Vector3d& v : b.vertices) m.vertices.push_back(v + Eigen::Vector3d(1, 1, 1));
  for (std::size_t f = 0; f < b.num_faces(); ++f) m.add_face({base + b.face(f)[0], base + b.face(f)[1], base + b.face(f)[2]});
  const SelfCrossings c = self_crossings(m);
  EXPECT_FALSE(c.pairs.empty());
  // A's top (z = 2) square over [1, 2]^2 and B's bottom (z = 1) square over [1, 2]^2 lie inside
  // the other cube and face into it: tangled, crossing or not.
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) centre += m.vertices[m.face(f)[k]] / 3;
    const bool inside_other = (f < b.num_faces()) ? (centre.array() > 1).all() : (centre.array() < 2).all();
    if (inside_other) EXPECT_TRUE(std::binary_search(c.tangled.begin(), c.tangled.end(), f)) << f;
  }
  EXPECT_GT(c.inward, 0u);
}

TEST(SelfCrossings, TheKeepOutSamplesEveryTangledFaceWithinAQuarterOfItsMargin) {
  // The margin is twice the tangled faces' mean edge length; every point of a tangled face lies
  // within a quarter of it of a sample (checked at 2 000 random points of them); nothing tangled,
  // nothing to keep off.
  std::set<std::size_t> spike;
  const Mesh m = test::spiked_cube(spike);
  const SelfCrossings c = self_crossings(m);
  const TangleKeepOut keep = tangle_keep_out(m, c);
  double length = 0;
  for (std::size_t f : c.tangled)
    for (int k = 0; k < 3; ++k) length += (m.vertices[m.face(f)[(k + 1) % 3]] - m.vertices[m.face(f)[k]]).norm();
  EXPECT_NEAR(keep.margin, 2 * length / (3.0 * c.tangled.size()), 1e-12);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int i = 0; i < 2000; ++i) {
    const std::uint32_t* t = m.face(c.tangled[i % c.tangled.size()]);
    double a = unit(rng), b = unit(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Eigen::Vector3d p = m.vertices[t[0]] + a * (m.vertices[t[1]] - m.vertices[t[0]]) + b * (m.vertices[t[2]] - m.vertices[t[0]]);
    double nearest = INFINITY;
    for (const Eigen::Vector3d& q : keep.samples) nearest = std::min(nearest, (q - p).norm());
    EXPECT_LE(nearest, keep.margin / 4) << p.transpose();
  }
  const TangleKeepOut none = tangle_keep_out(test::cube_mesh(4, 4.0), self_crossings(test::cube_mesh(4, 4.0)));
  EXPECT_TRUE(none.samples.empty());
  EXPECT_EQ(none.margin, 0);
}

TEST(SelfCrossings, AMeshGivenAsThePartKeepsNoMarginUnlessOneIsGiven) {
  // margin 0: the faces are the part, nothing kept off; a margin of one's own: its samples as
  // dense as that margin asks (a quarter of it), the rule's tangled faces the same.
  std::set<std::size_t> spike;
  const Mesh m = test::spiked_cube(spike);
  const SelfCrossings c = self_crossings(m);
  ASSERT_FALSE(c.tangled.empty());
  const TangleKeepOut none = tangle_keep_out(m, c, 0.0);
  EXPECT_TRUE(none.samples.empty());
  EXPECT_EQ(none.margin, 0);
  const TangleKeepOut rule = tangle_keep_out(m, c);
  const TangleKeepOut given = tangle_keep_out(m, c, rule.margin / 2);
  EXPECT_EQ(given.margin, rule.margin / 2);
  EXPECT_GT(given.samples.size(), rule.samples.size());
}

TEST(SelfCrossings, PolygonsAreFannedAndFacesThatDoNotFitAreCounted) {
  // The quad cube: no crossing. A third face on one edge (non-manifold): left out, counted.
  Mesh m = test::unit_cube();
  m.vertices.push_back(Eigen::Vector3d(0.5, -1, 0.5));
  m.add_face({0, 1, 8});
  const SelfCrossings c = self_crossings(m);
  EXPECT_EQ(c.faces_left_out, 1u);
  EXPECT_TRUE(c.pairs.empty());
}

}  // namespace
}  // namespace scallop
