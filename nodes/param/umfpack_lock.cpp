#include "nodes/param/umfpack_lock.h"

namespace scallop {

std::mutex& umfpack_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace scallop
