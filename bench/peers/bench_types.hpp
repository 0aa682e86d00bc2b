#pragma once
/// @file bench_types.hpp  Plain query and answer records shared by bench_mesh and its peers.
///
/// The peers (Embree, Bullet, FCL) see only these float arrays, never crux types, so every
/// engine answers exactly the same inputs: the mesh is loaded once with crux::loadMesh and
/// its vertices rounded to float once; every query is generated once in float.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <ctime>
#include <utility>
#include <vector>

#include <tbb/task_arena.h>

namespace crux::bench {

/// An indexed triangle mesh as flat float/uint32 arrays (the layout Embree and Bullet take
/// without copying). `positions` holds 3 floats per vertex plus one padding float, because
/// Embree reads the last vertex with a 16-byte load.
struct MeshArrays {
  std::vector<float> positions;
  std::vector<std::uint32_t> indices;  ///< 3 per triangle, counter-clockwise

  std::size_t vertexCount() const { return positions.empty() ? 0 : (positions.size() - 1) / 3; }
  std::size_t triangleCount() const { return indices.size() / 3; }
};

/// A ray: origin + s*dir, s >= 0, with |dir| = 1 up to float rounding. Bullet casts
/// segments, so it gets [origin, origin + length*dir]; `length` reaches beyond the mesh.
struct RayQuery {
  float origin[3];
  float dir[3];
  float length;
};

/// A closed segment [start, end] (a finite ray: Embree gets dir = end - start and tfar = 1,
/// Bullet the segment itself).
struct SegmentQuery {
  float start[3];
  float end[3];
};

/// A closest-hit answer: hit flag, distance in world units along the ray, triangle index
/// (when the engine reports one; otherwise kNoTriangle).
struct RayAnswer {
  float t;
  std::uint32_t triangle;
  std::uint8_t hit;
};

/// Triangle index meaning "this engine does not say which triangle".
inline constexpr std::uint32_t kNoTriangle = 0xffffffffu;

/// A sphere query (closed ball).
struct SphereQuery {
  float center[3];
  float radius;
};

/// An oriented box query: world axis i of the box is (axes[3i], axes[3i+1], axes[3i+2]).
struct BoxQuery {
  float center[3];
  float half[3];
  float axes[9];
};

/// A rigid placement: unit quaternion (w, x, y, z) then translation; x -> R x + t.
struct PoseQuery {
  float rotation[4];
  float translation[3];
};

/// A measured duration: wall clock and the process's CPU time (all its threads). For
/// single-threaded work cpu ~ wall on a quiet machine; cpu < wall means the process waited
/// for a core (a loaded machine), and the bench prints that ratio next to every figure.
struct Seconds {
  double wall = 0;
  double cpu = 0;
  Seconds& operator+=(const Seconds& o) {
    wall += o.wall;
    cpu += o.cpu;
    return *this;
  }
};

/// Starts at construction; elapsed() reads both clocks.
class Stopwatch {
 public:
  Stopwatch() : wall0_(std::chrono::steady_clock::now()), cpu0_(cpuNow()) {}
  Seconds elapsed() const {
    const auto wall1 = std::chrono::steady_clock::now();
    return {std::chrono::duration<double>(wall1 - wall0_).count(), cpuNow() - cpu0_};
  }

 private:
  static double cpuNow() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
  }
  std::chrono::steady_clock::time_point wall0_;
  double cpu0_;
};

/// Runs f() on the calling thread alone: inside a oneTBB task arena of one slot, so that the
/// oneTBB parallel algorithms f reaches run serially. A "1 thread" row needs it: crux's BVH build
/// and refit and Embree's commit run oneTBB's parallel algorithms on every core otherwise, and
/// Embree's device setting `threads=1` does not hold once another Embree device of the process
/// has asked for all cores (its task scheduler is shared): measured, both showed 150–200 %
/// CPU in rows labelled one thread.
template <class F>
auto onOneThread(F&& f) {
  tbb::task_arena arena(1);
  return arena.execute(std::forward<F>(f));
}

/// One pass of a bench's engine (a struct with `int threads` and `std::function<Seconds()> pass`):
/// a one-thread engine's on the calling thread alone (onOneThread), any other's as it comes (its
/// own std::threads, or a peer's all-core build).
template <class Engine>
Seconds runPass(Engine& e) {
  return e.threads == 1 ? onOneThread(e.pass) : e.pass();
}

}  // namespace crux::bench
