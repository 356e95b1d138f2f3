#pragma once
// Deterministic parallel reductions: work over n items is cut into a fixed number of chunks, each
// chunk sums into its own slot, and the caller adds the slots in chunk order. The result is then the
// same whatever the number of threads or their scheduling, so runs are reproducible bit for bit.
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstddef>

namespace eds {

constexpr int kReductionChunks = 16;

// TBB's scheduler synchronizes inside its own library, which ThreadSanitizer does not instrument: every
// hand-over between its workers would be reported. Under TSan the loops run serially (the same chunks,
// the same results), so that its reports concern eds's own threads.
#if defined(__SANITIZE_THREAD__)
inline constexpr bool kParallelLoops = false;
#else
inline constexpr bool kParallelLoops = true;
#endif

// tbb::parallel_for over a blocked range, serial under ThreadSanitizer.
template <typename Range, typename Body>
void parallelFor(const Range& range, const Body& body) {
  if constexpr (kParallelLoops)
    tbb::parallel_for(range, body);
  else
    body(range);
}

// Calls body(chunk) for chunk = 0 .. kReductionChunks-1, in parallel when `parallel`. Isolated: while
// the calling thread waits for its chunks it runs none of another thread's parallel work (the tracking
// thread's alignments and the back-end's bundle adjustment share the workers), so neither stage is held
// up by a piece of the other's.
template <typename Body>
void forEachChunkIndex(const Body& body, bool parallel = true) {
  if (parallel && kParallelLoops)
    tbb::this_task_arena::isolate([&] { tbb::parallel_for(0, kReductionChunks, body); });
  else
    for (int c = 0; c < kReductionChunks; ++c) body(c);
}

// Calls f(chunk, begin, end) for every chunk of [0, n); in parallel when `parallel` (small jobs cost
// more to hand out than to do), with the same chunks, hence the same sums, either way.
template <typename F>
void forEachChunk(std::size_t n, F&& f, bool parallel = true) {
  forEachChunkIndex(
      [&](int c) {
        f(c, n * static_cast<std::size_t>(c) / kReductionChunks,
          n * static_cast<std::size_t>(c + 1) / kReductionChunks);
      },
      parallel);
}

}  // namespace eds
