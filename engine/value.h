// Immutable typed values passed between nodes.
//
// A value is created once by the node that outputs it and then shared (never copied) by every
// consumer through std::shared_ptr<const Value>. Each value type has a name used in graph files
// and messages, a file extension for graph outputs, and binary (de)serialisation for the disk cache.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <istream>
#include <map>
#include <memory>
#include <mutex>
#include <ostream>
#include <string>
#include <vector>

namespace scallop {

// What nodes derive from a value alone (a search tree over a cloud's points, its height field),
// kept with the value and built once however many nodes ask: a value never changes once made, so
// neither does what is derived from it. Freed with the value. Copying or moving a value starts
// its copy with none (they are derived again on demand).
class DerivedStore {
 public:
  DerivedStore() = default;
  DerivedStore(const DerivedStore&) : DerivedStore() {}
  DerivedStore& operator=(const DerivedStore&) { return *this; }
  // The entry `key`, made by make() on first use; callers asking meanwhile wait for it (other
  // keys do not). A make() that throws leaves no entry, and the next caller tries again.
  template <class T>
  std::shared_ptr<const T> get(const std::string& key, const std::function<std::shared_ptr<const T>()>& make) const {
    Slot& slot = slot_of(key);
    std::lock_guard<std::mutex> lock(slot.mutex);
    if (!slot.value) slot.value = make();
    return std::static_pointer_cast<const T>(slot.value);
  }

 private:
  struct Slot {
    std::mutex mutex;
    std::shared_ptr<const void> value;
  };
  Slot& slot_of(const std::string& key) const;
  mutable std::mutex mutex_;
  mutable std::map<std::string, std::unique_ptr<Slot>> slots_;
};

class Value {
 public:
  virtual ~Value() = default;
  // Derived data built once per value (DerivedStore::get); thread-safe.
  template <class T>
  std::shared_ptr<const T> derived(const std::string& key, const std::function<std::shared_ptr<const T>()>& make) const {
    return derived_.get<T>(key, make);
  }
  // Name of the value type, e.g. "Cloud"; must match the ValueType it was registered under.
  virtual std::string type_name() const = 0;
  // Binary form for the disk cache.
  virtual void serialize(std::ostream& out) const = 0;
  // Writes the value as a user-facing file (a graph output): PLY for clouds, JSON for reports...
  virtual void write_file(const std::string& path) const;
  // Identity of the value for cache keys: by default the hash of its binary form.
  virtual std::string content_key() const;

 private:
  DerivedStore derived_;
};

using ValuePtr = std::shared_ptr<const Value>;

// Describes one value type: its name, the extension of the file a graph output of this type is
// written to, and how to read its binary cache form back.
struct ValueType {
  std::string name;
  std::string extension;  // without the dot: "ply", "ngc", "json", "png"
  std::string description;
  std::function<ValuePtr(std::istream&)> deserialize;
  // The version of serialize()'s layout, part of the cache key of every node that reads or writes
  // the type: raise it whenever that layout changes, so that this type's disk-cache entries miss
  // instead of being misread, and no other type's.
  int format = 1;
};

// All known value types by name.
class ValueTypes {
 public:
  // Throws std::logic_error when a type of that name is registered already.
  void add(ValueType type);
  const ValueType* find(const std::string& name) const;
  const std::map<std::string, ValueType>& all() const { return types_; }

 private:
  std::map<std::string, ValueType> types_;
};

// Little helpers for the binary cache form: fixed-width little-endian scalars and vectors of PODs.
// Reading past the end throws std::runtime_error, so a truncated stream is never taken as data.
namespace bin {
void write_u64(std::ostream& out, std::uint64_t v);
std::uint64_t read_u64(std::istream& in);
void write_f64(std::ostream& out, double v);
double read_f64(std::istream& in);
void write_string(std::ostream& out, const std::string& s);
std::string read_string(std::istream& in);
void write_bytes(std::ostream& out, const void* data, std::size_t size);
void read_bytes(std::istream& in, void* data, std::size_t size);

template <class T>
void write_vector(std::ostream& out, const std::vector<T>& v) {
  // T is plain data: scalars, or Eigen fixed-size vectors (a packed array of scalars).
  write_u64(out, v.size());
  write_bytes(out, v.data(), v.size() * sizeof(T));
}
template <class T>
std::vector<T> read_vector(std::istream& in) {
  // T is plain data: scalars, or Eigen fixed-size vectors (a packed array of scalars).
  std::uint64_t n = read_u64(in);
  if (n > (std::uint64_t(1) << 40) / sizeof(T)) throw std::runtime_error("corrupt vector length");
  // Read through a small buffer and appended: a vector sized first is zero-filled, then
  // overwritten (at a million points that fill was a sixth of a warm run).
  constexpr std::size_t kChunk = std::max<std::size_t>(1, 65536 / sizeof(T));
  std::vector<T> v;
  v.reserve(n);
  std::unique_ptr<T[]> chunk(new T[std::min<std::uint64_t>(n, kChunk)]);
  while (v.size() < n) {
    const std::size_t m = std::min<std::uint64_t>(n - v.size(), kChunk);
    read_bytes(in, chunk.get(), m * sizeof(T));
    v.insert(v.end(), chunk.get(), chunk.get() + m);
  }
  return v;
}
}  // namespace bin

}  // namespace scallop
