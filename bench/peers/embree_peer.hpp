#pragma once
/// @file embree_peer.hpp  Embree 3 as a bench peer: closest-hit rays (rtcIntersect1), any-hit rays
/// and segments (rtcOccluded1), build (rtcCommitScene) and refit (RTC_BUILD_QUALITY_REFIT).

#include "bench_types.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace crux::bench {

/// How the Embree scene is configured.
struct EmbreeConfig {
  bool robust = true;        ///< RTC_SCENE_FLAG_ROBUST (watertight-style, no unsafe shortcuts)
  bool highQuality = false;  ///< RTC_BUILD_QUALITY_HIGH (spatial splits) instead of MEDIUM
  int threads = 1;           ///< device threads for the build (0: Embree's default, all cores)
  /// Refit instead of rebuild when the vertices move: RTC_SCENE_FLAG_DYNAMIC, scene quality
  /// RTC_BUILD_QUALITY_LOW (the two-level structure that honours per-geometry quality) and
  /// geometry quality RTC_BUILD_QUALITY_REFIT; refit() then updates the vertex buffer and
  /// recommits. (Without DYNAMIC, Embree 3.13.5 rebuilds the REFIT geometry on every commit.)
  bool refit = false;
  /// Embree's `max_isa` device setting (empty: Embree picks the widest ISA the CPU has, which
  /// on an AVX-512 machine is an 8-wide BVH8<triangle4v> with AVX-512 intersectors). "sse4.2"
  /// gives its 4-wide BVH4<triangle4v> with SSE4.2 code: the like-for-like peer of crux's
  /// baseline x86-64 (SSE2, 4-wide) build.
  std::string maxIsa;

  std::string label() const;
};

/// One Embree device and one triangle scene over a shared (not copied) float mesh.
class EmbreePeer {
 public:
  EmbreePeer(const MeshArrays& mesh, const EmbreeConfig& config);
  ~EmbreePeer();
  EmbreePeer(const EmbreePeer&) = delete;
  EmbreePeer& operator=(const EmbreePeer&) = delete;

  /// Releases the scene and builds it again; returns the time of scene creation,
  /// geometry setup and rtcCommitScene.
  Seconds rebuild();
  /// Closest hit of every ray, one rtcIntersect1 each (tnear 0, tfar +inf).
  void closestHits(const RayQuery* rays, std::size_t n, RayAnswer* out) const;
  /// Any hit of every ray: one rtcOccluded1 each (tnear 0, tfar +inf); out[i] = 1 when occluded.
  void anyHits(const RayQuery* rays, std::size_t n, std::uint8_t* out) const;
  /// Does each closed segment touch the mesh: rtcOccluded1 with dir = end - start, tfar 1.
  void segmentHits(const SegmentQuery* segments, std::size_t n, std::uint8_t* out) const;
  /// After the shared vertex array changed (same count): rtcUpdateGeometryBuffer,
  /// rtcCommitGeometry, rtcCommitScene; returns their time. A refit when config.refit, else
  /// Embree rebuilds the changed geometry.
  Seconds refit();
  /// Bytes Embree allocated for the scene (memory monitor), vertices/indices excluded (shared).
  std::size_t sceneBytes() const;
  /// Whether this Embree build culls back faces (crux and Bullet hit both faces).
  bool backfaceCulling() const;
  const EmbreeConfig& config() const { return config_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  EmbreeConfig config_;
};

/// Embree's version string (RTC_VERSION_STRING).
std::string embreeVersion();

}  // namespace crux::bench
