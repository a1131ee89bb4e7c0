// The process's memory, for the per-node peak in progress events (Linux /proc; 0 elsewhere).
#pragma once

#include <cstddef>

namespace scallop {

// The process's resident-set high-water mark (VmHWM) in bytes, or 0 when unknown.
std::size_t peak_resident_bytes();

// Restarts the high-water mark at the current resident size (writes 5 to /proc/self/clear_refs,
// Linux 4.0 on); false when the system does not allow it.
bool reset_peak_resident();

}  // namespace scallop
