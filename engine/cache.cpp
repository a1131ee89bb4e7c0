#include "engine/cache.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cctype>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>

#include <xxhash.h>

#include "engine/hash.h"

namespace scallop {
namespace fs = std::filesystem;

std::string temp_path_beside(const std::string& target) {
  static std::atomic<unsigned> counter{0};
  static const std::string random = [] {  // tells apart two hosts' processes of the same pid
    std::random_device rd;
    char hex[17];
    std::snprintf(hex, sizeof hex, "%08x%08x", rd(), rd());
    return std::string(hex);
  }();
  char host[256] = "host";
  ::gethostname(host, sizeof host - 1);
  host[sizeof host - 1] = '\0';
  std::string name = fs::path(target).filename().string() + "." + host + "." + std::to_string(::getpid()) + "." +
                     std::to_string(counter++) + "." + random + ".tmp";
  std::replace(name.begin(), name.end(), '/', '_');  // a hostname is a plain name, but be sure
  return (fs::path(target).parent_path() / name).string();
}

namespace {
// Entry layout (format 3): magic, the entry's own key (u64 length + bytes), u64 output count, then
// per output: port, value type, u64 payload size, payload; last, 32 hex digits of XXH3-128 over
// everything before them. Format 2 had no key: an entry copied over another key's file passed
// its checksum and loaded as the wrong value. Entries of another format are a clean miss.
constexpr char kMagicPrefix[] = "SCALLOP-CACHE ";
constexpr char kMagic[] = "SCALLOP-CACHE 3\n";
constexpr std::size_t kMagicLen = sizeof(kMagic) - 1;
constexpr std::size_t kHashLen = 32;

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  in.seekg(0, std::ios::end);
  std::string bytes(static_cast<std::size_t>(std::max<std::streamoff>(0, in.tellg())), '\0');
  in.seekg(0);
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return bytes;
}

// An entry's file mapped read-only (empty when it cannot be opened): checked and loaded where the
// page cache holds it, without the zero-fill and copy of reading it into a string (at a million
// points, reading every entry that way was most of a warm run).
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return;
    struct stat st {};
    if (::fstat(fd, &st) == 0 && st.st_size > 0) {
      void* p = ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
      if (p != MAP_FAILED) data_ = static_cast<const char*>(p), size_ = static_cast<std::size_t>(st.st_size);
    }
    ::close(fd);
  }
  ~MappedFile() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::string_view bytes() const { return {data_, size_}; }

 private:
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

// A read-only stream over bytes that already sit in memory (no copy).
struct MemoryBuffer : std::streambuf {
  MemoryBuffer(const char* begin, std::size_t size) {
    char* b = const_cast<char*>(begin);
    setg(b, b, b + size);
  }
  std::size_t position() const { return static_cast<std::size_t>(gptr() - eback()); }
  void skip(std::size_t n) { setg(eback(), gptr() + n, egptr()); }
};

// Writes an entry into a fresh temp file beside `target` and renames it into place. Many
// processes on many hosts may write the same key into one shared folder (a batch on a cluster,
// DESIGN.md "Beyond one machine"): each writes a temp file of its own (temp_path_beside, opened
// O_EXCL so that it is never another writer's), and rename within one directory replaces the
// entry whole, so a reader sees the old entry, the new one or none, never a part of one. Two
// writers of one key write the same bytes (content-addressed), so which rename lands last does
// not matter. `write_body` streams the body through `put`; a checksum of the body goes last.
class AtomicWriter {
 public:
  explicit AtomicWriter(const std::string& target) : target_(target) {
    fs::create_directories(fs::path(target).parent_path());
    tmp_ = temp_path_beside(target);
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
    if (fd_ < 0) throw std::runtime_error("cannot create cache file '" + tmp_ + "': " + std::strerror(errno));
    state_ = XXH3_createState();
    XXH3_128bits_reset(state_);
  }
  ~AtomicWriter() {
    if (fd_ >= 0) {
      ::close(fd_);
      std::error_code ec;
      fs::remove(tmp_, ec);
    }
    XXH3_freeState(state_);
  }
  void put(const char* p, std::size_t n) {
    XXH3_128bits_update(state_, p, n);
    raw(p, n);
  }
  void put(const std::string& s) { put(s.data(), s.size()); }
  void commit() {
    XXH128_hash_t h = XXH3_128bits_digest(state_);
    char hex[33];
    std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                  static_cast<unsigned long long>(h.low64));
    raw(hex, kHashLen);
    ::fsync(fd_);
    ::close(fd_);
    fd_ = -1;
    fs::rename(tmp_, target_);
  }
  const std::string& temp_path() const { return tmp_; }

 private:
  void raw(const char* p, std::size_t n) {
    while (n > 0) {
      ssize_t w = ::write(fd_, p, n);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0)
        throw std::runtime_error("cannot write cache file '" + tmp_ + "': " +
                                 (w < 0 ? std::strerror(errno) : "nothing written"));
      p += w;
      n -= static_cast<std::size_t>(w);
    }
  }
  std::string target_, tmp_;
  int fd_ = -1;
  XXH3_state_t* state_ = nullptr;
};

