// Disk tier of the node-output cache: a content-addressed folder.
//
// An entry holds every output of one node run under its key (a Merkle chain: hash of node type,
// node version, canonical parameters and the keys of the inputs). Entries are written to a temp
// file and renamed into place, carry their own key and end with a checksum of everything before
// it, so a killed or crashed writer never leaves an entry that reads back wrong, and an entry
// copied over another key's file is a miss, not another node's value. A bad entry is deleted
// when it is found, so the recomputed one takes its place.
#pragma once

#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>

#include "engine/value.h"

namespace scallop {

// A name for a temp file in `target`'s folder, unique across hosts, processes and calls:
// <target name>.<hostname>.<pid>.<counter>.<random>.tmp. Two hosts sharing the folder (NFS) may
// run processes of the same pid; the hostname and the random part keep their temp files apart.
std::string temp_path_beside(const std::string& target);

class DiskCache {
 public:
  explicit DiskCache(std::string dir);
  // $XDG_CACHE_HOME/scallop, or ~/.cache/scallop.
  static std::string default_dir();

  struct Lookup {
    bool hit = false;
    std::map<std::string, ValuePtr> outputs;
    std::string why;  // for a miss: as Check::why, or "damaged entry (<what the decoder said>)"
  };
  // ports, when given: decode only these outputs (the others stay in the file, unread: a node's
  // picture or simulation is not decoded for its report alone).
  Lookup load(const std::string& key, const ValueTypes& types,
              const std::set<std::string>* ports = nullptr) const;

  struct Check {
    bool sound = false;
    // for a miss: "no entry", "damaged entry (checksum mismatch)", "damaged entry (bad header)",
    // "entry holds another key", "entry of another cache format (2, now 3)"
    std::string why;
  };
  // Whether a sound entry exists (header, key and checksum verified; values not decoded); a bad
  // one is deleted.
  Check check(const std::string& key) const;
  void store(const std::string& key, const std::map<std::string, ValuePtr>& outputs) const;

  // What the last run of a node (by graph and node id) was keyed on, for --explain.
  std::optional<nlohmann::json> last_manifest(const std::string& identity) const;
  void write_manifest(const std::string& identity, const nlohmann::json& manifest) const;

  std::string entry_path(const std::string& key) const;
  const std::string& dir() const { return dir_; }

  // Test hook: called with the temp file after the header of an entry is written (kill tests).
  std::function<void(const std::string& temp_path)> after_partial_write;

 private:
  std::string dir_;
};

}  // namespace scallop
