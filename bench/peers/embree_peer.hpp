#pragma once
/// @file embree_peer.hpp  Embree 3 as a bench peer: closest-hit rays (rtcIntersect1) and build.

#include "bench_types.hpp"

#include <cstddef>
#include <memory>
#include <string>

namespace crux::bench {

/// How the Embree scene is configured.
struct EmbreeConfig {
  bool robust = true;        ///< RTC_SCENE_FLAG_ROBUST (watertight-style, no unsafe shortcuts)
  bool highQuality = false;  ///< RTC_BUILD_QUALITY_HIGH (spatial splits) instead of MEDIUM
  int threads = 1;           ///< device threads for the build (0: Embree's default, all cores)

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
