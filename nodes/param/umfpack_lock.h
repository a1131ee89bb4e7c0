// One UMFPACK call at a time in the process. UMFPACK does its dense work through the BLAS, and
// Debian's serial OpenBLAS (the fastest BLAS packaged, 3x the reference one for these systems) is
// built without locks: two threads in it at once share its work buffers and compute wrong
// numbers (measured: a batch of two parts solving the same harmonic map at once got a relative
// residual of 3e-5 instead of 1e-15 in one of them; OpenBLAS issues 1755, 2126). Hold this
// lock around every factorisation and solve.
#pragma once

#include <mutex>

namespace scallop {

std::mutex& umfpack_mutex();

}  // namespace scallop
