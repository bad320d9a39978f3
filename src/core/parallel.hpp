// The one parallel-loop entry point. Each index is computed independently by the same code,
// so results do not depend on the number of threads.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace penumbra {

// Calls body(i) for i in [0, n), in parallel over chunks of `grain` indices.
template <class Body>
void parallel_for(int n, Body&& body, int grain = 1) {
  tbb::parallel_for(tbb::blocked_range<int>(0, n, grain), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i != r.end(); ++i) body(i);
  });
}

}  // namespace penumbra
