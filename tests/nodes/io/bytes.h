// Byte images of scalars, for hand-made binary files in the reader tests.
#pragma once

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>

namespace scallop::test {

// The little-endian bytes of v.
template <class T>
std::string le(T v) {
  std::string s(sizeof(T), '\0');
  std::memcpy(s.data(), &v, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(s.begin(), s.end());
  return s;
}

// The big-endian bytes of v.
template <class T>
std::string be(T v) {
  std::string s = le(v);
  std::reverse(s.begin(), s.end());
  return s;
}

}  // namespace scallop::test
