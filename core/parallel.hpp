#pragma once
// Parallel loops over index ranges, on TBB's work-stealing scheduler.

#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace rfd {

/// Calls body(begin, end) on disjoint chunks covering [0, count), in parallel.
/// `grain` is the smallest chunk worth a task; results must not depend on the chunking.
template <typename Body>
void parallel_for_chunks(std::size_t count, std::size_t grain, Body&& body) {
    if (count == 0) return;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, grain == 0 ? 1 : grain),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          body(range.begin(), range.end());
                      });
}

}  // namespace rfd
