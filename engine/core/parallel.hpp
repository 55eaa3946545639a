#pragma once
// CPU parallelism for the host-side work (geometry, body fit, metrics, synthetic scenes): plain
// threads over the machine's cores, exceptions rethrown on the calling thread.
#include <cstddef>
#include <functional>

namespace nf {

// The threads host work uses: NF_THREADS when set to a positive number (a batch task sharing the
// machine with others), else the machine's cores.
unsigned cpu_threads();

// Runs body(begin, end) over [0, count) split across the machine's cores, each thread given at
// least `min_per_thread` items: cheap items (a vertex, a pixel) need many to repay a thread's start,
// while items that each take a while (an image row, a grid slice) pass 1, or a few hundred of them
// would run on one core.
void parallel_for(std::size_t count, const std::function<void(std::size_t, std::size_t)>& body, std::size_t min_per_thread = 1024);

// Runs body(k) for k in [0, count) on all cores, handing out items one at a time (for items of
// very different cost, or few expensive ones). Rethrows the first exception on this thread.
void for_each_dynamic(int count, const std::function<void(int)>& body);

}  // namespace nf
