#pragma once
// CPU parallelism for the host-side work (geometry, body fit, metrics, synthetic scenes): plain
// threads over the machine's cores, exceptions rethrown on the calling thread.
#include <cstddef>
#include <functional>

namespace nf {

// The threads host work uses: NF_THREADS when set to a positive number (a batch task sharing the
// machine with others), else the machine's cores.
unsigned cpu_threads();

// Runs body(begin, end) over [0, count) split across the machine's cores.
void parallel_for(std::size_t count, const std::function<void(std::size_t, std::size_t)>& body);

// Runs body(k) for k in [0, count) on all cores, handing out items one at a time (for items of
// very different cost, or few expensive ones). Rethrows the first exception on this thread.
void for_each_dynamic(int count, const std::function<void(int)>& body);

}  // namespace nf
