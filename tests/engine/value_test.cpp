#include "engine/value.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

namespace scallop {
namespace {

struct Numbers final : Value {
  std::vector<int> v;
  std::string type_name() const override { return "Numbers"; }
  void serialize(std::ostream& out) const override { bin::write_vector(out, v); }
};

TEST(Value, WhatIsDerivedFromAValueIsMadeOnceAndSharedByEveryThread) {
  Numbers n;
  n.v = {1, 2, 3};
  std::atomic<int> made{0};
  const auto make_sum = [&] {
    ++made;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // others ask meanwhile
    int s = 0;
    for (int x : n.v) s += x;
    return std::make_shared<const int>(s);
  };
  std::vector<std::shared_ptr<const int>> got(8);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < got.size(); ++t)
    threads.emplace_back([&, t] { got[t] = n.derived<int>("sum", make_sum); });
  for (auto& t : threads) t.join();
  EXPECT_EQ(made, 1);
  for (const auto& g : got) {
    ASSERT_EQ(g, got[0]);  // the same object
    EXPECT_EQ(*g, 6);
  }
  // another key is another entry
  EXPECT_EQ(*n.derived<int>("count", [&] { return std::make_shared<const int>(int(n.v.size())); }), 3);
  EXPECT_EQ(n.derived<int>("sum", make_sum), got[0]);
  EXPECT_EQ(made, 1);
}

TEST(Value, ACopyDerivesAfreshAndAFailedMakeLeavesNoEntry) {
  Numbers n;
  n.v = {4};
  int made = 0;
  const auto make = [&] { return std::make_shared<const int>(++made); };
  EXPECT_EQ(*n.derived<int>("k", make), 1);
  const Numbers copy = n;  // its own data, derived again on demand
  EXPECT_EQ(*copy.derived<int>("k", make), 2);
  EXPECT_EQ(*n.derived<int>("k", make), 1);

  EXPECT_THROW(n.derived<int>("bad", []() -> std::shared_ptr<const int> { throw std::runtime_error("no"); }),
               std::runtime_error);
  EXPECT_EQ(*n.derived<int>("bad", make), 3);  // tried again, not remembered as failed
}

}  // namespace
}  // namespace scallop
