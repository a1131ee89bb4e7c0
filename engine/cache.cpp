#include "engine/cache.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "engine/hash.h"

namespace scallop {
namespace fs = std::filesystem;

namespace {
constexpr char kMagic[] = "SCALLOP-CACHE 1\n";
constexpr std::size_t kMagicLen = sizeof(kMagic) - 1;
constexpr std::size_t kHashLen = 32;

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Writes bytes to a fresh temp file in dir and renames it to `target` (atomic on POSIX).
void write_atomically(const std::string& dir, const std::string& target, const std::string& bytes,
                      const std::function<void(const std::string&)>& after_half) {
  static std::atomic<unsigned> counter{0};
  fs::create_directories(fs::path(target).parent_path());
  fs::create_directories(fs::path(dir) / "tmp");
  std::string tmp = (fs::path(dir) / "tmp" /
                     (fs::path(target).filename().string() + "." + std::to_string(::getpid()) + "." +
                      std::to_string(counter++) + ".tmp"))
                        .string();
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw std::runtime_error("cannot create cache file '" + tmp + "'");
  auto write_span = [&](const char* p, std::size_t n) {
    while (n > 0) {
      ssize_t w = ::write(fd, p, n);
      if (w <= 0) {
        ::close(fd);
        fs::remove(tmp);
        throw std::runtime_error("cannot write cache file '" + tmp + "'");
      }
      p += w;
      n -= static_cast<std::size_t>(w);
    }
  };
  std::size_t half = bytes.size() / 2;
  write_span(bytes.data(), half);
  if (after_half) after_half(tmp);
  write_span(bytes.data() + half, bytes.size() - half);
  ::fsync(fd);
  ::close(fd);
  fs::rename(tmp, target);
}
}  // namespace

DiskCache::DiskCache(std::string dir) : dir_(std::move(dir)) { fs::create_directories(dir_); }

std::string DiskCache::default_dir() {
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return (fs::path(x) / "scallop").string();
  if (const char* h = std::getenv("HOME"); h && *h) return (fs::path(h) / ".cache" / "scallop").string();
  return (fs::temp_directory_path() / "scallop-cache").string();
}

std::string DiskCache::entry_path(const std::string& key) const {
  return (fs::path(dir_) / key.substr(0, 2) / (key + ".entry")).string();
}

DiskCache::Lookup DiskCache::load(const std::string& key, const ValueTypes& types) const {
  Lookup r;
  std::string path = entry_path(key);
  if (!fs::exists(path)) {
    r.why = "no entry";
    return r;
  }
  std::string bytes = read_all(path);
  auto reject = [&](const std::string& why) {
    std::error_code ec;
    fs::remove(path, ec);  // a bad entry is dropped so the recomputed one replaces it
    r.why = "unreadable entry (" + why + "), recomputed";
    r.outputs.clear();
    return r;
  };
  if (bytes.size() < kMagicLen + kHashLen || bytes.compare(0, kMagicLen, kMagic) != 0) return reject("bad header");
  std::string body = bytes.substr(0, bytes.size() - kHashLen);
  if (hash_bytes(body) != bytes.substr(bytes.size() - kHashLen)) return reject("checksum mismatch");
  try {
    std::istringstream in(body.substr(kMagicLen));
    std::uint64_t n = bin::read_u64(in);
    for (std::uint64_t i = 0; i < n; ++i) {
      std::string port = bin::read_string(in);
      std::string type = bin::read_string(in);
      std::string payload = bin::read_string(in);
      const ValueType* vt = types.find(type);
      if (!vt || !vt->deserialize) return reject("unknown value type " + type);
      std::istringstream pin(payload);
      r.outputs[port] = vt->deserialize(pin);
    }
  } catch (const std::exception& e) {
    return reject(e.what());
  }
  r.hit = true;
  return r;
}

void DiskCache::store(const std::string& key, const std::map<std::string, ValuePtr>& outputs) const {
  std::ostringstream s;
  s.write(kMagic, kMagicLen);
  bin::write_u64(s, outputs.size());
  for (const auto& [port, value] : outputs) {
    bin::write_string(s, port);
    bin::write_string(s, value->type_name());
    std::ostringstream payload;
    value->serialize(payload);
    bin::write_string(s, payload.str());
  }
  std::string body = s.str();
  write_atomically(dir_, entry_path(key), body + hash_bytes(body), after_partial_write);
}

std::optional<nlohmann::json> DiskCache::last_manifest(const std::string& identity) const {
  std::string text = read_all((fs::path(dir_) / "manifests" / (hash_bytes(identity) + ".json")).string());
  if (text.empty()) return std::nullopt;
  try {
    return nlohmann::json::parse(text);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

void DiskCache::write_manifest(const std::string& identity, const nlohmann::json& manifest) const {
  write_atomically(dir_, (fs::path(dir_) / "manifests" / (hash_bytes(identity) + ".json")).string(),
                   manifest.dump(), nullptr);
}

}  // namespace scallop
