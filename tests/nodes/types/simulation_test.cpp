#include "nodes/types/simulation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "engine/node.h"
#include "nodes/all_nodes.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

Simulation two_samples() {
  Simulation s;
  s.report = {{"pass", false}, {"scallop_max", 0.061}};
  s.spacing = 0.1;
  s.scallop_limit = 0.05;
  s.gouge_tolerance = 0.01;
  s.outline = {{0, 0}, {1, 0}, {1, 1}};
  s.samples = {{1, 2, 3, 0.01, 0.04, 0, true}, {4, 5, 6, 0, NAN, 0.002, false}};
  return s;
}

std::string bytes_of(const Value& v) {
  std::ostringstream out;
  v.serialize(out);
  return out.str();
}

TEST(Simulation, CacheFormRoundTripsEveryField) {
  const Simulation s = two_samples();
  std::stringstream in(bytes_of(s));
  auto back = std::dynamic_pointer_cast<const Simulation>(Simulation::deserialize(in));
  ASSERT_TRUE(back);
  EXPECT_EQ(back->report, s.report);
  EXPECT_EQ(std::vector<double>({back->spacing, back->scallop_limit, back->gouge_tolerance}),
            std::vector<double>({0.1, 0.05, 0.01}));
  EXPECT_EQ(back->outline, s.outline);
  ASSERT_EQ(back->samples.size(), 2u);
  const SimSample& a = back->samples[0];
  EXPECT_EQ(std::vector<double>({a.x, a.y, a.z, a.weight, a.scallop, a.gouge}),
            std::vector<double>({1, 2, 3, 0.01, 0.04, 0}));
  EXPECT_TRUE(a.interior);
  EXPECT_TRUE(std::isnan(back->samples[1].scallop));  // uncut
  EXPECT_EQ(back->samples[1].gouge, 0.002);
  EXPECT_FALSE(back->samples[1].interior);
  EXPECT_TRUE(back->face.empty());
  // the same bytes again: the cache form has no padding that could differ
  EXPECT_EQ(bytes_of(*back), bytes_of(s));
}

TEST(Simulation, APartsSimulationKeepsTheFaceOfEachSample) {
  Simulation s = two_samples();
  s.face = {7, 3};
  std::stringstream in(bytes_of(s));
  auto back = std::dynamic_pointer_cast<const Simulation>(Simulation::deserialize(in));
  EXPECT_EQ(back->face, std::vector<std::uint32_t>({7, 3}));
  s.face = {7};
  std::stringstream bad(bytes_of(s));
  EXPECT_EQ(test::error_of<std::runtime_error>([&] { Simulation::deserialize(bad); }),
            "corrupt simulation: columns of different lengths");
}

TEST(Simulation, ATruncatedCacheEntryIsRefused) {
  const std::string b = bytes_of(two_samples());
  std::stringstream in(b.substr(0, b.size() - 1));
  EXPECT_THROW(Simulation::deserialize(in), std::runtime_error);
}

TEST(Simulation, ColumnsOfDifferentLengthsAreRefused) {
  std::stringstream in;
  bin::write_string(in, "{}");
  for (int i = 0; i < 3; ++i) bin::write_f64(in, 0.1);  // spacing, scallop_limit, gouge_tolerance
  bin::write_vector(in, std::vector<Eigen::Vector2d>{});
  for (std::size_t n : {2, 2, 2, 2, 1, 2}) bin::write_vector(in, std::vector<double>(n, 0.0));  // scallop short
  bin::write_vector(in, std::vector<std::uint8_t>(2, 1));
  EXPECT_EQ(test::error_of<std::runtime_error>([&] { Simulation::deserialize(in); }),
            "corrupt simulation: columns of different lengths");
}

TEST(Simulation, IsARegisteredValueTypeWithAFormatVersion) {
  const ValueType* t = builtin_registry().values().find("Simulation");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->extension, "bin");
  EXPECT_EQ(t->format, 2);
  EXPECT_FALSE(t->description.empty());
  std::stringstream in(bytes_of(two_samples()));
  EXPECT_EQ(t->deserialize(in)->type_name(), "Simulation");
}

}  // namespace
}  // namespace scallop
