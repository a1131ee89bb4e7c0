#include "engine/value.h"

#include <fstream>
#include <sstream>

#include "engine/hash.h"
#include <stdexcept>

namespace scallop {

void Value::write_file(const std::string& path) const {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  serialize(out);
}

DerivedStore::Slot& DerivedStore::slot_of(const std::string& key) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::unique_ptr<Slot>& slot = slots_[key];
  if (!slot) slot = std::make_unique<Slot>();
  return *slot;
}

std::string Value::content_key() const {
  std::ostringstream s;
  serialize(s);
  return hash_bytes(s.str());
}

void ValueTypes::add(ValueType type) {
  if (types_.count(type.name)) throw std::logic_error("value type '" + type.name + "' is registered twice");
  std::string name = type.name;
  types_[name] = std::move(type);
}

const ValueType* ValueTypes::find(const std::string& name) const {
  auto it = types_.find(name);
  return it == types_.end() ? nullptr : &it->second;
}

namespace bin {
void write_bytes(std::ostream& out, const void* data, std::size_t size) {
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
}
void read_bytes(std::istream& in, void* data, std::size_t size) {
  in.read(static_cast<char*>(data), static_cast<std::streamsize>(size));
  if (static_cast<std::size_t>(in.gcount()) != size) throw std::runtime_error("truncated binary value");
}
void write_u64(std::ostream& out, std::uint64_t v) { write_bytes(out, &v, sizeof v); }
std::uint64_t read_u64(std::istream& in) {
  std::uint64_t v;
  read_bytes(in, &v, sizeof v);
  return v;
}
void write_f64(std::ostream& out, double v) { write_bytes(out, &v, sizeof v); }
double read_f64(std::istream& in) {
  double v;
  read_bytes(in, &v, sizeof v);
  return v;
}
void write_string(std::ostream& out, const std::string& s) {
  write_u64(out, s.size());
  write_bytes(out, s.data(), s.size());
}
std::string read_string(std::istream& in) {
  std::uint64_t n = read_u64(in);
  if (n > (std::uint64_t(1) << 36)) throw std::runtime_error("corrupt string length");
  std::string s(n, '\0');
  read_bytes(in, s.data(), n);
  return s;
}
}  // namespace bin

}  // namespace scallop