// Counts the bytes a value's serialize() writes, keeping none of them: an entry's header gives
// each payload's size before the payload.
class CountingBuffer : public std::streambuf {
 public:
  std::uint64_t count() const { return count_; }

 protected:
  std::streamsize xsputn(const char*, std::streamsize n) override {
    count_ += static_cast<std::uint64_t>(n);
    return n;
  }
  int_type overflow(int_type c) override {
    if (!traits_type::eq_int_type(c, traits_type::eof())) ++count_;
    return traits_type::not_eof(c);
  }
  pos_type seekoff(off_type, std::ios_base::seekdir, std::ios_base::openmode) override {
    return pos_type(static_cast<off_type>(count_));
  }

 private:
  std::uint64_t count_ = 0;
};

// Streams a value's serialize() into an AtomicWriter through the caller's buffer (up to 1 MiB):
// a payload of a million points (tens of MB) is never held a second time, nor grown by doubling
// (measured at 1M points: building each payload in a string and copying it out was about a tenth
// of a cold run's CPU time, most of it page faults of the fresh buffers).
template <class Writer>
class WriterBuffer : public std::streambuf {
 public:
  WriterBuffer(Writer& w, char* buffer, std::size_t size) : w_(w), begin_(buffer), end_(buffer + size) {
    setp(begin_, end_);
  }
  void flush_to_writer() {
    const std::ptrdiff_t n = pptr() - pbase();
    if (n > 0) w_.put(pbase(), static_cast<std::size_t>(n));
    written_ += static_cast<std::uint64_t>(n);
    setp(begin_, end_);
  }
  std::uint64_t written() const { return written_ + static_cast<std::uint64_t>(pptr() - pbase()); }

 protected:
  int_type overflow(int_type c) override {
    flush_to_writer();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* p, std::streamsize n) override {
    if (n >= end_ - begin_) {  // large arrays: straight through
      flush_to_writer();
      w_.put(p, static_cast<std::size_t>(n));
      written_ += static_cast<std::uint64_t>(n);
      return n;
    }
    return std::streambuf::xsputn(p, n);
  }
  pos_type seekoff(off_type, std::ios_base::seekdir, std::ios_base::openmode) override {
    return pos_type(static_cast<off_type>(written()));
  }

 private:
  Writer& w_;
  char* begin_;
  char* end_;
  std::uint64_t written_ = 0;
};

std::string encoded_u64(std::uint64_t v) { return std::string(reinterpret_cast<const char*>(&v), sizeof v); }
std::string encoded_string(const std::string& s) { return encoded_u64(s.size()) + s; }

