// The registry refuses what would make two declarations clash or a port unusable.
#include <gtest/gtest.h>

#include "engine/node.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

NodeDecl node(std::string type, std::string in_type = "Number", std::string out_type = "Number") {
  NodeDecl d;
  d.type = std::move(type);
  d.input("a", in_type, "").output("out", out_type, "");
  d.run = [](NodeContext&) {};
  return d;
}

TEST(Registry, RefusesADuplicateNodeType) {
  Registry reg = test::make_test_registry();
  EXPECT_EQ(test::error_of([&] { reg.add(node("test.add")); }), "node type 'test.add' is registered twice");
}

TEST(Registry, RefusesAPortWhoseValueTypeIsNotRegistered) {
  Registry reg = test::make_test_registry();
  EXPECT_EQ(test::error_of([&] { reg.add(node("test.in", "Nmber")); }),
            "node type 'test.in': input 'a' has value type 'Nmber', which is not registered");
  EXPECT_EQ(test::error_of([&] { reg.add(node("test.out", "Number", "Mesh")); }),
            "node type 'test.out': output 'out' has value type 'Mesh', which is not registered");
  EXPECT_EQ(reg.find("test.in"), nullptr);
  EXPECT_EQ(reg.find("test.out"), nullptr);
}

TEST(Registry, RefusesADuplicateValueType) {
  Registry reg = test::make_test_registry();
  EXPECT_EQ(test::error_of([&] { reg.values().add({"Number", "txt", "again", nullptr}); }),
            "value type 'Number' is registered twice");
}

TEST(Registry, ADomainNamesItsOwnNodes) {
  Registry reg = test::make_test_registry();
  reg.add_domain("cloud", {node("cloud.denoise")});
  reg.add_domain("mesh", {node("mesh.denoise")});  // the same name in another domain: no clash
  EXPECT_NE(reg.find("cloud.denoise"), nullptr);
  EXPECT_NE(reg.find("mesh.denoise"), nullptr);
  EXPECT_EQ(test::error_of([&] { reg.add_domain("mesh", {node("denoise")}); }),
            "node type 'denoise' is in the domain 'mesh': name it 'mesh.<name>'");
  EXPECT_EQ(test::error_of([&] { reg.add_domain("mesh", {node("meshes.x")}); }),
            "node type 'meshes.x' is in the domain 'mesh': name it 'mesh.<name>'");
}

}  // namespace
}  // namespace scallop
