#pragma once
/// @file bullet_peer.hpp  Bullet (float build) as a bench peer: rays and segments via
/// btCollisionWorld::rayTest (closest, or any hit through a callback that cuts the ray at its
/// first hit), BVH refit via btBvhTriangleMeshShape::refitTree, and sphere/box overlap via btCollisionWorld::contactPairTest, both on a
/// btBvhTriangleMeshShape (quantized BVH) over a btTriangleIndexVertexArray that shares the
/// bench's float arrays.

#include "bench_types.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace crux::bench {

/// What Bullet said besides the boolean, for explaining disagreements.
struct BulletOverlapInfo {
  /// Queries where contactPairTest reported points but all with distance > 0 (Bullet reports
  /// closest points within its thresholds; the bench counts only distance <= 0 as overlap).
  std::size_t separatedReports = 0;
  /// Per query: the smallest reported contact distance (+inf when nothing was reported).
  std::vector<float> minDistance;
};

class BulletPeer {
 public:
  explicit BulletPeer(const MeshArrays& mesh);
  ~BulletPeer();
  BulletPeer(const BulletPeer&) = delete;
  BulletPeer& operator=(const BulletPeer&) = delete;

  /// Builds a fresh btBvhTriangleMeshShape (quantized AABB compression, BVH built in the
  /// constructor) over the shared arrays; returns the constructor's time.
  /// The rays and overlaps keep using the shape made by the constructor.
  Seconds timeBuild() const;
  /// Closest hit of every ray: rayTest(origin, origin + length*dir) with a
  /// ClosestRayResultCallback; t = hit fraction * segment length.
  void closestHits(const RayQuery* rays, std::size_t n, RayAnswer* out) const;
  /// Any hit of every ray: rayTest(origin, origin + length*dir) with a callback that sets the
  /// hit fraction to 0 at the first reported hit (Bullet has no any-hit query: the BVH walk goes
  /// on, but every later triangle is rejected at once).
  void anyHits(const RayQuery* rays, std::size_t n, std::uint8_t* out) const;
  /// Does each closed segment touch the mesh: rayTest(start, end), first-hit callback as above.
  void segmentHits(const SegmentQuery* segments, std::size_t n, std::uint8_t* out) const;
  /// After the shared vertex array changed (same count): bounds of the new vertices,
  /// btBvhTriangleMeshShape::refitTree(bounds) (requantizes and refits every node), and the
  /// world's AABB of the mesh object; returns their time.
  Seconds refit();
  /// Sphere–mesh overlap: a btSphereShape (its margin is its radius) against the mesh
  /// (margin 0); out[i] = 1 when some reported contact has distance <= 0.
  void sphereOverlaps(const SphereQuery* q, std::size_t n, std::uint8_t* out, BulletOverlapInfo* info = nullptr) const;
  /// Box–mesh overlap: a btBoxShape with margin 0 (full half extents kept).
  void boxOverlaps(const BoxQuery* q, std::size_t n, std::uint8_t* out, BulletOverlapInfo* info = nullptr) const;

  /// Margins actually in use, for the report.
  float meshMargin() const;
  /// Bytes of the quantized BVH (btOptimizedBvh serialization size, an estimate of its arrays).
  std::size_t bvhBytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Bullet's version (btGetVersion()) and precision, e.g. "3.24 float".
std::string bulletVersion();

}  // namespace crux::bench