// Checks magic, checksum and key of an entry held in memory; returns "" when it is sound, else
// why not. `body_at` receives where the outputs begin.
std::string verify_entry(std::string_view bytes, const std::string& key, std::size_t* body_at = nullptr) {
  if (bytes.compare(0, sizeof(kMagicPrefix) - 1, kMagicPrefix) == 0 && bytes.compare(0, kMagicLen, kMagic) != 0) {
    std::string version;
    for (std::size_t i = sizeof(kMagicPrefix) - 1; i < bytes.size() && version.size() < 8 && std::isdigit(static_cast<unsigned char>(bytes[i])); ++i)
      version += bytes[i];
    return "entry of another cache format (" + (version.empty() ? std::string("?") : version) + ", now 3)";
  }
  if (bytes.size() < kMagicLen + sizeof(std::uint64_t) + kHashLen || bytes.compare(0, kMagicLen, kMagic) != 0)
    return "damaged entry (bad header)";
  std::string_view body(bytes.data(), bytes.size() - kHashLen);
  if (hash_bytes(body) != bytes.substr(bytes.size() - kHashLen)) return "damaged entry (checksum mismatch)";
  std::uint64_t key_len = 0;
  std::memcpy(&key_len, bytes.data() + kMagicLen, sizeof key_len);
  const std::size_t key_at = kMagicLen + sizeof key_len;
  if (key_len > body.size() - key_at) return "damaged entry (bad header)";
  if (std::string_view(bytes.data() + key_at, key_len) != key) return "entry holds another key";
  if (body_at) *body_at = key_at + key_len;
  return "";
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

DiskCache::Check DiskCache::check(const std::string& key) const {
  std::string path = entry_path(key);
  if (!fs::exists(path)) return {false, "no entry"};
  std::string why = verify_entry(MappedFile(path).bytes(), key);
  if (why.empty()) return {true, ""};
  std::error_code ec;
  fs::remove(path, ec);  // a bad entry is dropped so the recomputed one replaces it
  return {false, why};
}

DiskCache::Lookup DiskCache::load(const std::string& key, const ValueTypes& types,
                                   const std::set<std::string>* ports) const {
  Lookup r;
  std::string path = entry_path(key);
  if (!fs::exists(path)) {
    r.why = "no entry";
    return r;
  }
  const MappedFile file(path);
  const std::string_view bytes = file.bytes();
  auto reject = [&](const std::string& why) {
    std::error_code ec;
    fs::remove(path, ec);  // a bad entry is dropped so the recomputed one replaces it
    r.why = why;
    r.outputs.clear();
    return r;
  };
  std::size_t body_at = 0;
  if (std::string bad = verify_entry(bytes, key, &body_at); !bad.empty()) return reject(bad);
  try {
    MemoryBuffer buf(bytes.data() + body_at, bytes.size() - body_at - kHashLen);
    std::istream in(&buf);
    std::uint64_t n = bin::read_u64(in);
    for (std::uint64_t i = 0; i < n; ++i) {
      std::string port = bin::read_string(in);
      std::string type = bin::read_string(in);
      std::uint64_t size = bin::read_u64(in);
      const ValueType* vt = types.find(type);
      if (!vt || !vt->deserialize) return reject("damaged entry (unknown value type " + type + ")");
      std::size_t at = buf.position() + body_at;
      if (size > bytes.size() - kHashLen - at) return reject("damaged entry (payload runs past the end)");
      if (!ports || ports->count(port)) {
        MemoryBuffer pbuf(bytes.data() + at, size);
        std::istream pin(&pbuf);
        r.outputs[port] = vt->deserialize(pin);
      }
      buf.skip(size);
    }
  } catch (const std::exception& e) {
    return reject(std::string("damaged entry (") + e.what() + ")");
  }
  r.hit = true;
  return r;
}

void DiskCache::store(const std::string& key, const std::map<std::string, ValuePtr>& outputs) const {
  AtomicWriter w(entry_path(key));
  w.put(kMagic, kMagicLen);
  w.put(encoded_string(key));
  w.put(encoded_u64(outputs.size()));
  if (after_partial_write) after_partial_write(w.temp_path());
  // One buffer for the entry, as large as its largest payload up to 1 MiB, not zero-filled (an
  // entry of many small outputs must not pay for a megabyte each).
  std::unique_ptr<char[]> buffer;
  std::size_t capacity = 0;
  for (const auto& [port, value] : outputs) {
    CountingBuffer counter;
    std::ostream counting(&counter);
    value->serialize(counting);
    w.put(encoded_string(port) + encoded_string(value->type_name()) + encoded_u64(counter.count()));
    const std::size_t wanted = static_cast<std::size_t>(std::clamp<std::uint64_t>(counter.count(), 1, 1 << 20));
    if (capacity < wanted) buffer.reset(new char[capacity = wanted]);
    WriterBuffer<AtomicWriter> to_file(w, buffer.get(), capacity);
    std::ostream out(&to_file);
    value->serialize(out);
    to_file.flush_to_writer();
    if (!out || to_file.written() != counter.count())
      throw std::runtime_error("the value of output '" + port + "' serialized to " +
                               std::to_string(counter.count()) + " bytes, then to " +
                               std::to_string(to_file.written()) + ": not the same twice");
  }
  w.commit();
}

std::optional<nlohmann::json> DiskCache::last_manifest(const std::string& identity) const {
  std::string text = read_all((fs::path(dir_) / "manifests" / (hash_bytes(identity) + ".json")).string());
  if (text.size() <= kHashLen) return std::nullopt;
  std::string_view body(text.data(), text.size() - kHashLen);
  if (hash_bytes(body) != text.substr(text.size() - kHashLen)) return std::nullopt;  // damaged: as if none
  try {
    return nlohmann::json::parse(body);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

void DiskCache::write_manifest(const std::string& identity, const nlohmann::json& manifest) const {
  std::string path = (fs::path(dir_) / "manifests" / (hash_bytes(identity) + ".json")).string();
  AtomicWriter w(path);
  w.put(manifest.dump());
  w.commit();
}

}  // namespace scallop
