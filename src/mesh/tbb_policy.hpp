// When the library may hand work to TBB worker threads.
#pragma once

namespace crux {

/// False in a ThreadSanitizer build (CMake CRUX_TSAN defines CRUX_TBB_SERIAL): Debian's oneTBB is
/// not TSan-instrumented, so TSan cannot see the synchronisation inside TBB's task scheduler and
/// reports false races between a task's spawner and the worker running it (e.g. in
/// tbb::parallel_invoke's function_invoker). There the parallel BVH build and the batch APIs run
/// their serial paths, which produce identical results (docs/threads.md); the concurrency TSan
/// checks is crux's own: many std::threads running const queries at once.
#ifdef CRUX_TBB_SERIAL
inline constexpr bool kTbbParallelAllowed = false;
#else
inline constexpr bool kTbbParallelAllowed = true;
#endif

}  // namespace crux
