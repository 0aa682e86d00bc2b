#pragma once
/// @file mesh_walk.hpp  Internal: the mesh queries' walks over a mesh's 4-wide BVH.
///
/// A query states its node test once, on one box, and may add a four-lane form for wide nodes
/// (SIMD over the node's coordinate arrays); these walkers run it over Mesh::bvh(). A query's
/// answer never depends on the walk's order (tested against the brute-force paths).

#include <crux/mesh/bvh.hpp>
#include <crux/mesh/mesh.hpp>

#include "node_tests.hpp"

#include <type_traits>
#include <utility>

namespace crux::mesh_detail {

template <class V, class = void>
struct HasTouches4 : std::false_type {};
template <class V>
struct HasTouches4<V, std::void_t<decltype(std::declval<const V&>().touches4(std::declval<const WideBvhNode&>()))>>
    : std::true_type {};

template <class V, class = void>
struct HasEntry4 : std::false_type {};
template <class V>
struct HasEntry4<V, std::void_t<decltype(std::declval<const V&>().entry4(std::declval<const WideBvhNode&>(),
                                                                         std::declval<Real (&)[4]>()))>>
    : std::true_type {};

/// Every slot whose path of boxes passes the visitor's test, depth first, leaves in the tree's
/// left-to-right order. Visitor: `bool touches(const Aabb&) const` (monotone: a box inside a
/// rejected one is rejected), optionally `unsigned touches4(const WideBvhNode&) const` (bit i:
/// touches' answer for lane i), and `bool slot(std::uint32_t k)` or `bool leaf(std::uint32_t
/// first, std::uint32_t count)` (a leaf's slots together; false stops the walk). Returns false
/// when the visitor stopped it.
/// walkSlots' adapter of a visitor to traverseWideBvhSlots (the wide node test from touches4
/// or touches); WalkLeaves also hands whole leaves to a visitor that takes them.
template <class V>
struct WalkSlots {
  V& v;
  unsigned enter(const WideBvhNode& n) const {
    if constexpr (HasTouches4<V>::value) return v.touches4(n);
    else return eachLane(n, [&](const Aabb& b) { return v.touches(b); });
  }
  bool slot(std::uint32_t k) { return v.slot(k); }
};
template <class V>
struct WalkLeaves : WalkSlots<V> {
  bool leaf(std::uint32_t first, std::uint32_t count) { return this->v.leaf(first, count); }
};

template <class V>
bool walkSlots(const Mesh& mesh, V& v) {
  if constexpr (detail::HasLeafSlots<V>::value) {
    WalkLeaves<V> w{{v}};
    return traverseWideBvhSlots(mesh.bvh(), w);
  } else {
    WalkSlots<V> w{v};
    return traverseWideBvhSlots(mesh.bvh(), w);
  }
}

/// Nearest first: subtrees in increasing key, deferred ones dropped when the visitor no longer
/// keeps their key. Visitor: `bool entry(const Aabb&, Real& key) const`, optionally
/// `unsigned entry4(const WideBvhNode&, Real (&keys)[4]) const` (entry's answers and keys per
/// lane), `bool keep(Real key) const`, and `bool leaf(std::uint32_t first, std::uint32_t count)`
/// (the slots of one leaf; false stops the walk). Returns false when the visitor stopped it.
template <class V>
bool walkOrdered(const Mesh& mesh, V& v) {
  struct Wide {
    V& v;
    unsigned enter(const WideBvhNode& n, Real (&keys)[4]) const {
      if constexpr (HasEntry4<V>::value) {
        return v.entry4(n, keys);
      } else {
        unsigned bits = 0;
        for (int i = 0; i < 4; ++i)
          if (n.used(i) && v.entry(n.laneBounds(i), keys[i])) bits |= 1u << i;
        return bits;
      }
    }
    bool keep(Real key) const { return v.keep(key); }
    bool leaf(std::uint32_t first, std::uint32_t count, Real) { return v.leaf(first, count); }
  } w{v};
  return traverseWideBvhOrdered(mesh.bvh(), w);
}

}  // namespace crux::mesh_detail
