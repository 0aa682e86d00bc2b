#pragma once
/// @file fcl_peer.hpp  FCL 0.7 as a bench peer: sphere/box/mesh overlap against a
/// BVHModel<OBBRSSd> with fcl::collide (num_max_contacts 1, no contact details, libccd GJK), and
/// BVH refit (beginUpdateModel / updateSubModel / endUpdateModel).

#include "bench_types.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace crux::bench {

class FclPeer {
 public:
  /// Converts the float mesh to double (exactly) and builds the model.
  explicit FclPeer(const MeshArrays& mesh);
  ~FclPeer();
  FclPeer(const FclPeer&) = delete;
  FclPeer& operator=(const FclPeer&) = delete;

  /// Builds a fresh BVHModel<OBBRSSd> (beginModel, addSubModel, endModel) from the double
  /// vertex/triangle arrays prepared by the constructor; returns its time.
  Seconds timeBuild() const;
  /// Sphere–mesh: fcl::collide(model, identity, Sphered(r), translation).
  void sphereOverlaps(const SphereQuery* q, std::size_t n, std::uint8_t* out) const;
  /// Box–mesh: fcl::collide(model, identity, Boxd(2*half), pose).
  void boxOverlaps(const BoxQuery* q, std::size_t n, std::uint8_t* out) const;
  /// Mesh–mesh: fcl::collide(model, identity, model, pose).
  void meshOverlaps(const PoseQuery* q, std::size_t n, std::uint8_t* out) const;
  /// Moves the model's vertices to `moved` (same count; converted to double before the clock
  /// starts) with beginUpdateModel, updateSubModel, endUpdateModel(refit = true, bottomup = true);
  /// returns the time of those three calls. Later queries see the moved model.
  Seconds refit(const MeshArrays& moved);
  /// Bytes of the model's vertex, triangle and BV arrays.
  std::size_t modelBytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// FCL's version string.
std::string fclVersion();

}  // namespace crux::bench
